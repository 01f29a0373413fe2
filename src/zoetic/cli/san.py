"""``zoetic san ...``: sensor-actuator networks for planar creatures."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.progress import Progress

from zoetic.cli.apps import app
from zoetic.cli.bench import bench_app, capped
from zoetic.cli.options import (
    Force,
    Json,
    Quick,
    RayAddress,
    Seed,
    Terrain,
    Workers,
    use_ray_address,
)
from zoetic.cli.output import console, emit, print_summary, progress_bar
from zoetic.outdir import prepare_out

san_app = typer.Typer(
    help="Sensor-actuator networks (van de Panne & Fiume 93): search, tune, show.",
    no_args_is_help=True,
)
app.add_typer(san_app, name="san")


def _bar(label: str, total: int) -> tuple[Progress, object]:
    bar = progress_bar("best {task.fields[best]}")
    tid = bar.add_task(label, total=total, best="-")
    return bar, tid


def _progress(bar: Progress, tid, unit: str = ""):
    def update(done: int, total: int, best: float) -> None:
        bar.update(tid, completed=done, best=f"{best:.3f}{unit}")

    return update


def _record(out: Path, network: Path) -> str:
    """Write the run record of a SAN run (its best network replayed); return its path, or
    "" when the run kept no network."""
    from zoetic.cli.records import write_san_record

    return str(write_san_record(out, network)) if network.is_file() else ""


def _with_files(out: Path, summary: dict, files: dict) -> dict:
    """Return the run's summary with the pictures drawn for it, written to summary.json."""
    from zoetic.io import write_json

    summary = summary | files
    write_json(out / "summary.json", summary)
    return summary


def _check_seconds(creature, seconds: float | None) -> None:
    """Refuse --seconds that would take the creature's world past its step limit."""
    from zoetic.san.creature import CreatureError
    from zoetic.san.creature_file import MAX_CREATURE_STEPS

    if seconds is not None and seconds / creature.dt > MAX_CREATURE_STEPS:
        raise CreatureError(
            f"--seconds {seconds:g} at the {creature.name}'s dt = {creature.dt:g} s is "
            f"{seconds / creature.dt:,.0f} steps (at most {MAX_CREATURE_STEPS:,}); use less"
        )


@san_app.command("creatures")
def creatures_cmd() -> None:
    """List the built-in creatures with their sensors, actuators and the paper's speed."""
    from rich.table import Table

    from zoetic.san import list_creatures, load_creature
    from zoetic.san.network import default_hidden

    table = Table(box=None, header_style="bold")
    for col in (
        "creature",
        "links",
        "sensors",
        "actuators",
        "hidden",
        "metric",
        "seconds",
        "paper cm/s",
    ):
        table.add_column(col, justify="left" if col in ("creature", "metric") else "right")
    for name in list_creatures():
        c = load_creature(name)
        table.add_row(
            name,
            str(len(c.links)),
            str(c.n_sensors),
            str(c.n_actuators),
            str(default_hidden(c)),
            c.metric,
            f"{c.seconds:g}",
            "-" if c.paper_speed is None else f"{c.paper_speed:g}",
        )
    console.print(table)


@san_app.command("search")
def search_cmd(
    creature: str = typer.Argument(..., help="Built-in creature name or creature .toml file."),
    trials: int = typer.Option(
        200, min=1, max=10_000_000, help="Random networks to generate and evaluate."
    ),
    top: int = typer.Option(10, min=1, help="How many of the best to keep (videos and files)."),
    seed: int = typer.Option(0, help="Random seed: same seed, same networks and metrics."),
    terrain: Terrain = "flat",
    seconds: float = typer.Option(
        None, min=0.1, max=1000.0, help="Evaluation time (default: creature's)."
    ),
    workers: Workers = None,
    out: Path = typer.Option(None, help="Output directory (default runs/<creature>)."),
    video: bool = typer.Option(True, help="Write a video of each kept gait."),
    gaits: bool = typer.Option(
        False,
        "--gaits",
        help="Cluster the kept gaits into distinct "
        "modes: modes.json and one labelled clip per mode.",
    ),
    evaluator: str = typer.Option("process", help="process (this machine) or ray (a cluster)."),
    ray_address: RayAddress = None,
    force: Force = False,
) -> None:
    """Phase 1: random SANs, evaluated in parallel; keeps the best (sans/*.json, videos)."""
    use_ray_address(ray_address)
    from zoetic.san import load_creature
    from zoetic.san.search import search, write_search
    from zoetic.viz.san import draw_search

    c = load_creature(creature)
    _check_seconds(c, seconds)
    out = prepare_out(out or Path("runs") / c.name, force)
    bar, tid = _bar(f"{c.name} {terrain}", trials)
    with bar:
        result = search(
            c,
            trials=trials,
            top=top,
            seed=seed,
            terrain=terrain,
            workers=workers,
            progress=_progress(bar, tid),
            seconds=seconds,
            evaluator=evaluator,
        )
    with console.status(f"writing {out}" + (" (videos)" if video else "")):
        summary = write_search(result, out, top=top)
        summary = _with_files(out, summary, draw_search(result, out, top=top, video=video))
        summary["record"] = _record(out, out / "sans" / "01.json")
    print_summary(summary, 18)
    if gaits:
        _gaits(result, top, out, video, workers)


def _gaits(result, top: int, out: Path, video: bool, workers: int | None) -> None:
    """Cluster the search's kept gaits that did not fall into modes; print and write them."""
    from zoetic.san.gaits import write_modes
    from zoetic.viz.san import draw_modes

    kept = [i for i in result.top(top) if not result.fell[i]]
    info = [{"rank": r, "trial": i} for r, i in enumerate(result.top(top), 1) if i in kept]
    with console.status(f"sorting {len(kept)} gaits into modes" + (" (clips)" if video else "")):
        networks = [result.networks[i] for i in kept]
        where = {"seconds": result.seconds, "terrain": result.terrain, "seed": result.seed}
        doc = write_modes(result.creature, networks, info, out, video=video, **where)
        draw_modes(result.creature, networks, doc, workers=workers, **where)
    console.print(
        f"{'distinct modes':>18}: {doc['modes_found']} among {len(kept)} kept gaits "
        f"that did not fall (distance > {doc['threshold']:g} scaled units)"
    )
    for m in doc["modes"]:
        best = m["best"]
        console.print(
            f"{'mode ' + str(m['mode']):>18}: {m['label']} ({m['count']} networks, "
            f"best {best['speed_cm_s']:.1f} cm/s, rank {best['rank']})"
        )
    console.print(f"{'modes':>18}: {out / 'modes.json'}")


@san_app.command("evolve")
def evolve_cmd(
    creature: str = typer.Argument(
        None,
        help="Built-in creature name or creature .toml file "
        "(default with --network: the creature its file carries).",
    ),
    network: Path = typer.Option(
        None,
        help="Start from this network .json (default: the best "
        "of a phase-1 search of --search random networks).",
    ),
    search_trials: int = typer.Option(
        200,
        "--search",
        min=1,
        max=1_000_000,
        help="Random networks for the start (without --network).",
    ),
    trials: int = typer.Option(
        500, min=0, max=10_000_000, help="Evolution steps (one evaluation each)."
    ),
    seed: Seed = 0,
    terrain: Terrain = "flat",
    out: Path = typer.Option(None, help="Output directory (default runs/<creature>-evolve)."),
    video: bool = typer.Option(True, help="Write video.mp4 of the evolved creature."),
    resume: bool = typer.Option(
        False, "--resume", help="Continue from <out>/checkpoint.npz of the same run."
    ),
    workers: int = typer.Option(None, min=1, help="Worker processes for the start's search."),
    force: Force = False,
) -> None:
    """Evolve the body (link lengths, sections, attachment points; masses coupled to them and
    to actuator strength) together with the network's Fig. 8 parameters (paper, 6.3)."""
    from zoetic.san.evolve import evolve, load_checkpoint, save_checkpoint, write_evolve
    from zoetic.san.network import load_with_creature, save_network
    from zoetic.viz.san import draw_evolve

    net, c = _evolve_subject(creature, network, terrain)
    out = out or Path("runs") / f"{c.name}-evolve"
    if not resume:
        prepare_out(out, force, "--resume")
    ckpt = out / "checkpoint.npz"
    start_file = out / "start.json"
    history = None
    if resume and ckpt.exists() and start_file.exists():
        net = load_with_creature(start_file, c)[0]
    elif net is None:
        net = _start_network(c, search_trials, seed, terrain, workers)
    config = {
        "creature": c.name,
        "seed": seed,
        "trials": trials,
        "terrain": terrain,
        "network": net.to_dict(),
    }
    if resume and ckpt.exists():
        history = load_checkpoint(ckpt, config)
        console.print(f"resuming {ckpt} at step {int(history['done'])} of {trials}")
    save_network(net, start_file, c)
    bar, tid = _bar(f"{c.name} evolve", trials)
    with bar:
        result = evolve(
            net,
            c,
            trials=trials,
            seed=seed,
            terrain=terrain,
            progress=_progress(bar, tid),
            resume=history,
            checkpoint=lambda _t, _sa, h: save_checkpoint(ckpt, config, h),
        )
    with console.status(f"writing {out}" + (" (video)" if video else "")):
        summary = write_evolve(result, out, terrain=terrain)
        summary = _with_files(out, summary, draw_evolve(result, out, terrain, video))
        summary["record"] = _record(out, out / "san.json")
    _print_evolve(c.name, summary)


def _evolve_subject(creature: str | None, network: Path | None, terrain: str):
    """Return (the starting network or None, the creature) evolution works on, refusing an
    unknown terrain, a missing creature and a creature that cannot evolve."""
    from zoetic.san import load_creature
    from zoetic.san.creature import CreatureError
    from zoetic.san.evolve import check_evolvable
    from zoetic.san.network import load_with_creature
    from zoetic.san.search import TERRAINS

    if terrain not in TERRAINS:
        raise CreatureError(f"unknown terrain {terrain!r} (expected 'flat' or 'rough')")
    if creature is None and network is None:
        raise typer.BadParameter("give a CREATURE (or --network FILE, whose creature it is)")
    net = None
    if network is not None:
        net, c = load_with_creature(network, creature)
    else:
        c = load_creature(creature)
    check_evolvable(c)
    return net, c


def _start_network(c, trials: int, seed: int, terrain: str, workers: int | None):
    """Return the best of a phase-1 search of ``trials`` random networks (one that did not
    fall, when any), evolution's starting point."""
    from zoetic.san.search import search

    bar, tid = _bar(f"{c.name} start search", trials)
    with bar:
        res = search(
            c,
            trials=trials,
            seed=seed,
            terrain=terrain,
            workers=workers,
            progress=_progress(bar, tid),
        )
    ok = [i for i in res.top(len(res.networks)) if not res.fell[i]]
    return res.networks[(ok or res.top(1))[0]]


def _print_evolve(name: str, summary: dict) -> None:
    """Print what evolution changed in the creature ``name`` (before and after) and its files."""
    from rich.table import Table

    table = Table(box=None, header_style="bold", title=f"what evolution changed ({name})")
    for col in ("parameter", "before", "after"):
        table.add_column(col, justify="left" if col == "parameter" else "right")
    for row in summary["changes"]:
        table.add_row(row["parameter"], f"{row['before']:.4g}", f"{row['after']:.4g}")
    table.add_row(
        "speed (cm/s)", f"{summary['speed_before_cm_s']:.2f}", f"{summary['speed_after_cm_s']:.2f}"
    )
    console.print(table)
    for key in ("creature_file", "network", "video", "record"):
        if key in summary:
            console.print(f"{key:>14}: {summary[key]}")


@san_app.command("tune")
def tune_cmd(
    network: Path = typer.Argument(..., help="A network .json (e.g. runs/cart/sans/01.json)."),
    method: str = typer.Option("sga", help="sga (stochastic gradient ascent) or anneal."),
    trials: int = typer.Option(1000, min=1, max=10_000_000, help="Evaluations to spend."),
    seed: Seed = 0,
    terrain: Terrain = "flat",
    creature: str = typer.Option(None, help="Creature (default: the one the file names)."),
    out: Path = typer.Option(None, help="Output directory (default: <file>-<method>)."),
    video: bool = typer.Option(True, help="Write video.mp4 of the tuned gait."),
    force: Force = False,
) -> None:
    """Phase 2: fine-tune the Fig. 8 parameters (delays, actuators, sensors), weights kept."""
    from zoetic.san.network import load_with_creature
    from zoetic.san.tune import METHODS, TuneError, tune, write_tune
    from zoetic.viz.san import draw_tune

    if method not in METHODS:
        raise TuneError(f"unknown tuning method {method!r}; use one of {', '.join(METHODS)}")
    net, c = load_with_creature(network, creature)
    out = prepare_out(out or network.with_name(f"{network.stem}-{method}"), force)
    bar, tid = _bar(f"{c.name} {method}", trials)
    with bar:
        result = tune(
            net,
            c,
            method=method,
            trials=trials,
            seed=seed,
            terrain=terrain,
            progress=_progress(bar, tid),
        )
    with console.status(f"writing {out}" + (" (video)" if video else "")):
        summary = write_tune(result, c, out, terrain=terrain)
        summary = _with_files(out, summary, draw_tune(result, c, out, terrain, video))
        summary["record"] = _record(out, out / "san.json")
    print_summary(summary, 18)


@san_app.command("show")
def show_cmd(
    path: Path = typer.Argument(..., help="A run directory (search or tune) or a network .json."),
    rank: int = typer.Option(1, min=1, help="For a search directory: which kept network."),
    seconds: float = typer.Option(
        None, min=0.1, max=1000.0, help="Replay time (default: creature's)."
    ),
    terrain: str = typer.Option(None, help="flat or rough (default: the run's)."),
    out: Path = typer.Option(
        None, help="Directory of the video (default: the run's, beside the network)."
    ),
    fps: int = typer.Option(30, min=1, help="Video frame rate."),
    creature: str = typer.Option(
        None,
        help="Creature (default: the one the file names; for an evolve run, its creature.toml).",
    ),
    force: Force = False,
) -> None:
    """Replay a network with its sensor and node states drawn beside the creature (video)."""
    from zoetic.san.creature import CreatureError
    from zoetic.san.network import load_with_creature
    from zoetic.san.search import speed_cm_s
    from zoetic.san.show import resolve_network
    from zoetic.viz.san import show_video

    file = resolve_network(path, rank)
    if creature is None and (file.parent / "creature.toml").is_file():
        creature = str(file.parent / "creature.toml")  # an evolve run's own body
    net, c = load_with_creature(file, creature)
    _check_seconds(c, seconds)
    terrain = terrain or str(net.info.get("terrain", "flat"))
    if out is not None and out.suffix.lower() in (".mp4", ".gif", ".webm", ".mov"):
        raise CreatureError(f"--out {out}: a directory; the video is written inside it")
    name = "show.mp4" if file.stem in ("san", f"{rank:02d}") else f"show-{file.stem}.mp4"
    target = (prepare_out(out, force) if out else path if path.is_dir() else file.parent) / name
    with console.status(f"rendering {target}"):
        written, rollout = show_video(net, c, target, seconds=seconds, terrain=terrain, fps=fps)
    speed = speed_cm_s(c, rollout.metric, rollout.distance, rollout.seconds)
    console.print(f"{'network':>10}: {file}")
    console.print(
        f"{'metric':>10}: {rollout.metric:.4f}  ({speed:.1f} cm/s"
        f"{', fell' if rollout.fell else ''})"
    )
    console.print(f"{'video':>10}: {written}")


@bench_app.command("san")
def bench_san_cmd(
    creature: str = typer.Option("walker", help="Creature to time."),
    trials: int = typer.Option(200, min=1, help="Random networks."),
    workers: Workers = None,
    json: Json = False,
    quick: Quick = False,
) -> None:
    """Wall time of a phase-1 search (random SANs x the creature's seconds, all cores)."""
    from zoetic.bench.san import bench_search

    emit(bench_search(creature, capped(quick, trials, 20), workers), json)
