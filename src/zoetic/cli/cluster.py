"""``zoetic bench ray``: the Ray evaluator's overhead per generation against in-process."""

from __future__ import annotations

import typer

from zoetic.cli.bench import bench_app, capped
from zoetic.cli.options import Json, Quick
from zoetic.cli.output import emit


@bench_app.command("ray")
def bench_ray_cmd(
    animal: str = typer.Option("shark"),
    population: int = typer.Option(64, min=1, help="Candidates per generation."),
    generations: int = typer.Option(5, min=1),
    actors: int = typer.Option(None, min=1, help="Ray actors (default: one per core)."),
    json: Json = False,
    quick: Quick = False,
) -> None:
    """Seconds per generation on a local Ray against in-process batches, side by side."""
    from zoetic.bench.ray import bench_ray

    population, generations = capped(quick, population, 16), capped(quick, generations, 2)
    emit(bench_ray(animal, "swim-straight", population, generations, actors), json)
