"""Plate 3 of Grzeszczuk & Terzopoulos 95: the shark race.

Four sharks learn to swim straight for increasing budgets (CMA-ES by default; the paper's
simulated annealing with --optimizer anneal --budgets 25,400,1500,3500); they then race side
by side, each playing its learned controller from the same start line, in one video.
Writes docs/figures/plate3_race.mp4, plate3_race.png (the paths) and plate3_race.json
(distance swum by each).

Run: python experiments/plate3_race.py [--budgets 16,400,1500,6000] [--optimizer cmaes]
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from zoetic.learning.run import LearnConfig, build
from zoetic.physics import State, rest_state
from zoetic.reproduce import figures_dir

OUT = figures_dir()
LANE = 0.7  # metres between lanes


def train(budget: int, optimizer: str, seed: int, controller: str):
    """Return (objective, best parameters) after ``budget`` evaluations."""
    setup = build(LearnConfig(animal="shark", task="swim-straight", optimizer=optimizer,
                              budget=budget, seed=seed, popsize=16,
                              controller=controller))  # fmt: skip
    opt, obj = setup.optimizer, setup.objective
    while opt.evaluations < budget and not opt.done():
        X = opt.ask()
        opt.tell(X, obj(X))
    return obj, opt.best_x


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--budgets", default="16,400,1500,6000")
    ap.add_argument("--optimizer", default="cmaes")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--controller",
        default="time",
        help="time (the paper's Plate 3), or periodic (zoetic learn's default)",
    )
    args = ap.parse_args()
    from zoetic.viz.plots import plot_path
    from zoetic.viz.render3d import render_video

    budgets = [int(b) for b in args.budgets.split(",")]
    OUT.mkdir(parents=True, exist_ok=True)
    positions, coms, report = [], [], {}
    for lane, budget in enumerate(budgets):
        obj, x = train(budget, args.optimizer, args.seed, args.controller)
        body = obj.body
        start = rest_state(body, 1, offset=(0.0, 0.0, LANE * (len(budgets) - 1 - lane)))
        obj.start = State(start.positions, start.velocities)
        traj = obj.simulate(x[None])
        positions.append(traj.positions[0])
        com = traj.com(body)[0]
        coms.append(com)
        report[f"{budget} evaluations"] = round(float(com[-1, 0] - com[0, 0]), 3)
        print(budget, report[f"{budget} evaluations"], flush=True)
    labels = [f"{b} evals" for b in budgets]
    render_video([body] * len(budgets), positions, traj.times, obj.medium,
                 OUT / "plate3_race.mp4", fps=30, labels=labels)  # fmt: skip
    plot_path(coms, OUT / "plate3_race.png", title="shark race: " + ", ".join(labels))
    (OUT / "plate3_race.json").write_text(json.dumps(report, indent=2) + "\n")
    order = np.argsort([-v for v in report.values()])
    print("finishing order (lane index):", order.tolist())


if __name__ == "__main__":
    main()
