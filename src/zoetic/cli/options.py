"""Options that several commands declare alike, each declared once as an annotated type.

A command gives the default in its signature (``seed: Seed = 0``), so the same option may
default differently in different commands while its flag and help text stay one."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated

import typer

Animal = Annotated[str, typer.Argument(help="Zoo animal name or animal .toml file.")]
"""The animal: a zoo name or an animal .toml file."""

Memory = Annotated[Path, typer.Option(help="Repertoire directory (zoetic repertoire train).")]
"""The learned repertoire a command's animal acts with."""

Seed = Annotated[int, typer.Option(help="Random seed: same seed, same result.")]
"""The run's random seed."""

RunDir = Annotated[Path, typer.Option(help="Run directory to write (it must be empty).")]
"""The directory a run writes its files into."""

Force = Annotated[
    bool,
    typer.Option("--force", help="Empty a non-empty --out (a zoetic run directory) first."),
]
"""Whether a command may replace the files of an earlier run in its --out."""

Method = Annotated[str, typer.Option(help="anneal (simulated annealing) or ga (genetic).")]
"""The search method of a macro controller."""

Evaluator = Annotated[str, typer.Option(help="batch (this machine) or ray (a cluster).")]
"""Where a search evaluates its candidates."""

RayAddress = Annotated[str, typer.Option(help="Ray cluster for --evaluator ray.")]
"""The Ray cluster an ``--evaluator ray`` search uses."""

Righting = Annotated[
    bool,
    typer.Option(
        help="Keep a fish upright: each window plays the planned entry or one of its "
        "righting variants (fins tilted, a gentler stroke), whichever its own simulation "
        "keeps nearest upright and at the start depth; --no-righting plays the plan as given.",
    ),
]
"""Whether a sequence of repertoire entries gets a fish's righting reflex."""

Fps = Annotated[int, typer.Option(min=1)]
"""The video's frame rate."""

Terrain = Annotated[str, typer.Option(help="flat, or rough (uneven ground).")]
"""The ground a SAN creature moves over."""

Workers = Annotated[int, typer.Option(min=1, help="Worker processes (default: all cores).")]
"""How many worker processes evaluate in parallel."""

Json = Annotated[bool, typer.Option("--json", help="Print one JSON object.")]
"""Whether a benchmark prints one JSON object instead of aligned lines."""

Quick = Annotated[
    bool,
    typer.Option(
        "--quick",
        help="Small sizes (caps the size options): seconds, not minutes; for a look, not a record.",
    ),
]
"""Whether a benchmark runs at its small sizes (``zoetic bench all --quick`` runs them all)."""


def use_ray_address(address: str | None) -> None:
    """Point Ray at the cluster of ``--ray-address`` (``ray.init()`` reads RAY_ADDRESS)."""
    if address:
        os.environ["RAY_ADDRESS"] = address


def given(ctx: typer.Context, name: str) -> bool:
    """True when the option ``name`` was given (on the command line or in the environment),
    not left at its default: a resumed run takes only what the user changed."""
    source = ctx.get_parameter_source(name)
    return source is not None and source.name not in ("DEFAULT", "DEFAULT_MAP")
