"""``zoetic abstract``, ``zoetic repertoire train|show`` and ``zoetic sequence`` (``repertoire
blend``: cli.blend)."""

from __future__ import annotations

import json
from functools import partial
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from zoetic.cli.apps import app
from zoetic.cli.learn import learn_bar
from zoetic.cli.options import Force, Righting, given, use_ray_address
from zoetic.cli.output import console, interrupted, print_summary

Strict = Annotated[
    bool,
    typer.Option(
        "--strict", help="Exit with status 1 if any entry does not do what its task promises."
    ),
]

repertoire_app = typer.Typer(
    help="Basic training: learn, abstract and keep a repertoire.", no_args_is_help=True
)
app.add_typer(repertoire_app, name="repertoire")


@app.command("abstract")
def abstract_cmd(
    source: Path = typer.Argument(..., help="Learning run directory or controller .json file."),
    modes: str = typer.Option("auto", help="auto (threshold) or K, the strongest modes kept."),
    threshold: float = typer.Option(0.3, help="auto keeps modes >= threshold x the strongest."),
    task: str = typer.Option(None, help="Task to compare on (default: the run's own task)."),
    out: Path = typer.Option(None, help="Where abstract.json/.png go (default: SOURCE's dir)."),
) -> None:
    """Abstract a learned controller into its primary modes (FFT) and say what it keeps."""
    from zoetic.learning.abstraction import parse_modes
    from zoetic.viz.media import abstract_files

    if source.is_dir():
        from zoetic.runs import check_run_dir

        check_run_dir(source)
    out = out or (source if source.is_dir() else source.parent)
    info = abstract_files(source, out, parse_modes(modes), threshold, task)
    o, a = info["original"], info["abstract"]
    m = info["measure"]
    console.print(
        f"modes per actuator: {info['modes_per_actuator']} ({info['rule']}), "
        f"frequencies {info['frequencies_hz']} Hz"
    )
    console.print(f"{m}: original {o[m]:.4g}, abstracted {a[m]:.4g} -> kept {info['kept']:.1%}")
    if "E" in o:
        console.print(f"E: original {o['E']:.4g}, abstracted {a['E']:.4g}")
    console.print(f"wrote {info['file']} and {info['figure']}")


@repertoire_app.command("train")
def train_cmd(
    ctx: typer.Context,
    animal: str = typer.Argument(..., help="Zoo animal name or animal .toml file."),
    out: Path = typer.Option(None, help="Repertoire directory (default memory/<animal>)."),
    budget: int = typer.Option(3000, min=10, max=10_000_000, help="Evaluations per learned entry."),
    pipeline: str = typer.Option(
        "periodic",
        help="periodic (a constant and two stroke harmonics per actuator, CMA-ES) or paper "
        "(the 1995 paper's: a time-domain controller from scratch, abstracted by FFT).",
    ),
    optimizer: str = typer.Option(
        None, help="anneal, simplex or cmaes (default: cmaes; --pipeline paper: anneal)."
    ),
    modes: str = typer.Option("auto", help="Modes kept by the abstraction: auto or K."),
    threshold: float = typer.Option(0.3, help="auto keeps modes >= threshold x the strongest."),
    nodes: int = typer.Option(
        None, min=2, help="Controller nodes per actuator (task's; --pipeline paper: 4 a stroke)."
    ),
    seed: int = typer.Option(0, help="Random seed: same seed, same repertoire."),
    evaluator: str = typer.Option("batch", help="batch, process or ray (see zoetic learn)."),
    ray_address: str = typer.Option(None, help="Ray cluster for --evaluator ray."),
    strict: Strict = False,
    resume: bool = typer.Option(
        False, "--resume", help="Continue the repertoire in --out (a new --budget is taken)."
    ),
    speeds: bool = typer.Option(
        False,
        "--speeds",
        help="A swimmer learns slow and medium straight swims too (for repertoire blend).",
    ),
    radii: bool = typer.Option(
        False,
        "--radii",
        help="A swimmer learns a turn of medium radius too (for repertoire blend --radius).",
    ),
    force: Force = False,
) -> None:
    """Learn the basic repertoire (straight, sharp and wide turns, mirrored; a fish's swim-up
    and swim-down; with --speeds, swims at steady slower speeds; with --radii, a medium turn);
    resumable. Each entry is judged against its task's promises. --pipeline paper learns each
    entry the 1995 paper's way (time domain, annealing or simplex, FFT abstraction)."""
    from zoetic.viz.drawer import Drawer

    with Drawer() as drawer:  # repertoire.png's process: it imports matplotlib meanwhile
        use_ray_address(ray_address)
        from zoetic.behavior.pipelines import check_training
        from zoetic.behavior.training import train_repertoire
        from zoetic.learning.abstraction import parse_modes
        from zoetic.runs import check_learnable

        check_training(pipeline, optimizer, threshold)
        modes = parse_modes(modes)
        check_learnable(animal)
        flags = ["--speeds"] * speeds + ["--radii"] * radii
        flags += ["--pipeline", pipeline] * (pipeline != "periodic")
        out, again = _training_dir(animal, out, resume, force, flags)
        with learn_bar() as bar:
            on_entry, progress = _entry_lines(bar)
            try:
                train_repertoire(
                    animal,
                    out,
                    budget,
                    seed,
                    optimizer,
                    modes,
                    threshold,
                    nodes,
                    on_entry,
                    progress,
                    evaluator,
                    budget if resume and given(ctx, "budget") else None,
                    speeds,
                    radii,
                    pipeline,
                )
            except KeyboardInterrupt:
                interrupted(f"{out} keeps what was learned; continue with: {again}")
        _report_trained(out, strict, drawer)


def _report_trained(out: Path, strict: bool, drawer) -> None:
    """Print a trained repertoire's entries, the ones learned again and the promises each
    keeps (``--strict``: exit 1 when one does not); repertoire.png is drawn by ``drawer``
    (a ``Drawer``) meanwhile."""
    from functools import partial

    from zoetic.behavior.promises import PromiseError
    from zoetic.learning.blas import one_blas_thread
    from zoetic.viz.media import show_repertoire

    with one_blas_thread():  # the entries replayed and judged: small linear algebra
        rows = show_repertoire(out, draw=partial(drawer.draw, "plot_repertoire"))
        try:
            _print_rows(rows, f"{out}")
            _report_restarts(out)
            _report_promises(out, strict)
        except PromiseError:
            drawer.wait()  # repertoire.png written, whatever the verdicts (--strict's exit)
            raise
        except BaseException:
            drawer.close()  # Ctrl-C or a failure: its report, without waiting for the figure
            raise
        drawer.wait()


def _entry_lines(bar):
    """Return the callbacks that give each repertoire entry its own line of the learning bar
    (``learn_bar``): on_entry(name, run) as an entry starts, progress(run) as it learns."""
    lines: dict = {}

    def on_entry(name: str, run) -> None:
        lines[id(run)] = bar.add_task(
            name,
            total=run.setup.config.budget,
            completed=run.evaluations,
            best="-",
            status="",
            rate="-",
        )

    def progress(run) -> None:
        bar.update(
            lines[id(run)], completed=run.evaluations, best=f"{run.setup.optimizer.best_f:.4g}"
        )

    return on_entry, progress


def _training_dir(
    animal: str,
    out: Path | None,
    resume: bool,
    force: bool,
    flags: list[str] = (),
) -> tuple[Path, str]:
    """Return the repertoire directory ready for training (a new or empty one, an emptied one
    under ``force``, or the one to continue under ``resume``) and the command that continues
    it; a non-empty directory without either is refused, naming both."""
    import shlex

    from zoetic.behavior.repertoire import INDEX
    from zoetic.errors import ZoeticError
    from zoetic.outdir import check_out_dir, prepare_out

    out = check_out_dir(out or Path("memory") / Path(animal).stem)
    again = ["zoetic", "repertoire", "train", animal, "--out", str(out), "--resume"]
    again = shlex.join(again + list(flags))
    if resume and force:
        raise ZoeticError(
            "--resume continues the repertoire in --out, --force replaces it: not both"
        )
    if not resume:
        return prepare_out(out, force, again), again
    if not (out / INDEX).is_file():
        raise ZoeticError(f"{out}: holds no {INDEX}, so no repertoire to continue; drop --resume")
    return out, again


def _report_restarts(memory: Path) -> None:
    """Print, for each entry learned again because it broke a promise (``behavior.restarts``),
    why, each try's run and seed and what it broke, and which try the repertoire keeps."""
    from zoetic.behavior.repertoire import Repertoire

    for name, info in Repertoire.load(memory).info.items():
        r = info.get("restarts")
        if not isinstance(r, dict):
            continue
        if "skipped" in r:
            console.print(f"{name}: not learned again ({r['skipped']}): {r['because']}")
            continue
        console.print(f"{name}: learned again: {r['because']}")
        for t in r["tries"]:
            broke = "keeps every promise" if t["met"] else "breaks " + "; ".join(t["broken"])
            console.print(f"  {t['run']} (seed {t['seed']}): {broke}")
        console.print(f"  kept: {r['kept']}")


def _report_promises(memory: Path, strict: bool) -> dict[str, dict]:
    """Judge every learned entry against its task's promises; print the ones it does not
    keep (and exit 1 under ``strict`` if any); return the verdicts by entry."""
    from zoetic.behavior.promises import check_promises, unmet_text
    from zoetic.behavior.repertoire import Repertoire
    from zoetic.behavior.training import judge_repertoire
    from zoetic.runs import repertoire_body

    animal = Repertoire.load(memory).animal
    verdicts = judge_repertoire(memory, repertoire_body(memory, animal))
    unmet = [n for n, v in verdicts.items() if not v["met"] and "mirror_of" not in v]
    for name in unmet:
        mirror = [m for m, v in verdicts.items() if v.get("mirror_of") == name]
        also = f" (nor does its mirror {', '.join(mirror)})" if mirror else ""
        console.print(f"[yellow]warning: {unmet_text(name, verdicts[name])}{also}[/]")
    if verdicts and not unmet:
        console.print(f"every learned entry keeps its task's promises ({len(verdicts)} judged)")
    if strict:
        check_promises(verdicts, str(memory))
    return verdicts


def _hz(freqs: list[float], most: int = 3) -> str:
    text = ", ".join(f"{f:g}" for f in freqs[:most])
    return text + (f" (+{len(freqs) - most})" if len(freqs) > most else "")


def _print_rows(rows: list[dict], title: str) -> None:
    table = Table(title=title)
    for col in ("entry", "seconds", "modes", "Hz (strongest)", "forward m", "turn deg", "source"):
        table.add_column(col, no_wrap=col == "entry")
    for r in rows:
        table.add_row(
            r["entry"],
            f"{r['seconds']:g}",
            str(r["modes"]),
            _hz(r["frequencies_hz"]),
            f"{r['forward_m']:.3f}",
            f"{r['turn_deg']:.1f}",
            str(r["source"]),
        )
    console.print(table)


@repertoire_app.command("show")
def show_cmd(
    memory: Path = typer.Argument(..., help="Repertoire directory."),
    json_out: bool = typer.Option(False, "--json", help="Print the rows as JSON."),
    strict: Strict = False,
) -> None:
    """Print a repertoire's entries and what each does; writes repertoire.png beside them.
    Each learned entry is judged against its task's promises (from every start of the task)."""
    from zoetic.behavior.promises import check_promises
    from zoetic.behavior.training import judge_repertoire
    from zoetic.errors import ZoeticError, naming
    from zoetic.runs import repertoire_body
    from zoetic.viz.media import show_repertoire

    try:
        rows = show_repertoire(memory)
    except ZoeticError as exc:  # e.g. the index names an unknown animal
        raise naming(memory, exc) from None
    if json_out:
        from zoetic.behavior.repertoire import Repertoire

        body = repertoire_body(memory, Repertoire.load(memory).animal)
        verdicts = judge_repertoire(memory, body)
        for r in rows:
            r["promise"] = verdicts.get(r["entry"])
        print(json.dumps(rows, indent=1))
        if strict:
            check_promises(verdicts, str(memory))
        return
    _print_rows(rows, str(memory))
    console.print(f"plot: {memory / 'repertoire.png'}")
    _report_restarts(memory)
    _report_promises(memory, strict)


@app.command("sequence")
def sequence_cmd(
    animal: str = typer.Argument(..., help="Zoo animal name or animal .toml file."),
    memory: Path = typer.Option(..., help="Repertoire directory."),
    entries: str = typer.Option(..., help='Entries in order, "name:seconds,name,...".'),
    overlap: float = typer.Option(0.05, help="Fraction of each entry shared with the next."),
    out: Path = typer.Option(Path("runs/sequence"), help="Output directory."),
    righting: Righting = True,
    video: bool = typer.Option(True, help="Write video.mp4."),
    force: Force = False,
) -> None:
    """Concatenate repertoire entries, cross-faded, into one controller; simulate it. A fish
    keeps upright by its fins' righting reflex (--no-righting: the plan as given)."""
    import numpy as np

    from zoetic.behavior.repertoire import Repertoire
    from zoetic.behavior.training import build_sequence, parse_sequence
    from zoetic.bodies import load_animal
    from zoetic.cli.track import motion_line
    from zoetic.control import save_controller
    from zoetic.control.measure import locomotion
    from zoetic.io import make_dir
    from zoetic.outdir import prepare_out
    from zoetic.record import read_record
    from zoetic.runs import simulate_run
    from zoetic.viz.learning import plot_controller
    from zoetic.viz.media import simulation_media

    body = load_animal(animal)
    rep = Repertoire.load(memory, body)
    items = parse_sequence(entries, rep)
    seq = build_sequence(rep, items, overlap)
    make_dir(prepare_out(out, force))
    seq, note = _upright(body, [n for n, _ in items], seq, righting)
    path = save_controller(seq, out / "sequence.json")
    t = np.linspace(0.0, seq.duration, 600)
    title = f"sequence: {entries}" + (" (righting)" if note.startswith("a righting") else "")
    plot_controller(
        t, seq.sample(t), body.actuator_names, body.actuator_side, out / "controller.png", title
    )
    media = partial(simulation_media, video=video, starts=seq.starts()[1:], title=title)
    summary = simulate_run(animal, str(path), seq.duration, out, media=media)
    rec = read_record(summary["record"])
    motion = locomotion(body, np.asarray(rec.animals[0].positions, float), rec.times)
    print_summary(summary | {"sequence": str(path)})
    console.print(f"{'righting':>12}: {note}")
    console.print(f"{'locomotion':>12}: {motion_line(motion)}")


def _upright(body, names: list[str], seq, righting: bool):
    """Return the sequence to play (with the fins' righting reflex where asked for and the
    animal has fins to right itself with) and a note saying what the reflex did."""
    from zoetic.behavior.tracking import TrackConfig
    from zoetic.behavior.upright import has_righting, right_plan

    config = TrackConfig()
    if not righting:
        return seq, "off (--no-righting): the plan as given"
    if not has_righting(body, seq, config.fin_tilt):
        return seq, f"none: the {body.name} has no pectoral fins to right itself with"
    result = right_plan(body, names, seq, config=config)
    s = result.summary()
    return result.sequence, (
        f"a righting variant played in {s['windows_righted']} of {s['windows']} windows "
        f"of {config.interval:g} s ({s['windows_gentle']} with the gentler stroke)"
    )
