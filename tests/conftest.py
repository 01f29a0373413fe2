"""Shared test helpers."""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

import pytest

# JAX's compiled programs go to a directory of this test session, removed at its end, never to
# the user's cache (~/.cache/zoetic/jax or their JAX_COMPILATION_CACHE_DIR); set before any
# test imports JAX, and inherited by the command-line runs the tests start.
JAX_TEST_CACHE = tempfile.mkdtemp(prefix="zoetic-test-jax-")
os.environ["ZOETIC_JAX_CACHE"] = JAX_TEST_CACHE
os.environ.pop("JAX_COMPILATION_CACHE_DIR", None)

from zoetic.bodies import load_animal  # noqa: E402


def pytest_sessionfinish(session, exitstatus) -> None:
    """Remove the session's JAX compilation cache."""
    shutil.rmtree(JAX_TEST_CACHE, ignore_errors=True)


def write_short_task(folder: Path, horizon: float, nodes: int) -> Path:
    """Write a short swim-forward task file (water, one distance term) and return its path:
    the learning tests' small, fast task."""
    path = folder / "short-swim.toml"
    path.write_text(
        'name = "short-swim"\nrequires = ["water"]\n'
        f"horizon = {horizon}\nnodes = {nodes}\n"
        '[[terms]]\nkind = "distance_along_heading"\nweight = -1.0\n'
    )
    return path


def cruise_from(world, body, poses, speed: float) -> None:
    """Place a world's animals (all of ``body``) at ``poses`` ((x, y, z) in m, yaw in rad), each
    moving at ``speed`` m/s along its heading: a scene's start of fishes already cruising."""
    from dataclasses import replace

    import numpy as np

    from zoetic.physics.world import placed_pose

    state = world.state
    heading = [np.array([np.cos(yaw), 0.0, np.sin(yaw)]) for _, yaw in poses]
    world.restore(
        replace(
            state,
            positions=tuple(placed_pose(body, p, yaw)[None] for p, yaw in poses),
            velocities=tuple(
                np.zeros_like(v) + speed * h for v, h in zip(state.velocities, heading, strict=True)
            ),
        )
    )


@pytest.fixture(scope="session")
def dolphin():
    """The zoo dolphin, loaded once for the stunt and contact tests."""
    return load_animal("dolphin")


@pytest.fixture(scope="session")
def beat_repertoire(dolphin):
    """The dolphin's repertoire for stunt tests: do-nothing and a 2 Hz tail beat (one mode,
    the zoo's wave phases)."""
    import numpy as np

    from zoetic.behavior.repertoire import Repertoire
    from zoetic.behavior.training import rest_abstraction
    from zoetic.control.abstract import AbstractController

    a = len(dolphin.actuator_names)
    beat = AbstractController(
        dolphin.name,
        tuple(dolphin.actuator_names),
        np.full(a, 0.5),
        np.full((a, 1), 2.0),
        np.full((a, 1), 0.5),
        -2 * np.pi * np.array([0, 0.5, 0.1, 0.6, 0.2, 0.7, 0, 0])[:, None],
        1.0,
    )
    rep = Repertoire(dolphin.name, tuple(dolphin.actuator_names))
    rep.add("do-nothing", rest_abstraction(dolphin), 1.0)
    rep.add("beat", beat, 1.0)
    return rep


@pytest.fixture
def pairs_one_by_one():
    """The reference for ``bodycontact.close_pairs``: every pair of animals (a < c) that
    ``bodycontact.close`` finds close, testing each pair on its own; same arguments."""
    from zoetic.physics.bodycontact import close

    def pairs(pos, vel, off, reach, pad: float, horizon: float) -> list[tuple[int, int]]:
        n = len(off) - 1
        return [
            (a, c)
            for a in range(n)
            for c in range(a + 1, n)
            if close(
                pos[off[a] : off[a + 1]],
                vel[off[a] : off[a + 1]],
                pos[off[c] : off[c + 1]],
                vel[off[c] : off[c + 1]],
                max(reach[a], reach[c]) + pad,
                pad,
                horizon,
            )
        ]

    return pairs
