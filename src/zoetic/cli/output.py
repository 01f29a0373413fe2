"""What every command prints with: one console, one number format for people, one JSON/table
emitter, one progress bar, and the one way a command says it was interrupted."""

from __future__ import annotations

import json
import math
from typing import Any, NoReturn

import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

console = Console()
err_console = Console(stderr=True)  # what a --json command says beside its one line

INTERRUPTED = {"told": False}  # whether the command already said how it stopped on Ctrl-C

# key endings that carry a unit (summary keys are snake_case with the unit last)
UNITS = (
    ("_cm_s", "cm/s"),
    ("_m_s", "m/s"),
    ("_m3_s", "m^3/s"),
    ("_deg", "deg"),
    ("_hz", "Hz"),
    ("_kg", "kg"),
    ("_m", "m"),
    ("_s", "s"),
)


def number(value: float, digits: int = 3) -> str:
    """Return a float for people: ``digits`` significant digits, whole numbers from 1000 up,
    no exponent between 1e-4 and 1e15 (12.649999999999999 -> 12.6, 1234.5 -> 1234)."""
    if not math.isfinite(value):
        return str(value)
    if value == 0:
        return "0"
    if abs(value) >= 10**digits:
        return f"{value:.0f}" if abs(value) < 1e15 else f"{value:.{digits - 1}e}"
    if abs(value) < 1e-4:
        return f"{value:.{digits - 1}e}"
    places = max(0, digits - 1 - math.floor(math.log10(abs(value))))
    text = f"{round(value, places):.{places}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def fmt(value: Any, unit: str = "") -> str:
    """Return a value for people: floats rounded (:func:`number`), lists and tables item by
    item, with ``unit`` after a number; JSON output keeps full precision (:func:`emit`)."""
    if isinstance(value, bool) or value is None:
        text = str(value)
    elif isinstance(value, float):
        text = number(value)
    elif isinstance(value, int):
        text = str(value)
    elif isinstance(value, list | tuple):
        return "[" + ", ".join(fmt(v) for v in value) + "]" + (f" {unit}" if unit else "")
    elif isinstance(value, dict):
        return ", ".join(f"{k} {fmt(v, unit_of(str(k)))}" for k, v in value.items())
    else:
        return str(value)
    numeric = isinstance(value, int | float) and not isinstance(value, bool)
    return f"{text} {unit}" if unit and numeric else text


def unit_of(key: str) -> str:
    """Return the unit a summary key names by its ending (distance_m -> m), or ""."""
    for ending, unit in UNITS:
        if key.endswith(ending):
            return unit
    return ""


def print_summary(result: dict, width: int = 12) -> None:
    """Print a result dict for people, one right-aligned ``key: value unit`` line each."""
    for key, value in result.items():
        console.print(f"{key:>{width}}: {fmt(value, unit_of(key))}", markup=False)


def emit(result: dict, as_json: bool) -> None:
    """Print a result dict as one JSON line (full precision), or as aligned ``key value``
    lines rounded for people."""
    if as_json:
        print(json.dumps(result))
    else:
        for key, value in result.items():
            print(f"{key:40s} {fmt(value, unit_of(key))}")


def interrupted(message: str) -> NoReturn:
    """Say on one line what a Ctrl-C left behind (and how to go on), then exit 130."""
    INTERRUPTED["told"] = True
    err_console.print(f"[yellow]interrupted:[/] {escape(message)}", highlight=False, soft_wrap=True)
    raise typer.Exit(130)


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
