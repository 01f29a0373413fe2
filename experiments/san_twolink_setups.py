"""Which twolink set-up shows the paper's three modes at Table 1's speed? (vdpf93 section 6.1)

The paper's two-link chain found "small flapping hops", "repeated 'jumps' onto its back" and
"a big aerial jump" among random SANs, and runs 12 cm/s (Table 1). The paper fixes only the
counts (2 links, 6 sensors, 1 actuator, 5 hidden nodes), one link heavier, the PD servo and
its suggested kd/ks = 0.1 s; the cart, its sibling with the same counts, has kd/ks = 0.05 s
and targets +-140 degrees (Fig. 11). Each set-up below changes the zoo's twolink in one or two
of the numbers the paper leaves open, then draws ``--trials`` random SANs (seed 0, the same
networks for every set-up), replays each once (``zoetic.san.gaits.gait_features``) and counts
the modes: small hops (in the air 15-30% of the time), big hops (30% or more), turned over
onto its back at least once (every link past 90 degrees), and repeatedly (the body turned
over twice or more). The
best two are then fine-tuned as Table 1 is (annealing, ``--tune-trials`` evaluations each).

"fold" is the creature file src/zoetic/san/zoo/variants/twolink-fold.toml (a variant, not a
zoo creature). Writes docs/figures/san_twolink_setups.json.
Run: python experiments/san_twolink_setups.py [--trials 300] [--tune-trials 250]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time

import numpy as np

from zoetic.reproduce import figures_dir
from zoetic.san import load_creature
from zoetic.san.gaits import REPEATED, gait_features
from zoetic.san.network import SanPolicy, random_network
from zoetic.san.search import speed_cm_s
from zoetic.san.show import record_every_for
from zoetic.san.tune import tune
from zoetic.san.world import World

FOLD = "src/zoetic/san/zoo/variants/twolink-fold.toml"  # kd/ks 0.05 s, targets +-180 degrees
SMALL_HOPS, BIG_HOPS = 0.15, 0.3  # of the time in the air: the gait labels' small, big hops
SETUPS = {  # name: changes to the zoo's twolink (see ``setup``)
    "zoo": {},
    "x2": {"strength": 2.0},
    "x4": {"strength": 4.0},
    "x8": {"strength": 8.0},
    "x16": {"strength": 16.0},
    "12 s": {"seconds": 12.0},
    "x2, 12 s": {"strength": 2.0, "seconds": 12.0},
    "L1 4x L2": {"masses": (0.2, 0.05)},
    "L2 heavier": {"masses": (0.1, 0.2)},
    "friction 0.3": {"friction": 0.3},
    "targets +-150": {"target_deg": 150.0},
    "targets +-180": {"target_deg": 180.0},
    "kd/ks 0.05": {"kd_ks": 0.05},
    "cart's servo": {"kd_ks": 0.05, "target_deg": 140.0},
    "cart's servo x2": {"strength": 2.0, "kd_ks": 0.05, "target_deg": 140.0},
    "fold": {"base": FOLD},
    "fold x0.7": {"base": FOLD, "strength": 0.7},
    "fold x0.5": {"base": FOLD, "strength": 0.5},
    "fold, friction 0.5": {"base": FOLD, "friction": 0.5},
    "fold, friction 0.3": {"base": FOLD, "friction": 0.3},
}


def setup(
    base: str = "twolink",
    strength: float = 1.0,
    kd_ks: float | None = None,
    target_deg: float | None = None,
    masses: tuple[float, float] | None = None,
    friction: float | None = None,
    seconds: float | None = None,
):
    """Return the ``base`` twolink (the zoo's, or a creature file) with its servo ``strength``
    times as stiff (ks and kd), kd/ks set to ``kd_ks`` s, targets +-``target_deg``, link masses
    (kg), friction, trial seconds."""
    c = load_creature(base)
    acts = []
    for a in c.actuators:
        ks = a.ks * strength
        a = dataclasses.replace(a, ks=ks, kd=a.kd * strength if kd_ks is None else ks * kd_ks)
        if target_deg is not None:
            a = dataclasses.replace(a, lo=-math.radians(target_deg), hi=math.radians(target_deg))
        acts.append(a)
    links = c.links
    if masses is not None:
        links = tuple(dataclasses.replace(ln, mass=m) for ln, m in zip(links, masses, strict=True))
    extra = {"friction": friction} if friction is not None else {}
    if seconds is not None:
        extra["seconds"] = seconds
    return dataclasses.replace(c, actuators=tuple(acts), links=links, **extra)


def survey(c, trials: int, seed: int, tune_trials: int) -> dict:
    """Return the modes counted over ``trials`` random SANs of ``c`` and the best tuned speed."""
    rng = np.random.default_rng(seed)
    nets = [random_network(c, rng) for _ in range(trials)]
    world, every = World(c), record_every_for(c, 50)
    feats, metrics = [], []
    for net in nets:
        ro = world.run(SanPolicy(net, c), record_every=every)
        feats.append(gait_features(c, ro))
        metrics.append(float(ro.metric) if np.isfinite(ro.metric) else -np.inf)
    speeds = np.array([f["speed_cm_s"] for f in feats])
    order = np.argsort(-np.array(metrics), kind="stable")
    repeated = [f for f in feats if f["flips"] >= REPEATED]
    tuned = []
    for i in order[:2] if tune_trials > 0 else []:
        res = tune(nets[i], c, method="anneal", trials=tune_trials, seed=0)
        tuned.append(round(speed_cm_s(c, res.after, 0.0), 1))
    return {
        "trials": trials,
        "moving": int((speeds >= 1.0).sum()),
        "small_hops": sum(SMALL_HOPS <= f["airborne"] < BIG_HOPS for f in feats),
        "big_hops": sum(f["airborne"] >= BIG_HOPS for f in feats),
        "turned_over": sum(f["flips"] >= 1 for f in feats),
        "repeated_flips": len(repeated),
        "repeated_cm_s": sorted((f["speed_cm_s"] for f in repeated), reverse=True),
        "top5_cm_s": [float(speeds[i]) for i in order[:5]],
        "tuned_cm_s": tuned,
        "best_tuned_cm_s": max([float(speeds[order[0]]), *tuned]),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--trials", type=int, default=300)
    ap.add_argument("--tune-trials", type=int, default=250)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--only", default="", help="set-up names separated by ; (default: all)")
    args = ap.parse_args()
    names = [n.strip() for n in args.only.split(";") if n.strip()] or list(SETUPS)
    path = figures_dir() / "san_twolink_setups.json"
    rows = json.loads(path.read_text()) if path.exists() else {}
    for name in names:
        t0 = time.perf_counter()
        row = survey(setup(**SETUPS[name]), args.trials, args.seed, args.tune_trials)
        rows[name] = {"changes": SETUPS[name], **row, "wall_s": round(time.perf_counter() - t0)}
        print(name, json.dumps({k: v for k, v in row.items() if k != "repeated_cm_s"}), flush=True)
        path.write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
