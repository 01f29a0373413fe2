"""Each dolphin trick discovered with default settings, judged against the stunt targets.

``zoetic bench stunts`` runs this: for every trick, the plan search's result, its success
flags against the issue's targets (a leap 0.4 s out of the water and 0.5 body lengths up, a
full somersault, a full spin about the long axis, a cleared bar, a nose-struck ball, a tail
strike in flight after half a somersault, a bellyflop splashing 3x a clean dive),
what it achieved, evaluations and wall time (target: each trick in <= 5 minutes on 2 cores).
"""

from __future__ import annotations

from pathlib import Path


def bench_stunts(
    animal: str, memory: Path | None, tricks: list[str], method: str, budget: int, seed: int
) -> dict:
    """Discover each trick (training the animal's repertoire once into runs/bench, keyed by
    its body and plan, when no memory is given) and return the figures as one JSON dict."""
    from zoetic.behavior.repertoire import Repertoire
    from zoetic.behavior.stunts import (
        SPLASH_RATIO,
        discover,
        load_trick,
        splash_ratio,
        targets_met,
    )
    from zoetic.bench.memory import bench_memory
    from zoetic.bodies import load_animal

    body = load_animal(animal)
    rep = Repertoire.load(
        memory if memory is not None else bench_memory(animal, body.name, seed), body
    )
    out: dict = {"animal": body.name, "method": method, "budget": budget, "seed": seed}
    keep = (
        "apex_above_surface_m",
        "apex_body_lengths",
        "air_time_s",
        "rotation_in_air_deg",
        "pitch_rotation_in_air_deg",
        "roll_rotation_in_air_deg",
        "ball_contact",
        "ball_parts",
        "tail_strike_rotation_deg",
        "ball_tail_distance_m",
        "striker_speed_m_s",
        "ball_speed_m_s",
        "hurdle_clearance_m",
        "splash_m3_s",
        "evaluations",
        "wall_s",
    )
    full = {}
    for name in tricks:
        tr = load_trick(name)
        s = full[name] = discover(body, rep, tr, method, budget, seed).summary()
        flags = targets_met(name, s, tr)
        out[name] = {
            "success": bool(flags) and all(flags.values()),
            "flags": flags,
            **{k: s[k] for k in keep if k in s},
        }
    if "bellyflop" in out and "clean-dive" in out:
        ratio = splash_ratio(full["bellyflop"], full["clean-dive"])
        out["splash_ratio"] = None if ratio is None else round(ratio, 2)
        out["splash_ratio_met"] = ratio is not None and ratio >= SPLASH_RATIO
    out["all_wall_s"] = round(
        sum(v["wall_s"] for v in out.values() if isinstance(v, dict) and "wall_s" in v), 2
    )
    out["each_within_5_min"] = all(
        v["wall_s"] <= 300 for v in out.values() if isinstance(v, dict) and "wall_s" in v
    )
    return out
