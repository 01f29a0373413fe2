"""SGA against annealing for SAN tuning (issue 26 item 4; the paper's discussion, Section 5).

Per creature: the best of ``--trials`` random SANs (phase 1, seed 0) is fine-tuned by
``sga`` (keep a change only if it improves) and by ``anneal`` (65 evaluations per
temperature, T <- 0.75 T) with the same evaluation budget ``--budget``, over ``--seeds``.
Reported: the tuned speed (cm/s and body lengths/s) per method and seed, and the median
gain over the start. Both walks use ``zoetic.san.tune.tune``; only ``method`` differs.

Run: python experiments/san_tuners.py [--creatures cart,threelink,luxo] [--budget 200]
     [--seeds 0,1] [--workers 2] [--out docs/figures/san_tuners.json]
"""

from __future__ import annotations

import argparse
import json
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from zoetic.san import load_creature
from zoetic.san.search import search, speed_cm_s
from zoetic.san.tune import tune


def _job(job: tuple) -> dict:
    name, net, method, budget, seed = job
    c = load_creature(name)
    out = tune(net, c, method=method, trials=budget, seed=seed)
    return {
        "creature": c.name,
        "method": method,
        "seed": seed,
        "before_cm_s": round(speed_cm_s(c, out.before, 0.0), 2),
        "after_cm_s": round(speed_cm_s(c, out.after, 0.0), 2),
        "after_bl_s": round(speed_cm_s(c, out.after, 0.0) / (100.0 * c.size), 3),
        "accepted": out.accepted,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--creatures", default="cart,threelink,luxo")
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--budget", type=int, default=200)
    ap.add_argument("--seeds", default="0,1")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    jobs = []
    for name in a.creatures.split(","):
        res = search(load_creature(name), trials=a.trials, seed=0, workers=a.workers)
        net = res.networks[res.top(1)[0]]
        for seed in (int(s) for s in a.seeds.split(",")):
            jobs += [(name, net, method, a.budget, seed) for method in ("sga", "anneal")]
    with ProcessPoolExecutor(max_workers=a.workers) as pool:
        rows = list(pool.map(_job, jobs))
    for r in rows:
        print(json.dumps(r), flush=True)
    print(f"{'creature':10s} {'start':>7s} {'sga':>12s} {'anneal':>12s} cm/s, budget {a.budget}")
    for name in dict.fromkeys(r["creature"] for r in rows):
        rs = [r for r in rows if r["creature"] == name]
        med = {
            m: np.median([r["after_cm_s"] for r in rs if r["method"] == m])
            for m in ("sga", "anneal")
        }
        runs = {
            m: "/".join(f"{r['after_cm_s']:.0f}" for r in rs if r["method"] == m)
            for m in ("sga", "anneal")
        }
        print(
            f"{name:10s} {rs[0]['before_cm_s']:7.1f} {med['sga']:6.1f} ({runs['sga']}) "
            f"{med['anneal']:6.1f} ({runs['anneal']})"
        )
    if a.out:
        Path(a.out).write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
