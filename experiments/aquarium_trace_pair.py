"""Period by period, what two fishes of the default tank thought before they touched.

For each brain period from T0 to T1 s: the centres' distance (m) and, for each of the two
fishes, its intention, target, side of avoidance, whether something lies ahead (``hit``),
whether only a fish threatens (``only``: the brake applies), how near (m) the nearest
contact is (``near``, ``fish_threats``) and its horizontal speed (m/s); then the tank's
fish-fish collisions after T0 - 1 s (names ``species_index``):
    python experiments/aquarium_trace_pair.py SEED A B T0 T1
"""

from __future__ import annotations

import argparse

import numpy as np

from zoetic.behavior.aquarium import shoal as sh
from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live


def traced(a: int, b: int, t0: float, t1: float, period: float):
    """Return ``Shoal._ahead`` wrapped to print fishes a and b's line from t0 to t1 s."""
    inner = sh.Shoal._ahead
    clock = [0.0]

    def ahead(self, pc, selves, meals, alive, food):
        hits, aways, near, only = inner(self, pc, selves, meals, alive, food)
        t, fb = clock[0], self.bodies
        clock[0] += period
        if t0 <= t <= t1:
            row = [f"t={t:5.1f} d={np.linalg.norm(fb.com[a] - fb.com[b]):.2f}"]
            for i in (a, b):
                th = self.brains[i].thought
                v = float(np.linalg.norm(fb.vel[i][[0, 2]]))
                row.append(
                    f"#{i} {th.intention:6} target={th.target} side={self.brains[i].avoid_side:+d}"
                    f" hit={int(hits[i])} only={int(only[i])} near={near[i]:.2f} v={v:.2f}"
                )
            print(" | ".join(row), flush=True)
        return hits, aways, near, only

    return ahead


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("seed", type=int)
    ap.add_argument("a", type=int)
    ap.add_argument("b", type=int)
    ap.add_argument("t0", type=float)
    ap.add_argument("t1", type=float)
    args = ap.parse_args()
    cfg = TankConfig(seed=args.seed, seconds=args.t1 + 0.5, record_period=0.1)
    sh.Shoal._ahead = traced(args.a, args.b, args.t0, args.t1, cfg.control_period)
    life = live(build_tank(cfg))
    print([e for e in life.events if e[2] == "collision" and e[0] > args.t0 - 1.0])


if __name__ == "__main__":
    main()
