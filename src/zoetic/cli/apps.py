"""The ``zoetic`` Typer application that every command module registers on (kept apart from
``zoetic.cli``, which imports those modules, so that no module imports its importer)."""

from __future__ import annotations

import typer

app = typer.Typer(
    name="zoetic",
    help="Physics-based artificial animals that learn to move by themselves.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)

_DEBUG = {"on": False}


@app.callback()
def _root(debug: bool = typer.Option(False, "--debug", help="Show full tracebacks.")) -> None:
    _DEBUG["on"] = debug
