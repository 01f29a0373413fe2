"""What every command prints with: one console, one JSON/table emitter, one progress bar."""

from __future__ import annotations

import json

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

console = Console()


def emit(result: dict, as_json: bool) -> None:
    """Print a result dict as one JSON line, or as aligned ``key value`` lines."""
    if as_json:
        print(json.dumps(result))
    else:
        for key, value in result.items():
            print(f"{key:40s} {value}")


def progress_bar(
    *fields: str, count: str = "{task.completed:>5.0f}/{task.total:.0f}", width: int = 20
) -> Progress:
    """A bar: description, bar, count, then one text column per rich format string in fields."""
    return Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(bar_width=width),
        TextColumn(count),
        *(TextColumn(f) for f in fields),
        TimeElapsedColumn(),
        console=console,
        transient=False,
    )
