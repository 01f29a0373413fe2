"""Shared test helpers."""

from __future__ import annotations

from pathlib import Path

import pytest

from zoetic.bodies import load_animal


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


@pytest.fixture(scope="session")
def dolphin():
    """The zoo dolphin, loaded once for the stunt and contact tests."""
    return load_animal("dolphin")
