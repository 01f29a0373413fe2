"""Section 6.2 and Fig. 13 of van de Panne & Fiume 93, and two claims of Sections 4 and 6.1.

1. Robustness (Fig. 13): phase 1 (200 random SANs on flat ground) for the bouncer, the walker
   and the luxo; the ``--top`` best gaits that do not fall are replayed on rough ground (three
   seeds) and in a valley between two 10% hills (``terrain="hill"``); then the best is
   fine-tuned on flat ground (annealing) and replayed the same way. The paper: "the same mode
   of locomotion is usually maintained" on rough terrain, and "the gaits are not as robust
   once they have been fine-tuned".
2. Friction (Section 6.1: the three- and four-link chains' best gait depends on friction):
   phase 1 at friction 0.3, 0.6 and 1.0 (the zoo's) with the same 200 networks; the best speed
   at each and how the network that is best at 1.0 ranks at the others.
3. Node delays (Section 4: without them "a creature that rested in an immobile state"): the
   top 10 random networks of several creatures replayed with T_on = T_off = 0 (k1, k2 so
   large that a node switches within one control tick); how many still move.

Writes docs/figures/san_robustness.json.
Run: python experiments/san_robustness.py [--trials 200] [--top 5] [--tune-trials 250]
     [--parts robustness,friction,delays] (parts not run keep their old numbers in the JSON)
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time

import numpy as np

from zoetic.reproduce import figures_dir
from zoetic.san import load_creature
from zoetic.san.network import SanPolicy
from zoetic.san.search import search, speed_cm_s
from zoetic.san.tune import tune
from zoetic.san.world import World

OUT = figures_dir()
ROUGH_SEEDS = (1, 2, 3)
FRICTION_CHAINS = ("threelink", "fourlink")
DELAY_CREATURES = ("cart", "twolink", "threelink", "fourlink", "luxo", "bouncer")


def _speed(c, net, terrain: str, seed: int = 0) -> tuple[float, bool]:
    r = World(c, terrain=terrain, seed=seed).run(SanPolicy(net, c))
    return round(speed_cm_s(c, r.metric, r.distance), 1), bool(r.fell)


def _on_terrains(c, net) -> dict:
    flat, flat_fell = _speed(c, net, "flat")
    rough = [_speed(c, net, "rough", s) for s in ROUGH_SEEDS]
    hill, hill_fell = _speed(c, net, "hill")
    return {
        "flat": flat,
        "rough": [v for v, _ in rough],
        "rough_fell": sum(f for _, f in rough),
        "hill": hill,
        "hill_fell": hill_fell,
        "rough_over_flat": round(float(np.mean([v for v, _ in rough])) / max(flat, 1e-9), 2),
    }


def robustness(name: str, trials: int, top: int, tune_trials: int, workers: int) -> dict:
    """Return flat/rough/hill speeds of the top random gaits and of the tuned best."""
    c = load_creature(name)
    res = search(c, trials=trials, seed=0, workers=workers)
    kept = [i for i in res.order if not res.fell[i]][:top]
    random_rows = [dict(trial=int(i), **_on_terrains(c, res.networks[i])) for i in kept]
    tuned = tune(res.networks[kept[0]], c, method="anneal", trials=tune_trials, seed=0)
    tc = tuned.network.tuned_creature(c)
    return {"random": random_rows, "tuned_best": _on_terrains(tc, tuned.network)}


def friction(name: str, trials: int, workers: int, mus=(0.3, 0.6, 1.0)) -> dict:
    """Return, per friction coefficient, the best speed and where 1.0's best network ranks."""
    base = load_creature(name)
    out, ref = {}, None
    for mu in mus:
        c = dataclasses.replace(base, friction=mu)
        res = search(c, trials=trials, seed=0, workers=workers)
        ranks = {int(i): r for r, i in enumerate(res.order, start=1)}
        best = int(res.order[0])
        out[str(mu)] = {
            "best_trial": best,
            "best_cm_s": round(float(res.speeds[best]), 1),
            "_ranks": ranks,
            "_speeds": res.speeds,
        }
        if abs(mu - 1.0) < 1e-9:
            ref = best
    for row in out.values():
        row["rank_of_best_at_1.0"] = row.pop("_ranks")[ref]
        row["speed_of_best_at_1.0_cm_s"] = round(float(row.pop("_speeds")[ref]), 1)
    return out


def no_delays(name: str, trials: int, workers: int, top: int = 10) -> dict:
    """Return the top random networks' speeds with and without node delays."""
    c = load_creature(name)
    res = search(c, trials=trials, seed=0, workers=workers)
    world = World(c)
    with_d, without = [], []
    for i in res.top(top):
        net = res.networks[i]
        fast = net.with_params(k1=np.full_like(net.k1, 1e6), k2=np.full_like(net.k2, -1e6))
        r = world.run(SanPolicy(fast, c))
        with_d.append(round(float(res.speeds[i]), 1))
        without.append(round(speed_cm_s(c, r.metric, r.distance), 1))
    bar = c.useful_speed or 1.0
    return {
        "with_delays_cm_s": with_d,
        "without_delays_cm_s": without,
        "useful_with": sum(v >= bar for v in with_d),
        "useful_without": sum(v >= bar for v in without),
        "bar_cm_s": bar,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--top", type=int, default=5)
    ap.add_argument("--tune-trials", type=int, default=250)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--parts", default="robustness,friction,delays")
    args = ap.parse_args()
    parts = args.parts.split(",")
    OUT.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    path = OUT / "san_robustness.json"
    out: dict = json.loads(path.read_text()) if path.exists() else {}
    out.update(trials=args.trials, rough_seeds=list(ROUGH_SEEDS), hill_slope=0.1)
    for name in ("bouncer", "walker", "luxo") if "robustness" in parts else ():
        out.setdefault("robustness", {})
        out["robustness"][name] = robustness(
            name, args.trials, args.top, args.tune_trials, args.workers
        )
        print(name, json.dumps(out["robustness"][name]), flush=True)
    if "friction" in parts:
        out["friction"] = {n: friction(n, args.trials, args.workers) for n in FRICTION_CHAINS}
        print(json.dumps(out["friction"]), flush=True)
    if "delays" in parts:
        out["no_delays"] = {n: no_delays(n, args.trials, args.workers) for n in DELAY_CREATURES}
        print(json.dumps(out["no_delays"]), flush=True)
    out["wall_s"] = round(time.perf_counter() - t0, 1)
    path.write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
