"""Plate 5 / Fig. 11: the dolphin's stunts, each discovered by simulated annealing over plans
of its repertoire entries, with the defaults of ``zoetic stunt``.

Trains (or reuses) the dolphin's basic repertoire, discovers every built-in trick, and prints
a Markdown table: apex of the centre of mass above the surface (m and body lengths), time
wholly out of the water, rotation in the air, ball contact (which body part), hurdle
clearance, splash measure, how deep it dived before the apex (the paper's finding: dive deep,
then thrust upward), the plan (entries and durations), plan evaluations, wall time and the
issue's targets met; then the bellyflop / clean-dive splash ratio. Writes the table, each
trick's summary.json and a strip of four frames per trick (like Plate 5 (a)-(d)) into --out.
About ten minutes on 2 idle cores (a minute or so a trick, plus the frames):
    python experiments/plate5_stunts.py [--memory DIR] [--budget 9600] [--seed 0]
        [--tricks leap,somersault]

The repertoire defaults to the one ``zoetic bench stunts`` trains and keys by the body and its
training tasks (runs/bench/dolphin-memory-<digest>), trained here if missing; the budget to
``zoetic stunt``'s (``behavior.stunts.BUDGET``), so the table and the bench line agree.

``--seeds 0-4`` (or ``0,2,4``) prints instead a table of successes per trick over those seeds
(no frames): each seed's targets met, how many of the six perturbed starts its plan still
meets them from (the trick's jitter, one at a time, each way), the plans searched (fewer
than the budget's where a ``stop_when_met`` trick met its targets from every start), the
wall time of each search and the median CPU time per search:
    python experiments/plate5_stunts.py --seeds 0-4 [--tricks somersault,leap]

``--launch SPEED`` starts every trick from a launch instead of its own start (SPEED m/s along
a body pitched ``--launch-pitch`` rad nose up, ``--launch-depth`` m down): a check of the
whole pipeline (terms, search, records, video) on a body that flies whatever its strength.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.stunts import (
    BUDGET,
    SPLASH_RATIO,
    discover,
    list_tricks,
    load_trick,
    parse_trick,
    splash_ratio,
    targets_met,
)
from zoetic.behavior.training import plan_digest, train_repertoire
from zoetic.bodies import load_animal
from zoetic.io import atomic_write_bytes, make_dir, read_toml, write_json
from zoetic.viz.stunts import frame_strip, stunt_frames


def strip_times(times: np.ndarray, com_y: np.ndarray, level: float) -> list[float]:
    """Four instants like Plate 5: leaving the water, the apex, re-entry, just after it (for a
    stunt still in the air at the end: leaving, rising, the apex, the end; for one that never
    leaves the water, four evenly spaced instants)."""
    above = com_y > level
    if not above.any():
        return list(np.linspace(times[0], times[-1], 4))
    i_apex = int(np.argmax(com_y))
    out_idx = np.flatnonzero(above[: i_apex + 1])
    back = np.flatnonzero(~above[i_apex:])
    i_exit = int(out_idx[0])
    i_in = i_apex + int(back[0]) if back.size else len(times) - 1
    i_after = min(len(times) - 1, i_in + int(round(0.3 / (times[1] - times[0]))))
    picks = [i_exit, i_apex, i_in, i_after]
    if not back.size:  # still in the air at the end: leaving, rising, the apex, the end
        picks = [i_exit, (i_exit + i_apex) // 2, i_apex, len(times) - 1]
    if len(set(picks)) < 4:  # it only broke the surface at the very end: spread them
        return list(np.linspace(times[0], times[-1], 4))
    return [float(times[i]) for i in picks]


def parse_seeds(text: str) -> list[int]:
    """Return the seeds of "0-4" or "0,2,4"."""
    if "-" in text:
        a, b = text.split("-", 1)
        return list(range(int(a), int(b) + 1))
    return [int(t) for t in text.split(",") if t.strip()]


def seed_table(body, rep, names: list[str], seeds: list[int], args) -> str:
    """Discover each trick from each seed; return a Markdown table of successes per trick."""
    rows = [
        f"| trick | seeds met (of {len(seeds)}) | per seed: targets met, perturbed starts met, "
        "plans searched (stopped: once met from every start), wall s | median CPU s a search |",
        "|---|---|---|---|",
    ]
    for name in names:
        trick = load_trick(name)
        cells, met, cpu = [], 0, []
        for seed in seeds:
            t0 = time.process_time()
            found = discover(body, rep, trick, args.method, args.budget, seed)
            cpu.append(time.process_time() - t0)
            s = found.summary()
            flags = targets_met(name, s, trick)
            ok = all(flags.values())
            write_json(args.out / name / f"seed{seed}.json", s | {"targets": flags})
            met += ok
            stopped = " stopped" if s.get("stopped_when_met") else ""
            cells.append(
                f"{seed}: {'yes' if ok else 'no'} "
                f"{s['perturbed_starts_met']}/{s['perturbed_starts']}, "
                f"{s['evaluations']} plans{stopped}, {s['wall_s']:.0f} s"
            )
        rows.append(f"| {name} | {met} | {'; '.join(cells)} | {np.median(cpu):.0f} |")
        print(rows[-1], flush=True)
    return "\n".join(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--memory",
        type=Path,
        default=None,
        help="default: runs/bench/dolphin-memory-<digest>, as zoetic bench stunts",
    )
    ap.add_argument("--out", type=Path, default=Path("runs/plate5"))
    ap.add_argument("--budget", type=int, default=BUDGET)
    ap.add_argument("--tricks", default=None, help="comma-separated (default: all built in)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--seeds",
        default=None,
        help="e.g. 0-4: a table of successes per trick over these seeds instead",
    )
    ap.add_argument("--method", default="anneal")
    ap.add_argument("--launch", type=float, default=None, help="start speed (m/s) for all")
    ap.add_argument("--launch-pitch", type=float, default=0.9)
    ap.add_argument("--launch-depth", type=float, default=0.8)
    ap.add_argument(
        "--train-budget",
        type=int,
        default=3000,
        help="evaluations per entry when the repertoire must be trained",
    )
    args = ap.parse_args()
    body = load_animal("dolphin")
    if args.memory is None:
        args.memory = Path("runs/bench") / f"{body.name}-memory-{plan_digest('dolphin')}"
    if not (args.memory / "repertoire.json").exists():
        t0 = time.perf_counter()
        train_repertoire("dolphin", args.memory, budget=args.train_budget, seed=args.seed)
        print(f"trained the repertoire in {time.perf_counter() - t0:.0f} s")
    rep = Repertoire.load(args.memory, body)
    make_dir(args.out)
    names = (
        list_tricks()
        if args.tricks is None
        else [t.strip() for t in args.tricks.split(",") if t.strip()]
    )
    if args.seeds is not None:
        table = seed_table(body, rep, names, parse_seeds(args.seeds), args)
        atomic_write_bytes(args.out / "seeds.md", (table + "\n").encode())
        print(f"\n{table}\n\nwrote {args.out}/seeds.md")
        return
    rows = [
        "| trick | apex m (body lengths) | s out of water | rotation in air deg (about the "
        "left-right axis) | ball contact (part) | striker -> ball m/s | hurdle clearance m "
        "| splash m^3/s | deepest before apex m | plan (entry s) | evaluations | wall s "
        "| targets met |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    summaries = {}
    for name in names:
        trick = load_trick(name)
        if args.launch is not None:
            doc = read_toml(trick.task.source, what="trick file")
            doc["start"] = doc.get("start", {}) | {
                "depth": args.launch_depth,
                "pitch": args.launch_pitch,
                "speed": args.launch,
            }
            trick = parse_trick(doc, trick.task.source)
        found = discover(body, rep, trick, args.method, args.budget, args.seed)
        s = found.summary()
        flags = targets_met(name, s, trick)
        summaries[name] = s | {"targets": flags}
        write_json(args.out / name / "summary.json", summaries[name])
        plan = ", ".join(f"{p['entry']} {p['duration_s']:.2f}" for p in s["plan"] if p["played"])
        ball = (
            "-"
            if "ball_contact" not in s
            else (
                s["ball_contact"] + (f" ({', '.join(s['ball_parts'])})" if s["ball_parts"] else "")
            )
        )
        speeds = (
            "-"
            if "ball_speed_m_s" not in s
            else f"{s['striker_speed_m_s']:.1f} -> {s['ball_speed_m_s']:.1f}"
        )
        hurdle = (
            "-"
            if "hurdle_clearance_m" not in s
            else (
                f"{s['hurdle_clearance_m']:.2f}" + (" touched" if s.get("hurdle_touched") else "")
            )
        )
        met = (
            "-" if not flags else ", ".join(f"{k} {'yes' if v else 'no'}" for k, v in flags.items())
        )
        if s["perturbed_starts"]:
            met += f"; perturbed starts {s['perturbed_starts_met']}/{s['perturbed_starts']}"
        rows.append(
            f"| {name} | {s['apex_above_surface_m']:.2f} ({s['apex_body_lengths']:.2f}) "
            f"| {s['air_time_s']:.2f} | {s['rotation_in_air_deg']:.0f} "
            f"({s['pitch_rotation_in_air_deg']:.0f}) | {ball} | {speeds} | {hurdle} "
            f"| {s['splash_m3_s']:.3f} | {s['deepest_before_apex_m']:.2f} | {plan} "
            f"| {s['evaluations']} | {s['wall_s']:.0f} | {met} |"
        )
        rec = found.record
        com_y = rec.traj.com(body)[0, :, 1]
        pick = [int(np.argmin(np.abs(rec.traj.times - t)))
                for t in strip_times(rec.traj.times, com_y, found.problem.level)]  # fmt: skip
        frames = list(stunt_frames(body, rec.traj.positions[0][pick], rec.traj.times[pick],
                                   body.medium, trick.objects, rec.balls[0][pick],
                                   size=(480, 270), title=name))  # fmt: skip
        labels = [f"({c}) t = {rec.traj.times[i]:.2f} s" for c, i in zip("abcd", pick, strict=True)]
        frame_strip(frames, args.out / name / "strip.png", labels)
        print(rows[-1], flush=True)
    table = "\n".join(rows)
    if {"bellyflop", "clean-dive"} <= set(summaries):
        r = splash_ratio(summaries["bellyflop"], summaries["clean-dive"])
        met = "met" if r is not None and r >= SPLASH_RATIO else "not met"
        table += "\n\nbellyflop / clean-dive splash: " + (
            "no ratio (not both left the water and re-entered)"
            if r is None
            else f"{r:.2f} (target >= {SPLASH_RATIO:g}, {met})"
        )
    atomic_write_bytes(args.out / "table.md", (table + "\n").encode())
    print()
    print(table)
    print(f"\nwrote {args.out}/ (table.md; per trick summary.json and strip.png)")


if __name__ == "__main__":
    main()
