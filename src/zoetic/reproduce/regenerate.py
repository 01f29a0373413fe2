"""Regenerate an experiment's figures and numbers, and the run record that says what made them.

A run record (``docs/figures/records/<experiment>[.quick].json``) holds the commit, the exact
command, the mode, the wall time, the content hash of every animal, creature, task, trick and
species file the run loaded (:mod:`zoetic.reproduce.provenance`), the hash of every output,
the numbers of its JSON outputs (or the JSON lines it printed) and the tail of its output.
A claim is stale when no record of its experiment exists or a recorded input has changed.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from zoetic.errors import ZoeticError
from zoetic.io import write_json
from zoetic.reproduce.provenance import (
    REPO,
    changed_files,
    file_hashes,
    loaded_files,
    relative,
    sha256,
)
from zoetic.reproduce.registry import Claim, Experiment, Registry

FIGURES = REPO / "docs" / "figures"
MAX_NUMBERS = 200_000  # characters of an output JSON kept in the record


def record_path(exp: str, quick: bool, figures: Path = FIGURES) -> Path:
    """Where the run record of ``exp`` in that mode lives (under ``figures``/records)."""
    return figures / "records" / f"{exp}{'.quick' if quick else ''}.json"


def commit() -> str:
    """The checkout's commit, with '+dirty' when tracked files differ from it."""
    try:
        head = subprocess.run(
            ["git", "-C", str(REPO), "rev-parse", "HEAD"], capture_output=True, text=True
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "-C", str(REPO), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
        ).stdout.strip()
    except OSError:
        return "unknown"
    return (head or "unknown") + ("+dirty" if dirty else "")


def argv(exp: Experiment, quick: bool, log: str) -> list[str]:
    """The command line that runs ``exp`` under the provenance runner."""
    head = list(exp.command)
    if head[0] != "-m":
        script = REPO / head[0]
        if not script.is_file():
            raise ZoeticError(f"experiment {exp.name!r}: {head[0]} does not exist in {REPO}")
        head[0] = str(script)
    args = exp.quick if quick else exp.full
    return [sys.executable, "-m", "zoetic.reproduce.runner", log, *head, *args]


def _numbers(exp: Experiment, out_dir: Path, stdout: str) -> dict[str, Any]:
    numbers: dict[str, Any] = {}
    for name in exp.outputs:
        p = out_dir / name
        if p.suffix == ".json" and p.is_file() and p.stat().st_size <= MAX_NUMBERS:
            numbers[name] = json.loads(p.read_text())
    if exp.stdout_json:
        lines = [ln for ln in stdout.splitlines() if ln.startswith("{")]
        numbers["stdout"] = [json.loads(ln) for ln in lines]
    return numbers


def _run(cmd: list[str], env: dict, timeout: float | None, name: str):
    """Run ``cmd`` in its own process group; on timeout end the group (workers included)."""
    proc = subprocess.Popen(
        cmd,
        cwd=REPO,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGTERM)
        proc.communicate()
        raise ZoeticError(f"{name}: did not finish within {timeout:.0f} s") from None
    return subprocess.CompletedProcess(cmd, proc.returncode, out, err)


def run_experiment(
    exp: Experiment, quick: bool, timeout: float | None = None, figures: Path = FIGURES
) -> dict:
    """Run ``exp`` (quick or full), write its run record and return it. Its figures go to
    ``figures`` (docs/figures), a quick run's to ``figures``/quick."""
    out_dir = figures / "quick" if quick else figures
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="zoetic-reproduce-") as tmp:
        log = str(Path(tmp) / "loaded.txt")
        cmd = argv(exp, quick, log)
        env = os.environ | {"ZOETIC_FIGURES": str(out_dir), "PYTHONPATH": str(REPO / "src")}
        t0 = time.time()
        proc = _run(cmd, env, timeout, exp.name)
        wall = time.time() - t0
        if proc.returncode != 0:
            tail = (proc.stdout + proc.stderr)[-2000:]
            raise ZoeticError(f"{exp.name}: exited with {proc.returncode}:\n{tail}")
        files = file_hashes(loaded_files(log))
    outputs = {
        relative(out_dir / n): sha256(out_dir / n) for n in exp.outputs if (out_dir / n).is_file()
    }
    rec = {
        "experiment": exp.name,
        "mode": "quick" if quick else "full",
        "commit": commit(),
        "command": command_line(exp, quick),
        "finished_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "wall_s": round(wall, 1),
        "load_average": round(os.getloadavg()[0], 1),  # timings mean little on a busy machine
        "files": files,
        "outputs": outputs,
        "numbers": _numbers(exp, out_dir, proc.stdout),
        "output_tail": proc.stdout[-1500:],
    }
    write_json(record_path(exp.name, quick, figures), rec)
    return rec


def load_record(exp: str, quick: bool, figures: Path = FIGURES) -> dict | None:
    """Return the run record of ``exp`` in that mode, or None if it was never made."""
    p = record_path(exp, quick, figures)
    return json.loads(p.read_text()) if p.is_file() else None


def command_line(exp: Experiment, quick: bool) -> str:
    """The command a run record of ``exp`` in that mode names."""
    return " ".join(["python", *exp.command, *(exp.quick if quick else exp.full)])


def latest_fresh(exp: Experiment | None, figures: Path = FIGURES) -> tuple[dict | None, bool]:
    """Return (the best record of ``exp``, stale?): a full record is preferred to a quick
    one, a fresh one to a stale one. A record is fresh when its inputs are unchanged and it
    ran the experiment's command as the registry now gives it; no record at all is stale."""
    if exp is None:
        return None, False
    recs = [load_record(exp.name, False, figures), load_record(exp.name, True, figures)]
    recs = [r for r in recs if r is not None]
    for r in recs:
        same = r["command"] == command_line(exp, r["mode"] == "quick")
        if same and not changed_files(r["files"]):
            return r, False
    return (recs[0] if recs else None), True


def lookup(numbers: dict, key: str) -> Any:
    """Return the value at "file.json:a/b/0/c" in a record's numbers, or None."""
    name, _, path = key.partition(":")
    value: Any = numbers.get(name)
    for part in filter(None, path.split("/")):
        if isinstance(value, list) and part.isdigit() and int(part) < len(value):
            value = value[int(part)]
        elif isinstance(value, dict) and part in value:
            value = value[part]
        else:
            return None
    return value


def claim_row(reg: Registry, c: Claim, figures: Path = FIGURES) -> dict:
    """The claim as one JSON-able row: the registry's fields, stale, and the latest run."""
    exp = reg.experiments[c.experiment] if c.experiment is not None else None
    rec, stale = latest_fresh(exp, figures)
    row = {
        "id": c.id,
        "paper": c.paper,
        "where": c.where,
        "says": c.says,
        "ours": c.ours,
        "status": c.status,
        "stale": stale,
        "explanation": c.explanation,
        "experiment": c.experiment,
        "command": None,
        "absent": c.absent,
        "run": None,
    }
    if exp is not None:
        row["command"] = f"zoetic reproduce {c.id}"
        row["script"] = " ".join(exp.command)
    if rec is not None:
        row["run"] = {
            "mode": rec["mode"],
            "commit": rec["commit"],
            "finished_utc": rec["finished_utc"],
            "wall_s": rec["wall_s"],
            "load_average": rec.get("load_average"),
            "changed_inputs": changed_files(rec["files"]),
            "command": rec["command"],
            "outputs": sorted(rec["outputs"]),
            "values": {k: lookup(rec["numbers"], k) for k in c.keys},
        }
    return row
