"""The aquarium with learned motor skills for every species, against the built-in wave.

Writes species files for the minnow and the shark with ``[motor] skills = "learned"`` (the
shark lattice's repertoire shipped in ``behavior/aquarium/skills/shark``, trained by
``scripts/train_aquarium_skills.py``) and lives the default scene (10 fishes, 15 food, 5
obstacles, 60 s) on each seed with learned skills and with the built-in wave, side by side;
prints one JSON line a run (food eaten, events, deepest penetrations, CPU realtime factor), the
motor calibration, and the means. Also reports how many fishes ended with a folded tail (nose
to tail-fin node under 0.8 of the rest length; see docs/aquarium.md, "Why the built-in wave
stays the default"). About 5 s of CPU a run:
    python experiments/aquarium_learned.py [--out /tmp/aquarium_learned] [--seeds 0 1 2]
"""

from __future__ import annotations

import argparse
import json
import re
import time
from pathlib import Path

import numpy as np

from zoetic.behavior.aquarium.bodystate import heading_weights
from zoetic.behavior.aquarium.locomotion import FOLDED, bend, learned_motor
from zoetic.behavior.aquarium.species import BUILT_IN, LEARNED, SKILLS_DIR, load_species
from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live, summarize
from zoetic.bodies import load_animal
from zoetic.tasks.terms import BodyFrame, roll_angle

ON_SIDE = np.radians(30.0)  # |roll| over this: the fish lies on its side


def species_file(out: Path, name: str, skills: str) -> Path:
    """Write the built-in species ``name`` with ``[motor] skills = skills`` (in a folder of
    that name under ``out``)."""
    text = Path(load_species(name).source).read_text()
    (out / skills).mkdir(parents=True, exist_ok=True)
    path = out / skills / f"{name}.toml"
    path.write_text(re.sub(r'^skills = "[^"]*"', f"skills = {json.dumps(skills)}", text,
                           flags=re.M))  # fmt: skip
    return path


def folded(body, positions: np.ndarray) -> bool:
    """Return True if the fish's tail fin ends folded forward (``locomotion.bend`` under
    ``FOLDED``, 0.8: a fold leaves 0.6-0.7, a fish steering hard bends to about 0.87)."""
    return bool(bend(body, positions[-1]) < FOLDED)


def rolled_time(tank, life) -> tuple[float, float, int]:
    """Return the fraction of live fish-time with |roll| over ``ON_SIDE`` (30 degrees), the
    fraction upside down (over 90 degrees), and how many fishes ever lay on their side; the
    roll of ``tasks.terms.roll_angle`` against each fish's heading, at the record times."""
    over = under = total = 0
    fishes_on_side = 0
    for a, f in enumerate(tank.fishes):
        p = life.positions[a]  # (R, N, 3)
        frame = BodyFrame.of(f.body)
        fwd = np.einsum("n,rnd->rd", heading_weights(f.body), p)
        roll = np.abs(roll_angle(np, p, frame.left, frame.right, fwd))
        k = np.minimum(np.arange(len(p)), len(life.alive) - 1)
        live_ = life.alive[k, a]
        over += int(np.count_nonzero(live_ & (roll > ON_SIDE)))
        under += int(np.count_nonzero(live_ & (roll > np.pi / 2)))
        total += int(np.count_nonzero(live_))
        fishes_on_side += bool((live_ & (roll > ON_SIDE)).any())
    return over / max(total, 1), under / max(total, 1), fishes_on_side


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("/tmp/aquarium_learned"))
    ap.add_argument("--seeds", type=int, nargs="+", default=list(range(10)))
    ap.add_argument(
        "--skills",
        nargs="+",
        choices=("learned", "built-in"),
        default=["learned", "built-in"],
        help="which to run (default both)",
    )
    ap.add_argument(
        "--no-righting",
        action="store_true",
        help="without the motor layer's righting reflex (TankConfig.righting)",
    )
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    print(json.dumps(learned_motor(load_animal("shark"), SKILLS_DIR / "shark").summary()))
    learned = tuple(species_file(args.out, n, LEARNED) for n in ("minnow", "shark"))
    built_in = tuple(species_file(args.out, n, BUILT_IN) for n in ("minnow", "shark"))
    rows: dict[str, list[dict]] = {"learned": [], "built-in": []}
    for seed in args.seeds:
        for label, (prey, pred) in (("learned", learned), ("built-in", built_in)):
            if label not in args.skills:
                continue
            tank = build_tank(TankConfig(seed=seed, record_period=0.1, prey_species=str(prey),
                                         predator_species=str(pred),
                                         righting=not args.no_righting))  # fmt: skip
            c0 = time.process_time()
            life = live(tank)
            cpu = time.process_time() - c0
            s = summarize(tank, life)
            folds = sum(folded(f.body, p) for f, p in zip(tank.fishes, life.positions,
                                                          strict=True))  # fmt: skip
            row = {
                "seed": seed, "skills": label, "food_eaten_fraction": s["food_eaten_fraction"],
                "events": s["events"], "deepest_into_obstacle_m": s["deepest_into_obstacle_m"],
                "deepest_into_fish_m": s["deepest_into_fish_m"], "folded_tails": folds,
                "cpu_realtime_factor": round(s["seconds"] / cpu, 1),
            }  # fmt: skip
            on_side, upside_down, fishes_on_side = rolled_time(tank, life)
            row["on_side_fraction"] = round(on_side, 3)
            row["upside_down_fraction"] = round(upside_down, 3)
            row["fishes_on_side"] = fishes_on_side
            rows[label].append(row)
            print(json.dumps(row), flush=True)
    print(json.dumps({label: {
        "food_eaten_mean": round(float(np.mean([r["food_eaten_fraction"] for r in rs])), 3),
        "catches": sum(r["events"]["catch"] for r in rs),
        "max_deepest_into_obstacle_m": max(r["deepest_into_obstacle_m"] for r in rs),
        "max_deepest_into_fish_m": max(r["deepest_into_fish_m"] for r in rs),
        "on_side_mean": round(float(np.mean([r["on_side_fraction"] for r in rs])), 3),
        "upside_down_mean": round(float(np.mean([r["upside_down_fraction"] for r in rs])), 3),
        "folded_tails": sum(r["folded_tails"] for r in rs),
        "cpu_realtime_factor_mean": round(float(np.mean([r["cpu_realtime_factor"]
                                                         for r in rs])), 1),
    } for label, rs in rows.items() if rs}))  # fmt: skip


if __name__ == "__main__":
    main()
