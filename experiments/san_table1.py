"""Table 1 of van de Panne & Fiume 93 (Sensor-actuator networks), reproduced.

The paper's procedure per creature: 200 random SANs (phase 1), each evaluated for the
creature's time (6 s; 30 s for the crawler and the fish) on flat ground, the top 10 kept, then
fine-tuning (phase 2: simulated annealing of the Fig. 8 parameters, weights kept) of the best
``--tune-top`` of them for ``--tune-trials`` evaluations each. Reported: the best random gait's
speed, the best tuned speed, the paper's, and the fraction of random networks that are useful,
both against the creature's absolute bar (``useful_speed_cm_s``: a quarter of Table 1's speed)
and relative to the search's best (``zoetic.san.search.useful_mask``). Then the cart: its best
kept gaits sorted into distinct modes by what the body does (rolls over, hops, direction,
which link carries it).

Writes docs/figures/san_table1.json, san_table1_ranking.png (every creature's ranking curve),
and san_cart_gaits.json (+ san_cart_gaits.png, one still per distinct mode).

Run: python experiments/san_table1.py [--trials 200] [--seed 0] [--creatures cart,walker]
     [--tune-top 2] [--tune-trials 250] [--workers 2] [--cart-trials 1000]
     [--no-gaits | --only-gaits] [--gait-creatures cart,bouncer,walker] [--rankings-only]
"""

from __future__ import annotations

import argparse
import json
import math
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from zoetic.san import list_creatures, load_creature
from zoetic.san.search import search, speed_cm_s, useful_mask, useful_threshold_cm_s
from zoetic.san.show import replay
from zoetic.san.tune import tune

OUT = Path(__file__).resolve().parents[1] / "docs" / "figures"


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


def gait_features(creature, rollout) -> dict:
    """Return what the body does over a replay: turns, height, contacts, direction."""
    poses = np.asarray(rollout.poses)  # (R, L, 3): x, height, angle
    ang = np.unwrap(poses[:, 0, 2])
    turns = (ang[-1] - ang[0]) / (2 * np.pi)
    touch = [i for i, s in enumerate(creature.sensors) if s.kind == "touch"]
    on = np.asarray(rollout.sensors)[:, touch]
    contact = on.mean(axis=0) if touch else np.zeros(0)
    airborne = float(np.mean(~on.any(axis=1))) if touch else 0.0
    return {
        "turns": round(float(turns), 2),
        "airborne": round(airborne, 2),
        "direction": "+x" if rollout.distance >= 0 else "-x",
        "contact": [round(float(v), 2) for v in contact],
        "speed_cm_s": round(speed_cm_s(creature, rollout.metric, rollout.distance), 1),
    }


def gait_mode(f: dict, creature) -> str:
    """Name a gait's mode from its features (coarse, by what one sees in the video)."""
    if abs(f["turns"]) >= 1.0:
        return "cartwheel (rolls over)"
    if f["airborne"] >= 0.15:
        return "hops"
    touch = [s.target for s in creature.sensors if s.kind == "touch"]
    if len(f["contact"]) and len(touch):
        per_link: dict[str, float] = {}
        for t, v in zip(touch, f["contact"], strict=True):
            per_link[t] = max(per_link.get(t, 0.0), v)
        mostly = sorted(per_link, key=per_link.get, reverse=True)
        if len(mostly) > 1 and per_link[mostly[1]] < 0.3:
            return f"drags on {mostly[0]}"
        if len(mostly) > 1 and per_link[mostly[1]] >= 0.3 and per_link[mostly[0]] >= 0.3:
            return "walks on both links"
    return "shuffles"


def cart_gaits(
    trials: int, seed: int, keep: int = 20, workers: int = 2, name: str = "cart"
) -> dict:
    """Search ``name`` (the cart) with ``trials`` networks and sort its best ``keep`` into modes."""
    c = load_creature(name)
    res = search(c, trials=trials, seed=seed, workers=workers)
    modes: dict[str, list] = {}
    stills = []
    for rank, i in enumerate(res.top(keep), start=1):
        if res.fell[i] or res.speeds[i] < 0.25 * res.speeds[res.top(1)[0]]:
            continue
        ro = replay(res.networks[i], c, fps=20)
        f = gait_features(c, ro)
        mode = f"{gait_mode(f, c)}, {f['direction']}"
        f.update(rank=rank, trial=int(i))
        if mode not in modes:
            stills.append((mode, res.networks[i], ro))
        modes.setdefault(mode, []).append(f)
    return {"trials": trials, "kept": keep, "modes": modes, "_stills": stills}


def plot_stills(c, stills, path: Path) -> None:
    """One row per distinct mode: the body drawn at a few instants, shifted along x."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from zoetic.san import draw

    n = len(stills)
    fig, axes = plt.subplots(n, 1, figsize=(8, 2.0 * n), dpi=100, squeeze=False)
    for ax, (mode, _net, ro) in zip(axes[:, 0], stills, strict=True):
        frames = list(draw.render_frames(c, ro, size=(480, 200)))
        picks = np.linspace(len(frames) // 4, len(frames) - 1, 4).astype(int)
        ax.imshow(np.concatenate([frames[k] for k in picks], axis=1))
        ax.set_title(mode, fontsize=9)
        ax.axis("off")
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
    ap.add_argument("--cart-trials", type=int, default=1000)
    ap.add_argument("--no-gaits", action="store_true")
    ap.add_argument("--only-gaits", action="store_true")
    ap.add_argument("--rankings-only", action="store_true", help="phase 1 and the ranking plot")
    ap.add_argument("--gait-creatures", default="cart", help="whose kept gaits to sort")
    args = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    names = [n for n in args.creatures.split(",") if n] or list_creatures()
    if args.rankings_only:
        res = {n: search(load_creature(n), args.trials, seed=args.seed, workers=args.workers)
               for n in names}  # fmt: skip
        plot_rankings(res, OUT / "san_table1_ranking.png")
        return
    if not args.only_gaits:
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
    for name in [] if args.no_gaits else args.gait_creatures.split(","):
        n = args.cart_trials if name == "cart" else args.trials
        gaits = cart_gaits(n, args.seed, workers=args.workers, name=name)
        stills = gaits.pop("_stills")
        (OUT / f"san_{name}_gaits.json").write_text(json.dumps(gaits, indent=2) + "\n")
        try:
            if stills:
                plot_stills(load_creature(name), stills, OUT / f"san_{name}_gaits.png")
        except ImportError as exc:  # drawing is optional for the numbers
            print(f"no stills: {exc}")
        print(name, json.dumps({k: len(v) for k, v in gaits["modes"].items()}, indent=2))


if __name__ == "__main__":
    main()
