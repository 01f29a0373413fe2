"""Fig. 10 of van de Panne & Fiume 93: the fish (and the crawler) chasing a dragged point.

For each creature: 200 random SANs evaluated on the follow metric (30 s, the follow point
dragged along a seeded spline), the best fine-tuned by annealing; then the tuned best is
replayed on the search's spline and on two other splines (seeds 1 and 2) it never saw. Plots
the creature's path (centre of its links) and the point's, and the distance between them
over time.

Writes docs/figures/san_pursuit.json and san_pursuit.png.
Run: python experiments/san_pursuit.py [--trials 200] [--tune-trials 150] [--workers 2]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from zoetic.reproduce import figures_dir

from zoetic.san import load_creature
from zoetic.san.search import search, speed_cm_s
from zoetic.san.show import replay
from zoetic.san.tune import tune

OUT = figures_dir()
SEEDS = (0, 1, 2)


def pursue(name: str, trials: int, tune_trials: int, workers: int) -> tuple[dict, list]:
    """Return the pursuit numbers per spline seed and the recorded rollouts."""
    c = load_creature(name)
    res = search(c, trials=trials, seed=0, workers=workers)
    best = res.top(1)[0]
    tuned = tune(res.networks[best], c, method="anneal", trials=tune_trials, seed=0)
    rows, rollouts = {}, []
    for seed in SEEDS:
        ro = replay(tuned.network, c, seed=seed, fps=10)
        body = np.asarray(ro.poses)[:, :, :2].mean(axis=1)
        gap = np.linalg.norm(np.asarray(ro.follow) - body, axis=1)
        rows[str(seed)] = {
            "pursuit_cm_s": round(speed_cm_s(c, ro.metric, ro.distance), 1),
            "gap_start_m": round(float(gap[0]), 2),
            "gap_end_m": round(float(gap[-1]), 2),
            "gap_mean_m": round(float(gap.mean()), 2),
        }
        rollouts.append((seed, ro, body, gap))
    out = {
        "random_best_cm_s": round(float(res.speeds[best]), 1),
        "tuned_cm_s": round(speed_cm_s(c, tuned.after, 0.0), 1),
        "follow_speed_m_s": c.follow_speed,
        "splines": rows,
    }
    return out, rollouts


def plot(results: dict, path: Path) -> None:
    """Per creature: paths (left) and the distance to the point over time (right)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from zoetic.viz.plots import save_figure

    fig, axes = plt.subplots(len(results), 2, figsize=(10, 3.6 * len(results)), squeeze=False)
    for (name, rollouts), (ax_p, ax_d) in zip(results.items(), axes, strict=True):
        for seed, ro, body, gap in rollouts:
            f = np.asarray(ro.follow)
            (line,) = ax_p.plot(body[:, 0], body[:, 1], lw=1.5, label=f"{name}, spline {seed}")
            ax_p.plot(f[:, 0], f[:, 1], ls="--", lw=1, color=line.get_color())
            ax_d.plot(ro.times, gap, color=line.get_color(), label=f"spline {seed}")
        ax_p.set_title(f"{name}: path (solid) and follow point (dashed), top view", fontsize=9)
        ax_p.set_aspect("equal", adjustable="datalim")
        ax_p.set_xlabel("x (m)")
        ax_p.set_ylabel("z, to the left (m)")
        ax_d.set_title(f"{name}: distance to the follow point", fontsize=9)
        ax_d.set_xlabel("time (s)")
        ax_d.set_ylabel("m")
        ax_d.legend(fontsize=7)
        for ax in (ax_p, ax_d):
            ax.grid(alpha=0.3)
    save_figure(fig, path, dpi=100)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--tune-trials", type=int, default=150)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    numbers, recorded = {}, {}
    for name in ("fish", "crawler"):
        numbers[name], recorded[name] = pursue(name, args.trials, args.tune_trials, args.workers)
        print(name, json.dumps(numbers[name]), flush=True)
    (OUT / "san_pursuit.json").write_text(json.dumps(numbers, indent=2) + "\n")
    plot(recorded, OUT / "san_pursuit.png")


if __name__ == "__main__":
    main()
