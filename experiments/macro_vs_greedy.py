"""Greedy tracking (Fig. 5) and planned macro controllers (section 3.2) on the same repertoire.

Part 1, Fig. 5: the shark greedily tracks a course of five targets; prints the real-time
factor (simulated s per wall s) of tracking, all six entries simulated as one batch at each
1 s re-evaluation.
Part 2, a task that needs planning: the goal lies behind the shark, and an obstacle disc sits
inside the tight left U-turn that greedy tracking takes. Greedy tracking (the obstacle in its
gain, with two weights, and the literal distance-only gain) against simulated annealing and
a genetic algorithm over plans of 6 (entry, duration) segments, each for several seeds, the
plans searched and played with the righting reflex as ``zoetic macro`` does (--no-righting: as
planned).

Writes docs/figures/fig5_tracking.png, macro_vs_greedy.png and macro_vs_greedy.json.
Run: python experiments/macro_vs_greedy.py [--memory memory/shark] [--budget 2000]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from zoetic.behavior.handmade import handmade_repertoire
from zoetic.behavior.macro import MacroProblem, ReachTask, path_scores, search
from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.tracking import TrackConfig, track
from zoetic.bodies import load_animal
from zoetic.io import write_json
from zoetic.reproduce import figures_dir

OUT = figures_dir()
COURSE = np.array([[2.0, 0.5], [4.0, 2.0], [5.0, 4.5], [3.5, 6.5], [1.0, 7.0]])
GOAL, OBSTACLE, HORIZON = (-4.0, 1.0), (0.5, 2.5, 1.0), 60.0
COLORS = {"greedy": "C0", "SA": "C1", "GA": "C2"}


def fig5(body, rep, tag: str = "") -> dict:
    """Track the five-target course; return its numbers and write its path figure."""
    from zoetic.viz.plots import plot_path

    res = track(body, rep, COURSE, TrackConfig(time_limit=120.0))
    s = res.summary()
    plot_path(res.com, OUT / f"fig5_tracking{tag}.png", targets=COURSE, starts=res.start_indices,
              title=f"Fig. 5: greedy tracking, {s['reached']}/{len(COURSE)} targets, "
                    f"{s['realtime_factor']:.0f}x real time")  # fmt: skip
    return s


def greedy(body, rep, task, radius, **config) -> tuple[dict, np.ndarray]:
    """Return greedy tracking's scores on the task and its path (R, 3)."""
    cfg = TrackConfig(time_limit=task.horizon, obstacles=np.array([OBSTACLE]), **config)
    res = track(body, rep, np.array([task.goal]), cfg)
    s = path_scores(res.com[None][..., [0, 2]], float(res.times[1]), task, radius)
    row = {k: float(v[0]) for k, v in s.items()} | {"wall_s": res.wall}
    print(f"  worst roll {res.motion['worst_roll_deg']:.0f} deg, depth span "
          f"{res.motion['depth_span_m']} m")  # fmt: skip
    return row, res.com


def _row(name: str, s: dict, evaluations: int = 0) -> str:
    reach = "never" if not np.isfinite(s["reach"]) else f"{s['reach']:.1f} s"
    return (f"{name:30s} E {s['cost']:6.2f}  final {s['final']:5.2f} m  closest "
            f"{s['closest']:5.2f} m  in obstacle {s['inside']:5.1f} s  reached {reach:>7s}"
            f"  {evaluations:5d} evals  {s['wall_s']:5.1f} s wall")  # fmt: skip


def figure(paths: dict, curves: dict, path: Path) -> None:
    """Write the paths beside the search curves (best E against evaluations)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle

    fig = Figure(figsize=(11, 4.6), dpi=110)
    FigureCanvasAgg(fig)
    ax, bx = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.25, 1]})
    ax.add_patch(Circle(OBSTACLE[:2], OBSTACLE[2], fc="0.78", ec="0.35", hatch="//",
                        label="obstacle"))  # fmt: skip
    for name, com in paths.items():
        ax.plot(com[:, 0], com[:, 2], lw=1.8, label=name, color=COLORS[name.split(" ")[0]])
    ax.plot(*paths[next(iter(paths))][0, [0, 2]], "s", color="0.2", ms=7, label="start")
    ax.plot(*GOAL, "o", color="black", ms=9, label="goal")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set(xlabel="x (m, forward)", ylabel="z (m, left)", title="U-turn past an obstacle")
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.legend(fontsize=8, loc="lower left")
    for name, runs in curves.items():
        for k, (n, f) in enumerate(runs):
            bx.plot(n, f, color=COLORS[name], alpha=0.8, label=name if k == 0 else None)
    bx.set_yscale("log")
    ticks = [0.5, 0.6, 0.8, 1, 1.5, 2, 3, 4, 6]
    bx.set_yticks(ticks, [f"{t:g}" for t in ticks])
    bx.minorticks_off()
    bx.set(xlabel="plans evaluated", ylabel="best E (m)", title="search progress (each seed)")
    bx.grid(True, lw=0.4, alpha=0.5)
    bx.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--memory", default=None, help="repertoire dir (default: the hand-made one)")
    ap.add_argument("--budget", type=int, default=2000)
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--tag", default="", help="suffix of the output files, e.g. _learned")
    ap.add_argument("--no-righting", action="store_true", help="plans played as planned")
    args = ap.parse_args()
    tag = args.tag
    body = load_animal("shark")
    rep = Repertoire.load(args.memory, body) if args.memory else handmade_repertoire(body)
    OUT.mkdir(parents=True, exist_ok=True)
    report = {"repertoire": args.memory or "hand-made (zoetic.behavior.tracking)",
              "fig5": fig5(body, rep, tag)}  # fmt: skip
    print(f"Fig. 5 course: {report['fig5']}")

    task = ReachTask(GOAL, (OBSTACLE,), HORIZON)
    righting = None if args.no_righting else TrackConfig()
    problem = MacroProblem(body, rep, task, segments=6, righting=righting)
    rows, paths = {}, {}
    for name, cfg in (("greedy", {}), ("greedy, obstacle weight 10", {"obstacle_weight": 10.0}),
                      ("greedy, distance-only gain", {"turn_radius": 0.0})):  # fmt: skip
        rows[name], com = greedy(body, rep, task, problem.radius, **cfg)
        print(_row(name, rows[name]), flush=True)
        if name == "greedy":
            paths[name] = com
    curves: dict[str, list] = {"SA": [], "GA": []}
    for method, label in (("anneal", "SA"), ("ga", "GA")):
        for seed in (int(s) for s in args.seeds.split(",")):
            res = search(problem, method, args.budget, seed)
            row = dict(res.scores) | {"wall_s": res.wall, "plan": res.summary()["plan"]}
            print(f"  worst roll {res.scores['roll']:.0f} deg, depth {res.scores['depth']:.2f} m")
            rows[f"{label} seed {seed}"] = row
            curves[label].append(tuple(np.array(res.history).T))
            print(_row(f"{label} seed {seed}", row, res.evaluations), flush=True)
            best = min((r for k, r in rows.items() if k.startswith(label)), key=lambda r: r["cost"])
            if best is row:
                traj = problem.rollout(res.entries, res.durations, record_every=4)
                paths[f"{label} (best seed)"] = traj.com(body)[0]
    marks = [m for m in (100, 250, 500, 1000, 2000, 4000) if m <= args.budget]
    progress = {}
    for label in ("SA", "GA"):
        costs = [r["cost"] for k, r in rows.items() if k.startswith(label)]
        at = [np.mean([f[np.searchsorted(n, m)] for n, f in curves[label]]) for m in marks]
        progress[label] = dict(zip(map(str, marks), np.round(at, 3).tolist(), strict=True))
        print(f"{label}: E mean {np.mean(costs):.3f}, best {np.min(costs):.3f}, "
              f"worst {np.max(costs):.3f} over {len(costs)} seeds; mean best E after "
              f"{progress[label]} evaluations")  # fmt: skip
    figure(paths, curves, OUT / f"macro_vs_greedy{tag}.png")
    clean = {k: {kk: (None if isinstance(v, float) and not np.isfinite(v) else v)
                 for kk, v in r.items()} for k, r in rows.items()}  # fmt: skip
    report |= {"task": {"goal": GOAL, "obstacle": OBSTACLE, "horizon_s": HORIZON,
                        "budget": args.budget}, "results": clean,
               "mean_best_E_after": progress}  # fmt: skip
    write_json(OUT / f"macro_vs_greedy{tag}.json", report)
    print(f"wrote {OUT}/fig5_tracking{tag}.png, macro_vs_greedy{tag}.png and .json")


if __name__ == "__main__":
    main()
