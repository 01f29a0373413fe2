"""Table 1 of van de Panne & Fiume 93 (Sensor-actuator networks), reproduced.

The paper's procedure per creature: 200 random SANs (phase 1), each evaluated for the
creature's time (6 s; 30 s for the crawler and the fish) on flat ground, the top 10 kept, then
fine-tuning (phase 2: simulated annealing of the Fig. 8 parameters, weights kept) of the best
``--tune-top`` of them for ``--tune-trials`` evaluations each. Reported: the best random gait's
speed, the best tuned speed, the paper's, and the fraction of random networks that are useful,
both against the creature's absolute bar (``useful_speed_cm_s``: a quarter of Table 1's speed)
and relative to the search's best (``zoetic.san.search.useful_mask``). The gait modes (the
cart's five) are ``experiments/san_gaits.py``.

Writes docs/figures/san_table1.json and san_table1_ranking.png (every creature's ranking
curve).

Run: python experiments/san_table1.py [--trials 200] [--seed 0] [--creatures cart,walker]
     [--tune-top 2] [--tune-trials 250] [--workers 2] [--rankings-only]
"""

from __future__ import annotations

import argparse
import json
import math
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from zoetic.reproduce import figures_dir
from zoetic.san import list_creatures, load_creature
from zoetic.san.search import search, speed_cm_s, useful_mask, useful_threshold_cm_s
from zoetic.san.tune import tune

OUT = figures_dir()


def _tune_job(job: tuple) -> float:
    net, c, trials = job
    return float(tune(net, c, method="anneal", trials=trials, seed=0).after)


def table(
    names: list[str], trials: int, seed: int, tune_top: int, tune_trials: int, workers: int
) -> tuple[dict, dict]:
    """Return Table 1 rows per creature (phase 1, then phase 2 on the best) and the searches."""
    rows, results = {}, {}
    for name in names:
        c = load_creature(name)
        t0 = time.perf_counter()
        res = search(c, trials=trials, seed=seed, workers=workers)
        best = res.top(1)[0]
        use = useful_mask(res)
        absolute = useful_mask(res, c.useful_speed) if c.useful_speed else None
        jobs = [(res.networks[i], c, tune_trials) for i in res.top(tune_top)]
        with ProcessPoolExecutor(max_workers=max(1, min(workers, len(jobs)))) as pool:
            tuned = list(pool.map(_tune_job, jobs)) if jobs and tune_trials > 0 else []
        tuned_cm_s = [round(speed_cm_s(c, f, 0.0), 1) for f in tuned]
        best_tuned = max([float(res.speeds[best]), *tuned_cm_s])
        rows[name] = {
            "links": len(c.links), "sensors": c.n_sensors, "actuators": c.n_actuators,
            "hidden": res.networks[0].n_hidden, "metric": c.metric, "seconds": c.seconds,
            "best_speed_cm_s": round(float(res.speeds[best]), 1),
            "top10_cm_s": [round(float(res.speeds[i]), 1) for i in res.top(10)],
            "tuned_cm_s": tuned_cm_s, "tune_trials": tune_trials,
            "best_tuned_cm_s": round(best_tuned, 1),
            "paper_speed_cm_s": c.paper_speed,
            "within_2x": None if not c.paper_speed else bool(
                0.5 <= best_tuned / c.paper_speed <= 2.0),
            "useful_bar_cm_s": c.useful_speed,
            "useful_absolute": None if absolute is None else int(absolute.sum()),
            "useful_absolute_fraction": None if absolute is None else round(
                float(absolute.mean()), 3),
            "useful_relative": int(use.sum()), "useful_relative_fraction": round(
                float(use.mean()), 3),
            "useful_relative_threshold_cm_s": round(useful_threshold_cm_s(res), 2),
            "fell": int(res.fell.sum()),
            "median_speed_cm_s": round(float(np.median(res.speeds)), 2),
            "wall_s": round(time.perf_counter() - t0, 1),
        }  # fmt: skip
        results[name] = res
        print(name, rows[name], flush=True)
    return rows, results


def plot_rankings(results: dict, path: Path) -> None:
    """One panel per creature: speed (cm/s) of every random SAN from best to worst."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(results)
    cols = min(5, n)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.0 * cols, 2.4 * rows), dpi=100, squeeze=False)
    for ax, (name, res) in zip(axes.flat, results.items(), strict=False):
        s = res.speeds[res.order]
        ax.plot(np.arange(1, len(s) + 1), s, color="0.25", lw=1.2)
        thr = res.creature.useful_speed or useful_threshold_cm_s(res)
        ax.axhline(thr, color="tab:green", ls=":", lw=1)
        if res.creature.paper_speed:
            ax.axhline(res.creature.paper_speed, color="tab:red", ls="--", lw=1)
        ax.set_title(f"{name} ({useful_mask(res, thr).mean() * 100:.1f}% useful)", fontsize=9)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    fig.supxlabel("rank of the random network", fontsize=9)
    fig.supylabel("speed (cm/s); red: paper's best, green: useful", fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--creatures", default="")
    ap.add_argument("--tune-top", type=int, default=2, help="tune this many of the best")
    ap.add_argument("--tune-trials", type=int, default=250, help="annealing evaluations each")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--rankings-only", action="store_true", help="phase 1 and the ranking plot")
    args = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    names = [n for n in args.creatures.split(",") if n] or list_creatures()
    if args.rankings_only:
        res = {n: search(load_creature(n), args.trials, seed=args.seed, workers=args.workers)
               for n in names}  # fmt: skip
        plot_rankings(res, OUT / "san_table1_ranking.png")
        return
    rows, results = table(
        names, args.trials, args.seed, args.tune_top, args.tune_trials, args.workers
    )
    path = OUT / "san_table1.json"
    if args.creatures and path.exists():  # a partial run updates its creatures' rows
        rows = {**json.loads(path.read_text()), **rows}
        print("partial run: san_table1_ranking.png not redrawn")
    else:
        plot_rankings(results, OUT / "san_table1_ranking.png")
    path.write_text(json.dumps(dict(sorted(rows.items())), indent=2) + "\n")


if __name__ == "__main__":
    main()
