"""``zoetic bench render``: what a video frame costs with the display skins against the raw
lattice's triangles, side by side on the same motion."""

from __future__ import annotations

import time

import numpy as np


def _frame_seconds(body, positions, times, skins, repeats: int) -> list[float]:
    """Return the wall seconds per frame of each of ``repeats`` renders of the motion."""
    from zoetic.viz.render3d import render_frames

    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _frame in render_frames(body, positions, times, body.medium, skins=skins):
            pass
        out.append((time.perf_counter() - t0) / len(times))
    return out


def bench_render(animal: str = "shark", frames: int = 30, repeats: int = 5) -> dict:
    """Return the median seconds per 640x360 frame of an animal swimming its own wave, drawn
    as its lattice's triangles (``lattice``) and as its display skin (``skin``: subdivided,
    with fins and markings), each repeat timed alternately, and their ratio."""
    from zoetic.bodies import load_animal
    from zoetic.control import controller_from_spec
    from zoetic.control.rollout import rollout
    from zoetic.physics.world import World
    from zoetic.render.skin import body_skin, look_of, make_skin

    body = load_animal(animal)
    wave = controller_from_spec("wave", body)
    traj = rollout(World([body]), wave, max(frames / 30.0, 0.2), 1 / 30, record_every=4)
    traj = traj.trajectory(0)
    idx = np.linspace(0, len(traj.times) - 1, frames).astype(int)
    pos, times = np.asarray(traj.positions[0])[idx], np.asarray(traj.times)[idx]
    lattice = make_skin(body.faces, body.rest_pos, look_of(body.name), None, body.forward, 0)
    skin = body_skin(body)
    old, new = [], []
    _frame_seconds(body, pos[:2], times[:2], [skin], 1)  # warm caches
    for _ in range(repeats):
        old += _frame_seconds(body, pos, times, [lattice], 1)
        new += _frame_seconds(body, pos, times, [skin], 1)
    a, b = float(np.median(old)), float(np.median(new))
    return {
        "animal": animal,
        "frames": frames,
        "lattice_triangles": len(lattice.triangles),
        "skin_triangles": len(skin.triangles),
        "lattice_ms_per_frame": round(1e3 * a, 2),
        "skin_ms_per_frame": round(1e3 * b, 2),
        "skin_over_lattice": round(b / a, 3),
    }
