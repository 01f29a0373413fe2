"""Does the SAN search generalise? Held-out creatures beside the zoo's (issue 26, item 7).

Per creature and seed: phase 1 (``--trials`` random SANs, the creature's own time) and
phase 2 (the best network fine-tuned by ``--method`` for ``--tune-trials`` evaluations).
Reported in body lengths per second (``Creature.size``, the sum of the link lengths), so
small and large creatures compare: the useful fraction (no fall and at least
``zoetic.san.search.USEFUL_BODY_LENGTHS_S`` = 0.1 body lengths/s), the falls, the best random
speed and the best tuned speed. The held-out creatures live in ``tests/data/san_heldout/``;
the search was never tuned on them.

Run: python experiments/san_heldout.py [--creatures all] [--seeds 0,21] [--trials 200]
     [--tune-trials 150] [--method sga] [--workers 2] [--out docs/figures/san_heldout.json]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from zoetic.san import load_creature
from zoetic.san.search import body_length_bar_cm_s, search, speed_cm_s, useful_mask
from zoetic.san.tune import tune

HELDOUT = Path(__file__).resolve().parents[1] / "tests" / "data" / "san_heldout"
ZOO = ["twolink", "threelink", "fourlink", "cart", "star", "luxo", "bouncer", "walker"]


def creatures(spec: str) -> list[str]:
    """Return the creatures named by ``spec``: all, zoo, heldout or a comma list."""
    held = [str(p) for p in sorted(HELDOUT.glob("*.toml"))]
    groups = {"zoo": ZOO, "heldout": held, "all": held + ZOO}
    return groups.get(spec) or spec.split(",")


def row(name: str, seed: int, trials: int, tune_trials: int, method: str, workers: int) -> dict:
    """Return one creature's figures for one seed (speeds in body lengths/s)."""
    c = load_creature(name)
    t0 = time.perf_counter()
    res = search(c, trials=trials, seed=seed, workers=workers)
    bl = 100.0 * c.size  # cm per body length
    useful = useful_mask(res, body_length_bar_cm_s(c))
    ok = ~res.fell
    best_random = float(res.speeds[ok].max()) if ok.any() else 0.0
    tuned = best_random
    if tune_trials > 0:
        best = res.top(1)[0]
        out = tune(res.networks[best], c, method=method, trials=tune_trials, seed=seed)
        tuned = max(tuned, speed_cm_s(c, out.after, 0.0))
    return {
        "creature": c.name,
        "seed": seed,
        "size_m": round(c.size, 3),
        "useful": round(float(useful.mean()), 3),
        "fell": round(float(res.fell.mean()), 3),
        "best_random_bl_s": round(best_random / bl, 3),
        "best_tuned_bl_s": round(tuned / bl, 3),
        "best_random_cm_s": round(best_random, 2),
        "best_tuned_cm_s": round(tuned, 2),
        "seconds": round(time.perf_counter() - t0, 1),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--creatures", default="all")
    ap.add_argument("--seeds", default="0,21")
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--tune-trials", type=int, default=150)
    ap.add_argument("--method", default="sga")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    rows = []
    for name in creatures(a.creatures):
        for seed in (int(s) for s in a.seeds.split(",")):
            r = row(name, seed, a.trials, a.tune_trials, a.method, a.workers)
            rows.append(r)
            print(json.dumps(r), flush=True)
    summary: dict[str, dict] = {}
    for r in rows:
        summary.setdefault(r["creature"], []).append(r)
    for name, rs in summary.items():
        med = {
            k: float(np.median([x[k] for x in rs]))
            for k in rs[0]
            if k.endswith(("l_s", "ul", "ll"))
        }
        print(
            f"{name:10s} useful {med['useful']:.3f} fell {med['fell']:.2f} "
            f"random {med['best_random_bl_s']:.3f} BL/s tuned {med['best_tuned_bl_s']:.3f} BL/s"
        )
    if a.out:
        Path(a.out).write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
