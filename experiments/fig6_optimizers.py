"""Fig. 6 of Grzeszczuk & Terzopoulos 95: annealing vs simplex, time vs frequency domain.

The shark with 3 actuators (left/right in antiphase per segment), M = 15 (NM = 45), goal
reaching E_v = |d_g|^2 with mu1 = 0, 3500 evaluations each. Also the cooling rates of
Fig. 6(b-c). Writes docs/figures/fig6.png, fig6_cooling.png and docs/figures/fig6.json.

Run: python experiments/fig6_optimizers.py [--budget 3500] [--seed 0]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from zoetic.learn.run import LearnConfig, build
from zoetic.viz.learning import plot_learning

OUT = Path(__file__).resolve().parents[1] / "docs" / "figures"


def learn_curve(config: LearnConfig, **anneal) -> tuple[np.ndarray, float]:
    """Return E of every evaluation and the wall time of one learning run."""
    setup = build(config)
    opt, obj = setup.optimizer, setup.objective
    if anneal:
        opt.T, opt.alpha = anneal.get("t0", opt.T), anneal.get("alpha", opt.alpha)
    curve: list[float] = []
    t0 = time.perf_counter()
    while opt.evaluations < config.budget and not opt.done():
        X = opt.ask()
        if len(X) == 0:
            break
        e = obj(X)
        opt.tell(X, e)
        curve.extend(e)
    if hasattr(opt, "close"):
        opt.close()
    return np.array(curve), time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--budget", type=int, default=3500)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    base = dict(animal="shark", task="reach-goal", nodes=15, coupling="antiphase",
                budget=args.budget, seed=args.seed)  # fmt: skip
    curves, report = {}, {}
    for optimizer in ("anneal", "simplex"):
        for controller in ("time", "frequency"):
            label = f"{optimizer}, {controller} domain"
            cfg = LearnConfig(optimizer=optimizer, controller=controller, **base)
            e, wall = learn_curve(cfg)
            curves[label] = e
            best = np.minimum.accumulate(np.where(np.isfinite(e), e, np.inf))
            near = int(np.argmax(best <= best[-1] + 0.05 * (best[0] - best[-1]))) + 1
            report[label] = {
                "final_E": round(float(best[-1]), 4),
                "initial_E": round(float(e[0]), 4),
                "evaluations_to_within_5pct": near,
                "evaluations": len(e),
                "seconds": round(wall, 2),
            }
            print(label, report[label], flush=True)
    plot_learning(curves, OUT / "fig6.png", title="Fig. 6(a): shark reaching a goal, NM = 45")
    cooling = {}
    for controller in ("time", "frequency"):
        for alpha in (0.8, 0.85, 0.9):
            cfg = LearnConfig(optimizer="anneal", controller=controller, **base)
            e, _ = learn_curve(cfg, alpha=alpha)
            cooling[f"{controller}, alpha {alpha}"] = e
            report[f"anneal {controller} alpha={alpha}"] = round(float(np.min(e)), 4)
    plot_learning(cooling, OUT / "fig6_cooling.png", title="Fig. 6(b-c): cooling rates")
    (OUT / "fig6.json").write_text(json.dumps(report, indent=2) + "\n")


if __name__ == "__main__":
    main()
