"""``zoetic bench vision``: frames per second of animat vision, side by side in one run."""

from __future__ import annotations

import time

import numpy as np

from zoetic.perception.eyes import head_frame, look
from zoetic.perception.pursuit import make_chase, run_chase


def bench_vision(frames: int = 150, seed: int = 0) -> dict:
    """Return rendered retina frames per second (both eyes, all component images), the whole
    perception-action loop's frames per second (render, recognise, gaze, steer, physics, 3
    fish) and the renderer's share of the loop, measured in the same process."""
    chase = make_chase(seed)
    run_chase(chase, 0.2)  # compile everything once
    chase = make_chase(seed)
    world, pred = chase.world, chase.predator
    spec = pred.gaze.spec
    mesh = chase.scenery.mesh(world)
    frame = head_frame(world.bodies[0], world.positions(0)[0])
    angles = np.radians([[10.0, 0.0], [14.0, 0.0]])
    t0 = time.perf_counter()
    for _ in range(frames):
        look(mesh, frame, angles, spec)
    render_s = (time.perf_counter() - t0) / frames
    t0 = time.perf_counter()
    for _ in range(frames):
        mesh = chase.scenery.mesh(world)
    mesh_s = (time.perf_counter() - t0) / frames
    t0 = time.perf_counter()
    result = run_chase(chase, frames / 30.0, fps=30.0)
    n = len(result.log)
    loop_s = (time.perf_counter() - t0) / max(n, 1)
    return {
        "benchmark": "vision",
        "eyes": 2,
        "levels": spec.levels,
        "pixels": spec.size,
        "triangles": int(len(mesh.triangles)),
        "retina_frames_per_second": round(1.0 / render_s, 1),
        "frames_per_second": round(1.0 / loop_s, 1),
        "render_share": round((render_s + mesh_s) / loop_s, 3),
        "loop_frames": n,
    }
