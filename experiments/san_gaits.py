"""Gait modes (van de Panne & Fiume 93, section 6.1) and evolution (section 6.3), measured.

1. Modes. The cart: 1000 random SANs (the paper's run), the best ``--cart-keep`` that do not
   fall replayed and sorted into distinct modes by what the body does
   (``zoetic.san.gaits``: direction, speed, rolling, time in the air, bounce, which link
   carries the weight, periodicity; average linkage cut at a stated distance on fixed
   scales). Then each mode's fastest network is fine-tuned (annealing, ``--tune-trials``
   evaluations) as the paper did to make promising modes periodic, and replayed: does it stay
   in its mode, is it more periodic, faster? The twolink, bouncer and walker: 200 random SANs,
   the best ``--keep``, sorted the same way (``--keep 0``: every gait that moves at least
   1 cm/s without falling). ``--strengths 1,4`` runs each creature once per factor S, which
   multiplies every actuator's stiffness and damping: the zoo's twolink is calibrated to
   Table 1's speed, and whether the paper's flips onto the back and aerial jumps appear
   depends on how strong its one actuator is, which the paper does not give; such a run is
   recorded under "<creature>-x<S>". A creature may be a file (``--creatures
   twolink,src/zoetic/san/zoo/variants/twolink-fold.toml``); its rows are named by the file's
   creature.
2. Evolution. Per creature, the best of 200 random SANs is improved for ``--evolve-trials``
   evaluations two ways from the same start: fine-tuning of the network alone (phase 2), and
   ``zoetic.san.evolve`` (body and network together, masses coupled to lengths, sections and
   actuator strength). Reported: speed before, tuned, evolved, and what evolution changed.

Writes docs/figures/san_modes.json (+ san_modes_<creature>.png, one still row per mode),
san_evolve.json; clips and evolved creature files under runs/san_gaits/.

Run: python experiments/san_gaits.py [--seed 0] [--workers 2] [--only modes|evolve]
     [--creatures cart,twolink,bouncer,walker] [--evolve-creatures cart,twolink,luxo,walker]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from zoetic.reproduce import figures_dir
from zoetic.san import load_creature
from zoetic.san.evolve import changes, evolve, write_evolve
from zoetic.san.gaits import THRESHOLD, describe_gaits, feature_matrix, gait_features, write_modes
from zoetic.san.search import search, speed_cm_s
from zoetic.san.show import replay
from zoetic.san.tune import tune
from zoetic.viz.san import draw_modes

ROOT = Path(__file__).resolve().parents[1]
OUT = figures_dir()
RUNS = ROOT / "runs" / "san_gaits"


def _rel(path: str | None) -> str | None:
    """Return ``path`` relative to the repository (the JSON is committed)."""
    return None if path is None else str(Path(path).resolve().relative_to(ROOT))


def _tune_mode(job: tuple) -> dict:
    """Fine-tune one mode's fastest network and replay it: mode kept? periodic? faster?"""
    net, c, trials, before = job
    res = tune(net, c, method="anneal", trials=trials, seed=0)
    after = gait_features(res.network.tuned_creature(c), replay(res.network, c, fps=50))
    X, _ = feature_matrix([before, after])
    return {
        "speed_before_cm_s": before["speed_cm_s"], "speed_after_cm_s": after["speed_cm_s"],
        "periodicity_before": before["periodicity"], "periodicity_after": after["periodicity"],
        "turns_after": after["turns"], "airborne_after": after["airborne"],
        "label_after": describe_gaits([after])[0].label,
        "distance_to_start": round(float(np.linalg.norm(X[0] - X[1])), 2),
        "same_mode": bool(np.linalg.norm(X[0] - X[1]) <= THRESHOLD),
    }  # fmt: skip


def strengthened(name: str, strength: float):
    """Return the creature (a zoo name or a creature file) with every actuator's ks and kd
    multiplied by ``strength``."""
    c = load_creature(name)
    if strength == 1.0:
        return c
    acts = tuple(
        dataclasses.replace(a, ks=a.ks * strength, kd=a.kd * strength) for a in c.actuators
    )
    return dataclasses.replace(c, name=f"{c.name}-x{strength:g}", actuators=acts)


def modes(
    name: str, trials: int, keep: int, seed: int, workers: int, tune_trials: int,
    strength: float = 1.0,
) -> dict:  # fmt: skip
    """Search, sort the best ``keep`` gaits (0: all that move) into modes (clips), fine-tune
    each mode (cart)."""
    c = strengthened(name, strength)
    t0 = time.perf_counter()
    res = search(c, trials=trials, seed=seed, workers=workers)
    ranked = res.top(len(res.networks))
    moving = [i for i in ranked if not res.fell[i] and res.metrics[i] > 0]
    kept = moving[:keep] if keep > 0 else [i for i in moving if res.speeds[i] >= 1.0]
    info = [{"rank": ranked.index(i) + 1, "trial": int(i)} for i in kept]
    networks = [res.networks[i] for i in kept]
    doc = write_modes(c, networks, info, RUNS / c.name, seed=seed)
    draw_modes(c, networks, doc, seed=seed, workers=workers)
    row = {
        "creature": c.name, "trials": trials, "kept": len(kept), "modes_found": doc["modes_found"],
        "kinds": doc["kinds"],
        "modes": [{"mode": m["mode"], "label": m["label"], "count": m["count"],
                   "best_cm_s": m["best"]["speed_cm_s"], "best_rank": m["best"]["rank"],
                   "turns": m["best"]["turns"], "upside": m["best"].get("upside"),
                   "flips": m["best"].get("flips"), "airborne": m["best"]["airborne"],
                   "periodicity": m["best"]["periodicity"], "clip": _rel(m.get("clip"))}
                  for m in doc["modes"]],
    }  # fmt: skip
    if tune_trials > 0:
        jobs = [(res.networks[m["best"]["trial"]], c, tune_trials, m["best"]) for m in doc["modes"]]
        with ProcessPoolExecutor(max_workers=max(1, min(workers, len(jobs)))) as pool:
            for m, t in zip(row["modes"], pool.map(_tune_mode, jobs), strict=True):
                m["fine_tuned"] = t
    row["wall_s"] = round(time.perf_counter() - t0, 1)
    _stills(c, res, doc, OUT / f"san_modes_{c.name}.png")
    print(c.name, json.dumps({m["label"]: m["count"] for m in row["modes"]}), flush=True)
    return row


def _stills(c, res, doc: dict, path: Path) -> None:
    """One row per mode: its fastest network's body at four instants."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from zoetic.viz import san as draw
    except ImportError as exc:  # drawing is optional for the numbers
        print(f"no stills: {exc}")
        return
    n = len(doc["modes"])
    fig, axes = plt.subplots(n, 1, figsize=(8, 1.9 * n), dpi=90, squeeze=False)
    for ax, m in zip(axes[:, 0], doc["modes"], strict=True):
        ro = replay(res.networks[m["best"]["trial"]], c, fps=10)
        frames = list(draw.render_frames(c, ro, size=(400, 180)))
        picks = np.linspace(len(frames) // 5, len(frames) - 1, 4).astype(int)
        ax.imshow(np.concatenate([frames[k] for k in picks], axis=1))
        ax.set_title(f"mode {m['mode']}: {m['label']} ({m['count']} networks, "
                     f"{m['best']['speed_cm_s']:.1f} cm/s)", fontsize=9)  # fmt: skip
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def _evolve_job(job: tuple) -> dict:
    name, seed, trials = job
    c = load_creature(name)
    res = search(c, trials=200, seed=seed, workers=1)
    ok = [i for i in res.top(200) if not res.fell[i]]
    net = res.networks[ok[0]]
    tuned = tune(net, c, method="anneal", trials=trials, seed=seed)
    ev = evolve(net, c, trials=trials, seed=seed)
    summary = write_evolve(ev, RUNS / f"{name}-evolve")
    cm = lambda m: round(speed_cm_s(c, m, 0.0), 1)  # noqa: E731
    return {
        "creature": name, "trials": trials, "start_cm_s": cm(ev.before),
        "tuned_cm_s": cm(tuned.after), "evolved_cm_s": cm(ev.after),
        "changes": changes(ev), "creature_file": _rel(summary["creature_file"]),
        "wall_s": round(ev.elapsed, 1),
    }  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--only", choices=("modes", "evolve"), default=None)
    ap.add_argument("--creatures", default="cart,twolink,bouncer,walker")
    ap.add_argument("--cart-trials", type=int, default=1000)
    ap.add_argument("--modes-file", default="san_modes.json", help="JSON the modes merge into")
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--cart-keep", type=int, default=40)
    ap.add_argument("--keep", type=int, default=20, help="0: every gait that moves")
    ap.add_argument("--strengths", default="1", help="actuator ks, kd multipliers, e.g. 1,4")
    ap.add_argument("--tune-trials", type=int, default=150, help="per cart mode")
    ap.add_argument("--evolve-creatures", default="cart,twolink,luxo,walker")
    ap.add_argument("--evolve-trials", type=int, default=300)
    args = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    if args.only != "evolve":
        rows = {}
        strengths = [float(s) for s in args.strengths.split(",") if s]
        for name in [n for n in args.creatures.split(",") if n]:
            cart = name == "cart"
            for k in strengths:
                row = modes(
                    name, args.cart_trials if cart else args.trials,
                    args.cart_keep if cart else args.keep, args.seed, args.workers,
                    args.tune_trials if cart else 0, k,
                )  # fmt: skip
                rows[row["creature"]] = row  # "<name>-x<S>" when strengthened
        path = OUT / args.modes_file
        old = json.loads(path.read_text()) if path.exists() else {}
        path.write_text(json.dumps({**old, **rows}, indent=2) + "\n")
    if args.only != "modes":
        names = [n for n in args.evolve_creatures.split(",") if n]
        jobs = [(n, args.seed, args.evolve_trials) for n in names]
        with ProcessPoolExecutor(max_workers=max(1, min(args.workers, len(jobs)))) as pool:
            rows = {r["creature"]: r for r in pool.map(_evolve_job, jobs)}
        for r in rows.values():
            print(r["creature"], r["start_cm_s"], r["tuned_cm_s"], r["evolved_cm_s"], flush=True)
        path = OUT / "san_evolve.json"
        old = json.loads(path.read_text()) if path.exists() else {}
        path.write_text(json.dumps({**old, **rows}, indent=2) + "\n")


if __name__ == "__main__":
    main()
