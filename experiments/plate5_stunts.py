"""Plate 5 / Fig. 11: the dolphin's stunts, each discovered by simulated annealing over plans
of its repertoire entries, with the defaults of ``zoetic stunt``.

Trains (or reuses) the dolphin's basic repertoire, discovers each trick, and prints a Markdown
table: apex of the centre of mass above the surface (m and body lengths), time wholly out of
the water, rotation in the air, contacts, ball rise, the plan (entries and durations), plan
evaluations and wall time. A few minutes on 2 cores:
    python experiments/plate5_stunts.py [--memory memory/dolphin] [--budget 3200] [--seed 0]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.stunts import discover, list_tricks, load_trick
from zoetic.behavior.training import train_repertoire
from zoetic.bodies import load_animal


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--memory", type=Path, default=Path("memory/dolphin"))
    ap.add_argument("--budget", type=int, default=3200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--method", default="anneal")
    args = ap.parse_args()
    body = load_animal("dolphin")
    if not (args.memory / "repertoire.json").exists():
        t0 = time.perf_counter()
        train_repertoire("dolphin", args.memory, seed=args.seed)
        print(f"trained the repertoire in {time.perf_counter() - t0:.0f} s")
    rep = Repertoire.load(args.memory, body)
    print("| trick | apex m (body lengths) | s out of water | rotation in air deg | contacts "
          "| ball rise m | plan | evaluations | wall s |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|")
    for name in list_tricks():
        s = discover(body, rep, load_trick(name), args.method, args.budget, args.seed).summary()
        plan = ", ".join(f"{p['entry']} {p['duration_s']:.2f}" for p in s["plan"] if p["played"])
        print(f"| {name} | {s['apex_above_surface_m']:.2f} ({s['apex_body_lengths']:.2f}) "
              f"| {s['air_time_s']:.2f} | {s['rotation_in_air_deg']:.0f} | {s['contacts']} "
              f"| {s.get('ball_rise_m', '-')} | {plan} | {s['evaluations']} "
              f"| {s['wall_s']:.0f} |")  # fmt: skip


if __name__ == "__main__":
    main()
