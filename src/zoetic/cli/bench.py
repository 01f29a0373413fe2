"""``zoetic bench ...``: benchmarks that print side-by-side ratios (never assertions)."""

from __future__ import annotations

from pathlib import Path

import typer

from zoetic.cli.apps import app
from zoetic.cli.options import Json, Quick
from zoetic.cli.output import emit, err_console
from zoetic.errors import ZoeticError

bench_app = typer.Typer(
    help="Benchmarks; figures are ratios measured side by side. All of them and one table of "
    "every figure beside its reference: zoetic bench all (--quick: small sizes, minutes).",
    no_args_is_help=True,
)
app.add_typer(bench_app, name="bench")


def capped(quick: bool, value, cap):
    """Return ``value``, or at most ``cap`` under ``--quick`` (a smaller value given stays)."""
    return min(value, cap) if quick else value


@bench_app.command("gym")
def bench_gym_cmd(
    env_id: str = typer.Option("zoetic/SharkSwim-v0", "--env", help="A zoetic environment id."),
    num_envs: int = typer.Option(64, min=1, help="Environments stepped together."),
    steps: int = typer.Option(100, min=1, help="Vector steps timed."),
    json: Json = False,
    quick: Quick = False,
) -> None:
    """Env steps per second: the native vector env against SyncVectorEnv, same actions."""
    from zoetic.bench.gym import bench_gym

    emit(bench_gym(env_id, capped(quick, num_envs, 16), capped(quick, steps, 20)), json)


@bench_app.command("vision")
def bench_vision_cmd(
    frames: int = typer.Option(150, min=10, help="Vision frames timed."),
    json: Json = False,
    quick: Quick = False,
) -> None:
    """Animat vision: retina frames/s (2 eyes x 4 levels) and the whole pursuit loop's."""
    from zoetic.bench.vision import bench_vision

    emit(bench_vision(capped(quick, frames, 20)), json)


@bench_app.command("jax")
def bench_jax_cmd(
    animal: str = typer.Option("shark", help="A built-in animal."),
    batch: list[int] = typer.Option(
        [256], min=1, help="Candidates simulated together; repeat for a sweep (64 ... 65536)."
    ),
    seconds: float = typer.Option(10.0, min=0.01, help="Simulated seconds per candidate."),
    repeats: int = typer.Option(2, min=1, help="Timed runs; the best counts."),
    numba: bool = typer.Option(
        False, "--numba", help="Also time the Numba kernel on the same activations, alternately."
    ),
    json: Json = False,
    quick: Quick = False,
) -> None:
    """The JAX backend on whatever device JAX sees: sim-s/s of a batch, compile time apart."""
    from zoetic.bench.jax_sim import benchmark

    batch = [capped(quick, b, 32) for b in batch]
    seconds, repeats = capped(quick, seconds, 1.0), capped(quick, repeats, 1)
    rows = [benchmark(animal, seconds, b, repeats, numba) for b in batch]
    emit({"jax": rows[0] if len(rows) == 1 else rows}, json)


@bench_app.command("render")
def bench_render_cmd(
    animal: str = typer.Option("shark", help="A built-in animal."),
    frames: int = typer.Option(30, min=2, help="Video frames per timed render."),
    repeats: int = typer.Option(5, min=1, help="Timed renders of each kind, alternated."),
    json: Json = False,
    quick: Quick = False,
) -> None:
    """A video frame's cost: the display skin against the raw lattice, same motion."""
    from zoetic.bench.render import bench_render

    emit(bench_render(animal, capped(quick, frames, 6), capped(quick, repeats, 2)), json)


@bench_app.command("track")
def bench_track_cmd(
    animal: str = typer.Option("shark", help="A built-in animal that swims or crawls."),
    memory: str = typer.Option(
        None,
        help="Repertoire directory (default: the animal's default repertoire, trained "
        "once into runs/bench).",
    ),
    time_limit: float = typer.Option(60.0, min=1.0, max=3600.0, help="Seconds per course."),
    json: Json = False,
    quick: Quick = False,
) -> None:
    """Tracking courses in 3D: targets reached, depth drift, worst roll and pitch per course."""
    from zoetic.bench.track import bench_track

    if quick and memory is None:
        memory = str(quick_memory(animal))
    emit(bench_track(animal, memory, capped(quick, time_limit, 10.0)), json)


def quick_memory(animal: str) -> Path:
    """The repertoire a ``--quick`` bench uses when given none: trained once with a small
    budget (a look at the bench, not at the animal's skills)."""
    from zoetic.bench.memory import QUICK_BUDGET, bench_memory
    from zoetic.bodies import load_animal

    return bench_memory(animal, load_animal(animal).name, budget=QUICK_BUDGET)


@bench_app.command("readme")
def bench_readme_cmd(
    readme: Path = typer.Option(Path("README.md"), help="The README whose commands to time."),
    section: list[str] = typer.Option(None, help="A ## section to run (default: Quick start)."),
    everything: bool = typer.Option(False, "--all", help="Every section's timed blocks."),
    json: Json = False,
    quick: Quick = False,
) -> None:
    """The CPU and wall time of the README's timed commands ([~12 s]), run as written."""
    from zoetic.bench.readme import QUICK_BLOCK_S, QUICK_START, bench_readme

    def say(row: dict) -> None:
        err_console.print(
            f"{row['cpu_s']:8.1f} s CPU {row['wall_s']:8.1f} s wall  {row['command']}",
            highlight=False,
        )

    sections = None if everything or quick and not section else tuple(section or [QUICK_START])
    cap = QUICK_BLOCK_S if quick else None
    emit(bench_readme(readme.resolve(), sections, say, cap), json)


@bench_app.command("train")
def bench_train_cmd(
    animal: str = typer.Option("shark", help="The animal whose repertoire is trained."),
    demo_budget: int = typer.Option(None, min=16, help="The demo's evaluations (default its)."),
    train_budget: int = typer.Option(None, min=10, help="Evaluations per repertoire entry."),
    json: Json = False,
    quick: Quick = False,
) -> None:
    """Wall time of zoetic demo's learning and of zoetic repertoire train, with defaults."""
    from zoetic.bench.memory import QUICK_BUDGET
    from zoetic.bench.train import bench_train
    from zoetic.learning.config import DEMO_BUDGET

    if quick:
        demo_budget = capped(quick, demo_budget or DEMO_BUDGET, 400)
        train_budget = capped(quick, train_budget or QUICK_BUDGET, QUICK_BUDGET)
    emit(bench_train(animal, demo_budget, train_budget), json)


@bench_app.command("all")
def bench_all_cmd(
    quick: Quick = False,
    only: list[str] = typer.Option(
        None, help="Run only this benchmark (repeatable; a wrong name lists them)."
    ),
    lines: bool = typer.Option(False, "--lines", help="Also print each benchmark's JSON line."),
    results: Path = typer.Option(
        None, help="Where to keep every benchmark's JSON (default runs/bench/results-MODE.json)."
    ),
    table_of: Path = typer.Option(
        None, "--from", help="Run nothing: the table of a results file an earlier run kept."
    ),
    reference: Path = typer.Option(
        Path("bench/reference.json"), help="The previous figures (written by --save-reference)."
    ),
    save_reference: bool = typer.Option(
        False, "--save-reference", help="Keep this run's figures in --reference."
    ),
    json: Json = False,
) -> None:
    """Every benchmark once (--quick: its small sizes), then one table: each figure beside
    the same run's baseline, the papers' figures and the previous figure, with the ratio."""
    import json as jsonlib

    from zoetic.bench.summary import BENCHES, load_reference, run_all, stamp, table_rows
    from zoetic.cli.output import console
    from zoetic.io import load_json

    keys = {b.key for b in BENCHES}
    for key in only or ():
        if key not in keys:
            raise ZoeticError(f"--only {key}: no such benchmark; one of {', '.join(sorted(keys))}")
    if table_of is not None:
        kept = load_json(table_of, "bench results file")
        ok = isinstance(kept, dict) and isinstance(kept.get("benches"), dict)
        if not ok or kept.get("mode") not in ("quick", "full"):
            raise ZoeticError(f"{table_of}: not the results of zoetic bench all (mode, benches)")
        mode, found = kept["mode"], kept["benches"]
    else:
        mode = "quick" if quick else "full"

        def said(key: str, result: dict, took: dict) -> None:
            if lines:
                print(jsonlib.dumps(result), flush=True)
            state = f"failed: {result['error']}" if "error" in result else "done"
            err_console.print(
                f"bench {key}: {state} ({took['wall_s']:.0f} s wall, {took['cpu_s']:.0f} s CPU)",
                highlight=False,
            )

        where = stamp()
        found, timings = run_all(quick, tuple(only or ()), said)
        kept = {"mode": mode, **where, "benches": found, "timings": timings}
        out = results or Path("runs/bench") / f"results-{mode}.json"
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(jsonlib.dumps(kept, indent=1) + "\n", encoding="utf-8")
    rows = table_rows(found, mode, load_reference(reference))
    if save_reference:
        from zoetic.bench.summary import save_reference as keep

        keep(reference, rows, mode, {k: kept.get(k, "?") for k in ("host", "date", "commit")})
    if json:
        emit({"mode": mode, "rows": rows}, True)
    else:
        print_table(rows, mode, kept)
        for key, result in found.items():
            if "error" in result:
                console.print(f"bench {key} failed: {result['error']}", highlight=False)


def print_table(rows: list[dict], mode: str, kept: dict) -> None:
    """The figures for people: figure | this run | reference | ratio | source, one figure's
    further references on the lines under it."""
    from rich.console import Console
    from rich.table import Table

    from zoetic.bench.figures import PAPERS
    from zoetic.cli.output import console, number

    out = console if console.is_terminal else Console(width=150)  # a file: one line a row

    def show(v, unit: str = "") -> str:
        text = v if isinstance(v, str) else "-" if v is None else number(float(v))
        return f"{text} {unit}".rstrip() if isinstance(v, int | float) else text

    title = (
        f"zoetic bench all ({mode}): {kept.get('host', '?')}, load {kept.get('load_1min', '?')}"
        f" at the start, {kept.get('date', '?')}, commit {kept.get('commit', '?')}"
    )
    table = Table(title=title, title_justify="left")
    for name, justify in (("figure", "left"), ("this run", "right"), ("reference", "right")):
        table.add_column(name, justify=justify)
    table.add_column("x faster", justify="right")
    table.add_column("reference is", overflow="fold")
    last = None
    for row in rows:
        same = row["key"] == last
        last = row["key"]
        table.add_row(
            "" if same else row["figure"],
            "" if same else show(row["value"], row["unit"]),
            show(row["reference"], row["unit"]),
            "-" if row["ratio"] is None else f"{number(row['ratio'])}x",
            row["source"],
        )
    out.print(table)
    took = kept.get("timings") or {}
    if took:
        wall, cpu = (sum(t[k] for t in took.values()) for k in ("wall_s", "cpu_s"))
        out.print(f"{len(took)} benchmarks: {wall:.0f} s wall, {cpu:.0f} s CPU in all")
    if mode == "quick":
        out.print("quick: small sizes, a look and not a record; times of a fixed amount of work")
        out.print("  are compared with the papers' only by a full run (zoetic bench all)")
    cited = {row["source"] for row in rows}
    for paper in PAPERS.values():
        if paper.source in cited:
            out.print(f"{paper.source}: {paper.quote}", highlight=False)
