"""``zoetic bench ...``: benchmarks that print side-by-side ratios (never assertions)."""

from __future__ import annotations

import json

import typer

from zoetic.cli import app

bench_app = typer.Typer(help="Benchmarks; figures are ratios measured side by side.")
app.add_typer(bench_app, name="bench")


def _emit(result: dict, as_json: bool) -> None:
    if as_json:
        print(json.dumps(result))
    else:
        for key, value in result.items():
            print(f"{key:40s} {value}")
