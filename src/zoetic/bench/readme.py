"""``zoetic bench readme``: run the README's timed commands and print each one's wall time.

The README's conventions, read here and by tests/test_readme.py:

- its shell examples are fenced ```sh blocks of zoetic commands, one a line (``./run.sh CMD``
  is ``zoetic CMD``: run.sh passes its arguments on; a trailing ``\\`` continues a line);
- a command whose comment holds ``[~12 s]`` or ``[~3 min]`` states the CPU time it takes
  (user + system, over all its threads and child processes), which this bench measures (a fresh
  process each, in a temp dir, after the commands before it in its block). CPU time, unlike wall
  time, hardly depends on what else the machine runs; on 2 idle cores a command's wall time is
  between half its CPU time (both cores busy) and all of it (one core).
- ``<!-- test: slow -->`` on the line before a fence puts that block in the slow test tier.
"""

from __future__ import annotations

import os
import re
import resource
import shlex
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from zoetic.errors import ZoeticError

MARK = re.compile(r"\[~(\d+(?:\.\d+)?) (s|min)\]")
SLOW = "<!-- test: slow -->"
QUICK_START = "Quick start"
QUICK_BLOCK_S = 12.0  # --quick: each block's commands up to the first stated over this (CPU s)


@dataclass(frozen=True)
class Command:
    """One command line of a block: its arguments (``zoetic`` first) and the time it states."""

    argv: tuple[str, ...]
    stated_s: float | None
    line: int  # 1-based line of the README

    @property
    def text(self) -> str:
        return shlex.join(self.argv)


@dataclass(frozen=True)
class Block:
    """A fenced code block of the README."""

    lang: str
    text: str
    section: str  # the ## heading it is under
    slow: bool
    line: int  # 1-based line of its first line of code

    def commands(self, where: str = "README.md") -> list[Command]:
        """The block's command lines (sh blocks only), comments and continuations resolved."""
        out: list[Command] = []
        pending, start, stated = "", 0, None
        for k, raw in enumerate(self.text.splitlines()):
            code = raw.split(" #")[0] if not raw.lstrip().startswith("#") else ""
            if not pending:
                start = self.line + k
            pending += " " + code.rstrip().removesuffix("\\")
            mark = MARK.search(raw[len(code) :])
            if mark is not None:
                stated = float(mark[1]) * (60 if mark[2] == "min" else 1)
            if code.rstrip().endswith("\\"):
                continue
            argv, command_stated = shlex.split(pending), stated
            pending, stated = "", None
            if not argv:
                continue
            if argv[0] == "./run.sh":
                argv = ["zoetic", *argv[1:]]
            if argv[0] != "zoetic":
                raise ZoeticError(f"{where}:{start}: a sh block holds zoetic commands only")
            out.append(Command(tuple(argv), command_stated, start))
        return out


def blocks(text: str) -> list[Block]:
    """Every fenced block of a README, in order."""
    out: list[Block] = []
    lines = text.splitlines()
    section, k = "", 0
    while k < len(lines):
        line = lines[k]
        if line.startswith("## "):
            section = line[3:].strip()
        if line.startswith("```") and len(line) > 3:
            end = next(j for j in range(k + 1, len(lines)) if lines[j].startswith("```"))
            slow = k > 0 and lines[k - 1].strip() == SLOW
            body = "\n".join(lines[k + 1 : end])
            out.append(Block(line[3:].strip(), body, section, slow, k + 2))
            k = end
        k += 1
    return out


def read_readme(path: Path) -> list[Block]:
    """The blocks of the README at ``path``, or a ZoeticError that says where to run from."""
    if not path.is_file():
        raise ZoeticError(f"{path}: no such README; run from a zoetic checkout or give --readme")
    return blocks(path.read_text(encoding="utf-8"))


def children_cpu_s() -> float:
    """CPU seconds (user + system) of this process's finished child processes so far."""
    use = resource.getrusage(resource.RUSAGE_CHILDREN)
    return use.ru_utime + use.ru_stime


def commands_within(commands: list[Command], cap: float | None) -> list[Command]:
    """The commands before the first that states more than ``cap`` CPU seconds (None: all);
    a block's commands only need the ones before them, so the prefix runs as written."""
    if cap is None:
        return commands
    over = [k for k, c in enumerate(commands) if c.stated_s is not None and c.stated_s > cap]
    return commands[: over[0]] if over else commands


def bench_readme(
    path: Path,
    sections: tuple[str, ...] | None = (QUICK_START,),
    on_row=None,
    max_stated_s: float | None = None,
) -> dict:
    """Run the blocks of ``sections`` (None: all) that time a command; time each command.
    ``max_stated_s``: run each block only up to its first command stated over this.

    Every command of those blocks gets a row (``stated_s`` is None where the README states no
    time), so a command that has grown slow shows up too.
    Commands run as ``python -m zoetic ...`` in a fresh process each, in one temp dir, so the
    times include starting Python and loading the compiled kernels from their cache.
    ``on_row(row)`` sees each row as soon as it is measured."""
    todo = [
        commands_within(b.commands(str(path)), max_stated_s)
        for b in read_readme(path)
        if b.lang == "sh"
        and (sections is None or b.section in sections)
        and any(c.stated_s is not None for c in b.commands(str(path)))
    ]
    rows = []
    with tempfile.TemporaryDirectory(prefix="zoetic-readme-") as tmp:
        for commands in todo:
            for cmd in commands:
                t0, cpu0 = time.perf_counter(), children_cpu_s()
                done = subprocess.run(
                    [sys.executable, "-m", "zoetic", *cmd.argv[1:]],
                    cwd=tmp,
                    capture_output=True,
                    text=True,
                )
                wall, cpu = time.perf_counter() - t0, children_cpu_s() - cpu0
                if done.returncode != 0:
                    raise ZoeticError(
                        f"{path}:{cmd.line}: `{cmd.text}` failed ({done.returncode}): "
                        f"{done.stderr.strip()[-500:]}"
                    )
                row = {"command": cmd.text, "stated_s": cmd.stated_s}
                rows.append(row | {"cpu_s": round(cpu, 1), "wall_s": round(wall, 1)})
                if on_row is not None:
                    on_row(rows[-1])
    return {"cpus": os.cpu_count(), "load_1min": round(os.getloadavg()[0], 1), "commands": rows}
