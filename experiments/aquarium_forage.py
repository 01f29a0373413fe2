"""How well the default tank's fishes forage, over seeds: food eaten, share of brain periods
spent avoiding and eating, deepest penetrations (into obstacles, into fishes), CPU realtime
factor. One JSON line a seed, then the means. About 3 s of CPU a seed:
    python experiments/aquarium_forage.py [--seeds 0 1 2 ... 9] [--seconds 60]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live, summarize


def timed_life(seed: int, seconds: float):
    """Live the default scene from ``seed``: return the tank, its life, its summary and the
    CPU seconds the life took."""
    tank = build_tank(TankConfig(seed=seed, seconds=seconds, record_period=0.1))
    c0 = time.process_time()
    life = live(tank)
    cpu = time.process_time() - c0
    return tank, life, summarize(tank, life), cpu


def run(seed: int, seconds: float) -> dict:
    """Live the default scene from ``seed`` and return its foraging figures."""
    _, _, s, cpu = timed_life(seed, seconds)
    share = s["intention_share"]
    return {
        "seed": seed,
        "food_eaten": s["food_eaten_fraction"],
        "avoid": round(share["avoid"], 3),
        "eat": round(share["eat"], 3),
        "deepest_into_obstacle_m": s["deepest_into_obstacle_m"],
        "deepest_into_fish_m": round(s["deepest_into_fish_m"], 4),
        "collisions_between_fishes": s["collisions_between_fishes"],
        "catches": s["events"]["catch"],
        "cpu_realtime_factor": round(seconds / cpu, 1),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=list(range(10)))
    ap.add_argument("--seconds", type=float, default=60.0)
    args = ap.parse_args()
    live(build_tank(TankConfig(fishes=2, food=1, obstacles=1, seconds=0.2)))  # compile
    rows = [run(s, args.seconds) for s in args.seeds]
    for r in rows:
        print(json.dumps(r))
    keys = ("food_eaten", "avoid", "eat", "cpu_realtime_factor")
    print(
        json.dumps(
            {
                "mean": {k: round(float(np.mean([r[k] for r in rows])), 3) for k in keys},
                "min_food_eaten": min(r["food_eaten"] for r in rows),
                "max_deepest_into_obstacle_m": max(r["deepest_into_obstacle_m"] for r in rows),
                "max_deepest_into_fish_m": max(r["deepest_into_fish_m"] for r in rows),
            }
        )
    )


if __name__ == "__main__":
    main()
