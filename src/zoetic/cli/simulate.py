"""``zoetic simulate`` and ``zoetic animals``."""

from __future__ import annotations

from functools import partial
from pathlib import Path

import typer
from rich.table import Table

from zoetic.cli.apps import app
from zoetic.cli.bench import bench_app, capped
from zoetic.cli.options import Force, Json, Quick
from zoetic.cli.output import console, emit, print_summary


@app.command()
def animals() -> None:
    """List the built-in animals, one line each."""
    from zoetic.bodies import list_animals, load_animal

    table = Table(box=None, header_style="bold")
    for col in ("animal", "nodes", "springs", "muscles", "actuators", "medium", "mass kg"):
        table.add_column(col, justify="left" if col in ("animal", "medium") else "right")
    for name in list_animals():
        b = load_animal(name)
        table.add_row(
            name,
            str(b.n_nodes),
            str(b.n_springs),
            str(b.n_muscles),
            str(b.n_actuators),
            b.medium,
            f"{b.total_mass:.2f}",
        )
    console.print(table)


@app.command()
def simulate(
    animal: str = typer.Argument(..., help="A zoo animal's name or an animal .toml file."),
    controller: str = typer.Option("wave", help="wave, rest, or a controller .json file."),
    seconds: float = typer.Option(
        None,
        min=0.01,
        help="Simulated time (s); default 10, or a stunt's own duration for its macro.json.",
    ),
    out: Path = typer.Option(Path("runs/simulate"), help="Output directory."),
    medium: str = typer.Option(None, help="Override the medium: ground, water, sea, vacuum."),
    dt: float = typer.Option(None, help="Time step (s); default the animal's own."),
    video: bool = typer.Option(True, help="Write video.mp4."),
    fps: int = typer.Option(30, min=1, help="Video frame rate."),
    force: Force = False,
) -> None:
    """Simulate one animal under a controller; write record.npz, video.mp4 and path.png."""
    from zoetic.behavior.stunts import is_macro_file
    from zoetic.outdir import prepare_out
    from zoetic.runs import simulate_run
    from zoetic.viz.media import simulation_media

    prepare_out(out, force)
    if is_macro_file(controller) and medium is None and dt is None:  # a stunt, replayed whole
        from zoetic.bodies import load_animal
        from zoetic.cli.stunt import write_replay

        result = write_replay(load_animal(animal), Path(controller), seconds, out, video, fps)
    else:
        media = partial(simulation_media, video=video, fps=fps)
        result = simulate_run(
            animal, controller, 10.0 if seconds is None else seconds, out, medium, dt, media
        )
    print_summary(result)


@bench_app.command("simulate")
def bench_simulate_cmd(
    animal: str = typer.Option("shark"),
    seconds: float = typer.Option(10.0, min=0.1),
    batch: int = typer.Option(512, min=1),
    json: Json = False,
    quick: Quick = False,
) -> None:
    """Simulated seconds per second: one candidate, a batch on all cores, and NumPy."""
    from zoetic.bench.simulate import bench_simulate

    seconds, batch = capped(quick, seconds, 2.0), capped(quick, batch, 128)
    emit(bench_simulate(animal, seconds, batch, capped(quick, 3, 2)), json)
