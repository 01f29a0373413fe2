"""``zoetic bench all``: every benchmark once, and one table of their figures beside references.

Each benchmark runs as ``zoetic bench NAME --json`` (``--quick`` for its small sizes) in a
fresh process; its JSON line is kept as it is (``results``), and the table only reads it: no
figure is timed twice. A figure's references, in this order:

- the baseline its benchmark measured side by side in the same run (the NumPy reference, the
  in-process evaluator, the raw lattice, annealing for the optimizers that match it);
- the paper's figure, where a paper gives one (:data:`PAPERS`, cited);
- the previous figure kept in a reference file (``bench/reference.json``: per mode, quick or
  full, each figure's value with the host, date and commit that measured it;
  ``zoetic bench all --save-reference`` writes it).

The ratio is "times faster than the reference": this run over the reference for a rate, the
reference over this run for a time; a count (targets reached) has none.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from zoetic.bench.figures import FIGURES, Figure, readme_figures
from zoetic.bench.readme import children_cpu_s


@dataclass(frozen=True)
class Bench:
    """One benchmark invocation: its key in the results and its ``zoetic bench`` arguments."""

    key: str
    argv: tuple[str, ...]


BENCHES = (
    Bench("simulate", ("simulate",)),
    Bench("learn", ("learn",)),
    Bench("train", ("train",)),
    Bench("skills", ("skills",)),
    Bench("san", ("san",)),
    Bench("ray", ("ray",)),
    Bench("jax", ("jax",)),
    Bench("gym", ("gym",)),
    Bench("vision", ("vision",)),
    Bench("aquarium", ("aquarium",)),
    # its history's scene: 15 food particles, 5 obstacles (the defaults grow with the fishes)
    Bench("aquarium-60", ("aquarium", "--fishes", "60", "--food", "15", "--obstacles", "5")),
    Bench("aquarium-vision", ("aquarium", "--perception", "vision")),
    Bench("aquarium-skills", ("aquarium", "--skills", "both")),
    Bench("stunts", ("stunts",)),
    Bench("track", ("track",)),
    Bench("render", ("render",)),
    Bench("readme", ("readme",)),
)
CPU_ONLY = {"JAX_PLATFORMS": "cpu"}  # the JAX CPU figure on a host whose JAX sees a GPU


def run_bench(argv: tuple[str, ...], quick: bool, env: dict | None = None) -> dict:
    """Run ``zoetic bench ARGV --json`` in a fresh process; return its JSON object, or
    ``{"error": ...}`` with the end of what it said when it failed."""
    cmd = [sys.executable, "-m", "zoetic", "bench", *argv, "--json", *(["--quick"] * quick)]
    done = subprocess.run(cmd, capture_output=True, text=True, env=os.environ | (env or {}))
    lines = [s for s in done.stdout.splitlines() if s.startswith("{")]
    if done.returncode != 0 or not lines:
        said = (done.stderr.strip() or done.stdout.strip())[-300:]
        return {"error": f"exit {done.returncode}: {said}"}
    return json.loads(lines[-1])


def run_all(
    quick: bool,
    only: tuple[str, ...] | None = None,
    on_done: Callable[[str, dict, dict], None] | None = None,
    runner: Callable[..., dict] = run_bench,
) -> tuple[dict, dict]:
    """Run every benchmark (``only``: those keys); return ``{key: its JSON}`` and
    ``{key: {"wall_s", "cpu_s"}}`` (its process's CPU time, which a busy host hardly
    changes); ``on_done`` sees each key, result and timing as it finishes. On a host where JAX
    runs on a GPU, ``jax`` is that run and ``jax-cpu`` the same bench on the CPU."""
    results: dict = {}
    timings: dict = {}

    def one(key: str, argv: tuple[str, ...], env: dict | None = None) -> None:
        t0, cpu0 = time.perf_counter(), children_cpu_s()
        results[key] = runner(argv, quick) if env is None else runner(argv, quick, env)
        timings[key] = {
            "wall_s": round(time.perf_counter() - t0, 1),
            "cpu_s": round(children_cpu_s() - cpu0, 1),
        }
        if on_done:
            on_done(key, results[key], timings[key])

    for bench in BENCHES:
        if only and bench.key not in only:
            continue
        one(bench.key, bench.argv)
        if bench.key == "jax" and results["jax"].get("jax", {}).get("backend", "cpu") != "cpu":
            one("jax-cpu", bench.argv, CPU_ONLY)
    return results, timings


def is_number(v) -> bool:
    """Whether a JSON value is a number (not a bool, a count 'k/n' or None)."""
    return isinstance(v, int | float) and not isinstance(v, bool)


def ratio(value, reference, higher_is_better: bool) -> float | None:
    """Times faster than the reference (None where either is missing, zero or not a number)."""
    if not (is_number(value) and is_number(reference)) or not value or not reference:
        return None
    return value / reference if higher_is_better else reference / value


def figure_rows(fig: Figure, results: dict, mode: str, previous: dict) -> list[dict]:
    """The table's rows of one figure: one per reference (a row without one when it has
    none); empty when the figure's benchmark did not run or failed (its value None: the
    benchmark ran and measured nothing, e.g. an optimizer that never matched annealing)."""
    value = fig.value(results)
    ran = "error" not in results.get(fig.bench, {"error": "not run"})
    if value is None and not ran:
        return []
    refs = []
    base = fig.baseline(results) if fig.baseline and not isinstance(value, str) else None
    if base is not None:
        refs.append((base, fig.baseline_label))
    if fig.paper and (mode == "full" or not fig.sized):
        refs.append((fig.paper.value, fig.paper.source))
    prev = previous.get(mode, {}).get(fig.key)
    if prev is not None:
        refs.append((prev["value"], f"previous: {prev['host']}, {prev['date']}, {prev['commit']}"))
    row = {"key": fig.key, "figure": fig.label, "unit": fig.unit, "value": value}
    if not refs:
        return [row | {"reference": None, "ratio": None, "source": ""}]
    return [
        row | {"reference": ref, "ratio": ratio(value, ref, fig.higher), "source": source}
        for ref, source in refs
    ]


def table_rows(results: dict, mode: str, previous: dict | None = None) -> list[dict]:
    """Every row of the table of ``results`` (``{bench key: its JSON}``), in figure order."""
    rows: list[dict] = []
    for fig in (*FIGURES, *readme_figures(results)):
        rows += figure_rows(fig, results, mode, previous or {})
    return rows


def load_reference(path: Path) -> dict:
    """The previous figures kept in ``path`` (``{mode: {key: {value, host, date, commit}}}``),
    or none when it does not exist."""
    if not path.is_file():
        return {}
    from zoetic.errors import ZoeticError
    from zoetic.io import load_json

    kept = load_json(path, "bench reference file")
    for mode, figures in kept.items() if isinstance(kept, dict) else [("", None)]:
        if mode not in ("quick", "full") or not isinstance(figures, dict):
            raise ZoeticError(f"{path}: expected {{'quick'|'full': {{figure: ...}}}}, got {mode!r}")
        for key, fig in figures.items():
            if not isinstance(fig, dict) or not {"value", "host", "date", "commit"} <= set(fig):
                raise ZoeticError(f"{path}: {mode}.{key}: needs value, host, date and commit")
    return kept


def save_reference(path: Path, rows: list[dict], mode: str, stamp: dict) -> dict:
    """Keep this run's numeric figures in ``path`` under ``mode`` (others stay); return it."""
    kept = load_reference(path)
    figures = kept.setdefault(mode, {})
    for row in rows:
        if is_number(row["value"]):
            figures[row["key"]] = {"value": row["value"], "label": row["figure"], **stamp}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(kept, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    return kept


def stamp() -> dict:
    """Where and when this run measured: the CPU (and its cores), the UTC date, the commit,
    and the host's load (1-minute average) as it started: a busy host's figures are low."""
    from zoetic.bench.simulate import host_cpu

    cpu = host_cpu()
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=True
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        commit = "unknown"
    return {
        "host": f"{cpu['cpu']} x{os.cpu_count()} ({cpu['simd_float32_lanes']} lanes)",
        "date": time.strftime("%Y-%m-%d", time.gmtime()),
        "commit": commit or "unknown",
        "load_1min": round(os.getloadavg()[0], 1),
    }
