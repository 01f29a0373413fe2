"""``zoetic bench ...``: benchmarks that print side-by-side ratios (never assertions)."""

from __future__ import annotations

from pathlib import Path

import typer

from zoetic.cli.apps import app
from zoetic.cli.options import Json
from zoetic.cli.output import emit, err_console

bench_app = typer.Typer(help="Benchmarks; figures are ratios measured side by side.")
app.add_typer(bench_app, name="bench")


@bench_app.command("gym")
def bench_gym_cmd(
    env_id: str = typer.Option("zoetic/SharkSwim-v0", "--env", help="A zoetic environment id."),
    num_envs: int = typer.Option(64, min=1, help="Environments stepped together."),
    steps: int = typer.Option(100, min=1, help="Vector steps timed."),
    json: Json = False,
) -> None:
    """Env steps per second: the native vector env against SyncVectorEnv, same actions."""
    from zoetic.bench.gym import bench_gym

    emit(bench_gym(env_id, num_envs, steps), json)


@bench_app.command("vision")
def bench_vision_cmd(
    frames: int = typer.Option(150, min=10, help="Vision frames timed."),
    json: Json = False,
) -> None:
    """Animat vision: retina frames/s (2 eyes x 4 levels) and the whole pursuit loop's."""
    from zoetic.bench.vision import bench_vision

    emit(bench_vision(frames), json)


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
) -> None:
    """The JAX backend on whatever device JAX sees: sim-s/s of a batch, compile time apart."""
    from zoetic.bench.jax_sim import benchmark

    rows = [benchmark(animal, seconds, b, repeats, numba) for b in batch]
    emit({"jax": rows[0] if len(rows) == 1 else rows}, json)


@bench_app.command("render")
def bench_render_cmd(
    animal: str = typer.Option("shark", help="A built-in animal."),
    frames: int = typer.Option(30, min=2, help="Video frames per timed render."),
    repeats: int = typer.Option(5, min=1, help="Timed renders of each kind, alternated."),
    json: Json = False,
) -> None:
    """A video frame's cost: the display skin against the raw lattice, same motion."""
    from zoetic.bench.render import bench_render

    emit(bench_render(animal, frames, repeats), json)


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
) -> None:
    """Tracking courses in 3D: targets reached, depth drift, worst roll and pitch per course."""
    from zoetic.bench.track import bench_track

    emit(bench_track(animal, memory, time_limit), json)


@bench_app.command("readme")
def bench_readme_cmd(
    readme: Path = typer.Option(Path("README.md"), help="The README whose commands to time."),
    section: list[str] = typer.Option(None, help="A ## section to run (default: Quick start)."),
    everything: bool = typer.Option(False, "--all", help="Every section's timed blocks."),
    json: Json = False,
) -> None:
    """The CPU and wall time of the README's timed commands ([~12 s]), run as written."""
    from zoetic.bench.readme import QUICK_START, bench_readme

    def say(row: dict) -> None:
        err_console.print(
            f"{row['cpu_s']:8.1f} s CPU {row['wall_s']:8.1f} s wall  {row['command']}",
            highlight=False,
        )

    sections = None if everything else tuple(section or [QUICK_START])
    emit(bench_readme(readme.resolve(), sections, say), json)
