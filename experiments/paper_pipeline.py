"""The paper's pipeline against today's, side by side (Grzeszczuk & Terzopoulos 95, sections
3-4): per animal, a repertoire trained each way and the Fig. 5 course tracked with each.

"periodic" is ``zoetic repertoire train ANIMAL`` (a constant and two stroke harmonics per
actuator, CMA-ES, harmonics thresholded); "paper-T" is ``... --pipeline paper --threshold T``
(a time-domain controller learned from scratch by annealing or the simplex method, abstracted
by FFT at T; the controllers are learned once and abstracted at each of --thresholds). Every
entry is learned with the same budget and seed each way. For every learned entry: its task
score E (the learned and the abstracted controller's, as the task scores them from its first
start), whether the entry keeps its task's promises (``training.judge_repertoire``, every
start), the modes it keeps and what the abstraction keeps of the task's measure and, for the
paper pipeline, of the distance swum. Then greedy tracking (``zoetic track``'s
``behavior.tracking.track``) of the Fig. 5 course of ``macro_vs_greedy.py``: targets reached,
when, and the depth and roll on the way.

Writes paper_pipeline.json and paper_pipeline_ANIMAL.png (the tracking paths, top and
side view) under docs/figures (or $ZOETIC_FIGURES); the repertoires go to --memory/ANIMAL/PIPE.
Run: python experiments/paper_pipeline.py [--animals shark,shark-1995] [--budget 300]
     [--optimizer anneal] [--thresholds 0.3,1] [--time-limit 60] [--memory runs/paper_pipeline]
"""

from __future__ import annotations

import argparse
import shutil
import sys
import time
from pathlib import Path

import numpy as np

from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.tracking import TrackConfig, track
from zoetic.behavior.training import judge_repertoire, train_repertoire
from zoetic.bodies import load_animal
from zoetic.io import write_json
from zoetic.reproduce import figures_dir
from zoetic.viz.tracking import plot_plan

sys.path.insert(0, str(Path(__file__).resolve().parent))
from macro_vs_greedy import COURSE  # noqa: E402  (the Fig. 5 course, defined once there)

OUT = figures_dir()
PIPELINES = ("periodic", "paper")


def entry_rows(memory: Path, body) -> list[dict]:
    """Return one row per learned entry of the repertoire in ``memory`` (mirrors left out)."""
    rep = Repertoire.load(memory, body)
    verdicts = judge_repertoire(memory, body)
    rows = []
    for name in rep.names:
        info = rep.info[name]
        if "task" not in info:  # do-nothing and the mirrored right turns
            continue
        v = verdicts.get(name, {"met": None, "promises": []})
        rows.append(
            {
                "entry": name,
                "task": info["task"],
                "E_learned": info["original"].get("E"),
                "E_abstracted": info["abstract"].get("E"),
                "promise_met": v["met"],
                "unmet": [
                    f"{o['promise']} ({o['worst']:g})" for o in v["promises"] if not o["met"]
                ],
                "modes": int(np.sum(info["modes_per_actuator"])),
                "measure": info["measure"],
                "kept": info["kept"],
                "distance_kept": info.get("distance_kept"),
                "optimizer": info.get("optimizer", "cmaes"),
            }
        )
    return rows


def track_course(body, memory: Path, time_limit: float) -> tuple[dict, object]:
    """Track the Fig. 5 course with the repertoire; return its numbers and the result."""
    rep = Repertoire.load(memory, body)
    res = track(body, rep, COURSE, TrackConfig(time_limit=time_limit))
    s = res.summary()
    row = {k: s[k] for k in ("reached", "targets", "reach_times_s", "simulated_s", "controllers")}
    row |= {k: s[k] for k in ("depth_change_m", "depth_span_m", "worst_roll_deg", "wall_s")}
    return row, res


def train(animal: str, memory: Path, pipe: str, threshold: float, args) -> float:
    """Train one repertoire (skipped entries already learned there); return its CPU s."""
    t0 = time.process_time()
    paper = pipe != "periodic"
    train_repertoire(
        animal,
        memory,
        args.budget,
        args.seed,
        optimizer=args.optimizer if paper else None,
        threshold=threshold,
        pipeline="paper" if paper else "periodic",
    )
    return time.process_time() - t0


def one_animal(animal: str, args) -> dict:
    """Train both repertoires of one animal (the paper's learned once, abstracted at every
    threshold), tabulate their entries, track the course with each and write the figure."""
    body = load_animal(animal)
    out, paths, starts, labels = {}, [], [], []
    pipes = [("periodic", args.thresholds[0])]
    pipes += [(f"paper-{t:g}", t) for t in args.thresholds]
    for pipe, threshold in pipes:
        memory = args.memory / animal / pipe
        learned = args.memory / animal / pipes[1][0] / "runs"
        if pipe.startswith("paper") and pipe != pipes[1][0] and not (memory / "runs").exists():
            shutil.copytree(learned, memory / "runs")  # the same learned controllers
        cpu = train(animal, memory, pipe, threshold, args)
        rows = entry_rows(memory, body)
        course, res = track_course(body, memory, args.time_limit)
        out[pipe] = {"train_cpu_s": round(cpu, 1), "entries": rows, "fig5": course}
        paths.append(res.com)
        starts.append(res.start_indices)
        labels.append(f"{pipe}: {course['reached']}/{course['targets']}")
        print(f"{animal} {pipe}: trained in {cpu:.0f} s CPU; Fig. 5 course {course}", flush=True)
    plot_plan(
        paths,
        labels,
        OUT / f"paper_pipeline_{animal}.png",
        np.column_stack([COURSE[:, 0], np.zeros(len(COURSE)), COURSE[:, 1]]),
        np.zeros((0, 3)),
        starts,
        title=f"{animal}: Fig. 5 course, today's periodic entries vs the paper pipeline's "
        f"({args.optimizer}, budget {args.budget})",
        band=0.5,
    )
    return out


def table(report: dict) -> str:
    """Return the Markdown table of every animal's entries and tracking, both pipelines."""
    lines = [
        "| animal | pipeline | entry | E learned | E abstracted | modes | kept | promise |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for animal, pipes in report["animals"].items():
        for pipe, r in pipes.items():
            for e in r["entries"]:
                kept = f"{e['measure']} {e['kept']:.2f}"
                if e["distance_kept"] is not None:
                    kept += f", distance {e['distance_kept']:.2f}"
                ok = "kept" if e["promise_met"] else "broken: " + "; ".join(e["unmet"])
                lines.append(
                    f"| {animal} | {pipe} | {e['entry']} | {e['E_learned']:.3g} | "
                    f"{e['E_abstracted']:.3g} | {e['modes']} | {kept} | {ok} |"
                )
    lines += [
        "",
        "| animal | pipeline | targets reached | reached at (s) | simulated (s) | depth at end "
        "(m) | depth span (m) | worst roll (deg) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for animal, pipes in report["animals"].items():
        for pipe, r in pipes.items():
            c = r["fig5"]
            times = ", ".join("-" if t is None else f"{t:g}" for t in c["reach_times_s"])
            lo, hi = c["depth_span_m"]
            lines.append(
                f"| {animal} | {pipe} | {c['reached']}/{c['targets']} | {times} | "
                f"{c['simulated_s']:g} | {c['depth_change_m']:+.2f} | {lo:+.2f} to {hi:+.2f} | "
                f"{c['worst_roll_deg']:.0f} |"
            )
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--animals", default="shark,shark-1995")
    ap.add_argument("--budget", type=int, default=300, help="evaluations per learned entry")
    ap.add_argument("--optimizer", default="anneal", choices=("anneal", "simplex"))
    ap.add_argument(
        "--thresholds", default="0.3", help="the paper pipeline's abstraction thresholds"
    )
    ap.add_argument("--time-limit", type=float, default=60.0, help="tracking, simulated s")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--memory", type=Path, default=Path("runs/paper_pipeline"))
    args = ap.parse_args()
    args.thresholds = [float(t) for t in args.thresholds.split(",")]
    report = {
        "setup": {
            "budget": args.budget,
            "optimizer": args.optimizer,
            "thresholds": args.thresholds,
            "time_limit_s": args.time_limit,
            "seed": args.seed,
            "course": COURSE.tolist(),
        },
        "animals": {a: one_animal(a, args) for a in args.animals.split(",")},
    }
    write_json(OUT / "paper_pipeline.json", report)
    print(table(report))
    print(f"wrote {OUT}/paper_pipeline.json and paper_pipeline_ANIMAL.png")


if __name__ == "__main__":
    main()
