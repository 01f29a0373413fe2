"""Tracking courses in 3D: does greedy tracking with a repertoire keep the animal at its depth
and upright while it reaches every target?

``zoetic bench track`` runs this: a suite of courses (targets ahead, behind, to either side,
so every start heading relative to the course is met; level ones at the start depth and 3D
ones that climb and dive) tracked with the default repertoire of an animal (trained once and
kept under runs/bench, keyed by the body and its training tasks) or a given one. The animal
always starts facing +x, so the first target's bearing is the start heading relative to the
course: 0 (ahead-left, dive), 90 (left), 180 (behind), about 160 (dive-behind) and -45
degrees (right-zigzag, climb-right). Per course:
targets reached (in 3D), simulated seconds, the depth change and span (m, relative to the
start depth), the worst depth error from the target being tracked (m), the worst roll and
pitch (deg); over the level courses, the worst depth excursion, which default tracking aims to
keep within DEPTH_BAND, and over all courses the worst roll, aimed within ROLL_LIMIT.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

DEPTH_BAND = 0.5  # m: a level course's aim for the depth excursion
ROLL_LIMIT = 30.0  # deg: every course's aim for the worst roll
# name -> targets "x,z" or "x,y,z" (y m above the start depth); the animal starts facing +x
COURSES = {
    "ahead-left": "3,0;5,2;4,5",  # the course of the issue report
    "behind": "-3,0;-3,3",  # first target straight behind the start heading
    "left": "0,3;2,5;-1,6",  # first target abeam to the left
    "right-zigzag": "2,-2;4,0;6,-2;8,0",  # first target ahead to the right
    "dive": "3,-1,0;5,-2,2;4,-2,5",  # down 2 m while turning left
    "climb": "3,1,1;1,2,3;-1,2,2",  # up 2 m while turning back
    "dive-behind": "-3,-1,1;-4,-1.5,3",  # down 1.5 m, the first target behind
    "climb-right": "2,1,-2;4,1.5,-1",  # up 1.5 m, the first target ahead to the right
}


def _depth_error(result) -> float:
    """Return the worst |height - the tracked target's height| (m) along a tracking path,
    the target being tracked switching when the previous one is reached."""
    reached = np.where(np.isfinite(result.reached), result.reached, np.inf)
    goal = np.minimum(np.searchsorted(reached, result.times, side="right"), len(reached) - 1)
    return float(np.max(np.abs(result.com[:, 1] - result.targets[goal, 1])))


def bench_track(
    animal: str = "shark", memory: str | Path | None = None, time_limit: float = 60.0, seed: int = 0
) -> dict:
    """Return the course suite's figures (see the module docstring) for one animal."""
    from zoetic.behavior.repertoire import Repertoire
    from zoetic.behavior.targets import parse_targets
    from zoetic.behavior.tracking import TrackConfig, track
    from zoetic.bench.memory import bench_memory
    from zoetic.bodies import load_animal

    body = load_animal(animal)
    rep = Repertoire.load(
        memory if memory is not None else bench_memory(animal, body.name, seed), body
    )
    courses, wall = {}, 0.0
    for name, text in COURSES.items():
        pts = parse_targets(text, f"course {name}")
        r = track(body, rep, pts, TrackConfig(time_limit=time_limit))
        s = r.summary()
        wall += r.wall
        courses[name] = {
            "targets": text,
            "reached": f"{s['reached']}/{s['targets']}",
            "simulated_s": s["simulated_s"],
            "depth_change_m": s["depth_change_m"],
            "depth_span_m": s["depth_span_m"],
            "worst_depth_error_m": round(_depth_error(r), 3),
            "worst_roll_deg": s["worst_roll_deg"],
            "worst_pitch_deg": s["worst_pitch_deg"],
        }
    level = [
        c
        for n, c in courses.items()
        if not any(len(p.split(",")) == 3 for p in COURSES[n].split(";"))
    ]
    drift = max(max(abs(v) for v in c["depth_span_m"]) for c in level)
    roll = max(c["worst_roll_deg"] for c in courses.values())
    return {
        "animal": body.name,
        "memory": str(memory),
        "reached": f"{sum(int(c['reached'].split('/')[0]) for c in courses.values())}/"
        f"{sum(int(c['reached'].split('/')[1]) for c in courses.values())}",
        "level_depth_drift_m": round(drift, 3),
        "level_depth_within_band": bool(drift <= DEPTH_BAND),
        "worst_roll_deg": roll,
        "roll_within_limit": bool(roll <= ROLL_LIMIT),
        "worst_pitch_deg": max(c["worst_pitch_deg"] for c in courses.values()),
        "tracking_wall_s": round(wall, 2),
        "courses": courses,
    }
