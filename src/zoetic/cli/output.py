"""What every command prints with: one console, one JSON/table emitter, one progress bar."""

from __future__ import annotations

import json

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

console = Console()
err_console = Console(stderr=True)  # what a --json command says beside its one line


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


def duration_words(seconds: float) -> str:
    """A wall time as people say it: '40 s', '7 min', '1.5 h'."""
    if seconds < 90:
        return f"{max(seconds, 1):.0f} s"
    if seconds < 90 * 60:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


class Countdown:
    """Say once, early in a long search, how long the rest will take on this machine.

    The first progress call only starts the clock (that step also compiles the kernels); the first
    call at least ``after_s`` later prints the time left at the rate since then."""

    def __init__(self, total: int, unit: str, after_s: float = 1.0):
        self.total, self.unit, self.after_s = total, unit, after_s
        self.start: tuple[float, int] | None = None
        self.said = False

    def __call__(self, done: int, out: Console = console) -> None:
        import time

        now = time.perf_counter()
        if self.start is None:
            self.start = (now, done)
            return
        t0, n0 = self.start
        if self.said or now - t0 < self.after_s or done <= n0 or done >= self.total:
            return
        per = (now - t0) / (done - n0)
        out.print(
            f"expected: about {duration_words(per * (self.total - done))} more for "
            f"{self.total - done} {self.unit} ({per * 1e3:.0f} ms each on this machine)"
        )
        self.said = True
