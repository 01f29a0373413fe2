"""``zoetic stunt``: discover a macro controller for a trick (leap, hurdle, somersault, ...)."""

from __future__ import annotations

from pathlib import Path

import typer

from zoetic.cli.apps import app
from zoetic.cli.bench import bench_app, capped, quick_memory
from zoetic.cli.options import (
    Animal,
    Evaluator,
    Force,
    Fps,
    Json,
    Memory,
    Method,
    Quick,
    RayAddress,
    RunDir,
    Seed,
    use_ray_address,
)
from zoetic.cli.output import Countdown, console, emit
from zoetic.cli.track import track_bar


def write_replay(body, path: Path, seconds: float | None, out: Path, video: bool, fps: int) -> dict:
    """Replay a stunt's macro.json; write record.npz (and video.mp4) into out."""
    from zoetic.behavior.stunts import load_macro, replay
    from zoetic.cli.records import solid_things, write_sequence_record
    from zoetic.io import make_dir

    traj, balls = replay(body, path, seconds)
    ctrl, info = load_macro(path, body)
    make_dir(out)
    things = solid_things(info["objects"], traj.times, balls)
    record = write_sequence_record(
        out, "stunt", body, traj.times, traj.positions[0], ctrl, things, splash=True
    )
    com = traj.com(body)[0]
    files = {"record": str(record)}
    if video:
        from zoetic.viz.stunts import render_stunt_video

        files["video"] = str(
            render_stunt_video(
                body,
                traj.positions[0],
                traj.times,
                body.medium,
                out / "video.mp4",
                info["objects"],
                balls,
                fps=fps,
                macro=path,
            )
        )
    return {
        "animal": body.name,
        "seconds": round(float(traj.times[-1]), 3),
        "apex_y_m": round(float(com[:, 1].max()), 3),
        **files,
    }


@app.command()
def stunt(
    animal: Animal,
    memory: Memory,
    trick: str = typer.Option(
        "leap",
        help="A built-in trick (leap, hurdle, somersault, spin, "
        "ball-nose, ball-tail, bellyflop, clean-dive) or a trick .toml "
        "file.",
    ),
    method: Method = "anneal",
    budget: int = typer.Option(
        None,
        min=1,
        max=10_000_000,
        help="Stunt simulations to run (default 9600: as many plans, or a third as many "
        "for a robust trick, each played from 3 starts; the time is said early).",
    ),
    seed: Seed = 0,
    segments: int = typer.Option(None, min=1, help="Entries in a plan (default: the trick's)."),
    out: RunDir = Path("runs/stunt"),
    video: bool = typer.Option(True, help="Write video.mp4 (objects drawn as buoys)."),
    fps: Fps = 30,
    evaluator: Evaluator = "batch",
    ray_address: RayAddress = None,
    force: Force = False,
) -> None:
    """Discover a stunt: a macro controller of repertoire entries that scores the trick's style
    terms best; writes macro.json (replay: zoetic simulate ANIMAL --controller macro.json),
    video.mp4, score.png, record.npz and summary.json."""
    use_ray_address(ray_address)
    from zoetic.behavior.repertoire import Repertoire
    from zoetic.behavior.stunt_problem import starts_per_plan
    from zoetic.behavior.stunts import BUDGET, discover, load_trick
    from zoetic.bodies import load_animal
    from zoetic.outdir import prepare_out

    prepare_out(out, force)
    tr = load_trick(trick)
    body = load_animal(animal)
    rep = Repertoire.load(memory, body)
    budget = budget or BUDGET
    k = starts_per_plan(tr)
    plans = max(1, budget // k)
    starts = f" from {k} starts (the worst counts)" if k > 1 else ""
    console.print(
        f"{body.name} {tr.name}: {plans} plans by {method}, each a {tr.task.horizon:g} s "
        f"simulation{starts}; the time it takes here is printed after the first steps "
        "(--budget sets the simulations)"
        + (
            "; it stops early once a plan meets the targets from every moved start"
            if tr.stop_when_met
            else ""
        )
    )
    countdown = Countdown(plans, "plans")
    with track_bar("plans") as bar:
        tid = bar.add_task(f"{body.name} {tr.name} ({method})", total=plans, info="")

        def update(opt) -> None:
            bar.update(tid, completed=min(opt.evaluations, plans), info=f"E {opt.best_f:.3f}")
            countdown(opt.evaluations, bar.console)

        found = discover(
            body, rep, tr, method, budget, seed, segments, progress=update, evaluator=evaluator
        )
    summary = _write_stunt(out, body, tr, found, memory, seed)
    _draw_stunt(out, body, tr, found, summary, video, fps)
    _report(tr.name, method, found.result, summary, found.measures, out, video)


def _write_stunt(out: Path, body, tr, found, memory: Path, seed: int) -> dict:
    """Write a discovered stunt's macro.json, summary.json and record; return its summary."""
    from zoetic.behavior.stunts import macro_document, targets_met
    from zoetic.cli.records import figures, solid_things, write_sequence_record
    from zoetic.io import make_dir, write_json

    problem, result, rec = found.problem, found.result, found.record
    make_dir(out)
    write_json(out / "macro.json", macro_document(problem, result.sequence, tr.task.source))
    summary = found.summary()
    summary |= {
        "targets": targets_met(tr.name, summary, tr),
        "memory": str(memory),
        "seed": seed,
        "history": [[n, round(f, 5)] for n, f in result.history],
    }
    write_json(out / "summary.json", summary)
    times = rec.traj.times
    write_sequence_record(
        out,
        "stunt",
        body,
        times,
        rec.traj.positions[0],
        result.sequence,
        solid_things(tr.objects, times, rec.balls[0]),
        figures(summary),
        splash=True,
    )
    return summary


def _draw_stunt(out: Path, body, tr, found, summary: dict, video: bool, fps: int) -> None:
    """Write a discovered stunt's score.png (its style terms over time) and video.mp4."""
    from zoetic.behavior.stunts import score_series
    from zoetic.viz.stunts import plot_score

    rec, got, seconds = found.record, found.measures, summary["seconds"]
    starts = found.result.sequence.starts()
    plot_score(
        rec.traj.times,
        score_series(found.problem, rec),
        out / "score.png",
        starts[starts < seconds],
        title=f"{body.name} {tr.name}: E = {summary['E']:.3f}, apex "
        f"{got['apex_above_surface_m']:.2f} m, {got['air_time_s']:.2f} s in air, "
        f"{got['rotation_in_air_deg']:.0f} deg in air",
    )
    if video:
        from zoetic.viz.stunts import render_stunt_video

        render_stunt_video(
            body,
            rec.traj.positions[0],
            rec.traj.times,
            body.medium,
            out / "video.mp4",
            tr.objects,
            rec.balls[0],
            fps=fps,
            macro=out / "macro.json",
            title=f"{body.name} {tr.name}",
        )


def _report(
    name: str, method: str, result, summary: dict, got: dict, out: Path, video: bool
) -> None:
    """Print what a discovered stunt achieved and what was written."""
    stopped = ", stopped once met from every start" if result.stopped else ""
    console.print(
        f"{name} ({method}, {result.evaluations} plans{stopped}, {result.wall:.1f} s): "
        f"E = {summary['E']:.4f}; apex {got['apex_above_surface_m']:.3f} m above the surface "
        f"({got['apex_body_lengths']:.2f} body lengths), {got['air_time_s']:.2f} s wholly in "
        f"the air, {got['rotation_in_air_deg']:.0f} deg rotation in the air "
        f"({got['pitch_rotation_in_air_deg']:.0f} about the left-right axis, "
        f"{got['roll_rotation_in_air_deg']:.0f} about the long axis), "
        f"{got['contacts']} contacts, splash {got['splash_m3_s']:.3f} m^3/s"
    )
    if "ball_contact" in got:
        console.print(
            f"ball contact: {got['ball_contact']}"
            + (f" ({', '.join(got['ball_parts'])})" if got["ball_parts"] else "")
        )
    if "hurdle_clearance_m" in got:
        console.print(
            f"hurdle: clearance {got['hurdle_clearance_m']:.3f} m, "
            f"{'over' if got['bar_crossed'] else 'not over'} the bar, "
            f"{'touched' if got.get('hurdle_touched') else 'not touched'}"
        )
    if summary["perturbed_starts"]:
        j = summary["jitter"]
        console.print(
            f"targets met from {summary['perturbed_starts_met']} of "
            f"{summary['perturbed_starts']} perturbed starts (start {j['depth']:g} m deeper or "
            f"shallower, turned {j['heading']:g} deg, pitched {j['pitch']:g} deg; one at a time)"
        )
    played = [f"{p['entry']} {p['duration_s']:.2f} s" for p in summary["plan"] if p["played"]]
    console.print("plan: " + ", ".join(played))
    console.print(
        f"wrote {out}/ (macro.json, summary.json, record.npz, score.png"
        f"{', video.mp4' if video else ''})"
    )


@bench_app.command("stunts")
def bench_stunts_cmd(
    memory: Path = typer.Option(
        None,
        help="The dolphin's repertoire (zoetic repertoire train); "
        "default: trained once into runs/bench/dolphin-memory-<digest>, "
        "keyed by the body and its training tasks.",
    ),
    animal: str = typer.Option("dolphin"),
    tricks: str = typer.Option(
        "leap,somersault,spin,hurdle,ball-nose,ball-tail,bellyflop,clean-dive",
        help="Comma-separated tricks.",
    ),
    method: str = typer.Option("anneal"),
    budget: int = typer.Option(
        None, min=1, help="Stunt simulations per trick (default: as zoetic stunt)."
    ),
    seed: int = typer.Option(0),
    json: Json = False,
    quick: Quick = False,
) -> None:
    """Each trick discovered: its success flags against the issue's targets, what it achieved,
    evaluations and wall time (target: each trick in <= 15 s on an idle 2-core machine).
    --quick: the first trick only, 100 plans, a repertoire trained with a small budget."""
    from zoetic.behavior.stunts import BUDGET
    from zoetic.bench.stunts import bench_stunts

    names = [t.strip() for t in tricks.split(",") if t.strip()]
    if quick and memory is None:
        memory = quick_memory(animal)
    out = bench_stunts(
        animal,
        memory,
        names[:1] if quick else names,
        method,
        capped(quick, budget or BUDGET, 100),
        seed,
    )
    emit(out, json)
