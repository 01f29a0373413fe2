"""Which data files a run loaded, and their content hashes.

A regenerated figure must say what it was made from: the animal, creature, task, trick and
species files it read. Rather than trust each experiment to declare them, the run is watched:
:func:`install` adds an audit hook (``sys.addaudithook``) that notes every file the process,
and the worker processes it forks, opens for reading under the package's data folders. Each
path is appended once per process to a log file (one path a line), which
:func:`loaded_files` reads back. :func:`file_hashes` gives the sha256 of each, and
:func:`changed_files` compares a record's hashes with the files as they are now.
"""

from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

import zoetic

PACKAGE = Path(zoetic.__file__).resolve().parent
REPO = PACKAGE.parents[1]  # src/zoetic -> the checkout's root

# folder under src/zoetic -> what its files are (the longest matching folder wins)
KINDS = {
    "bodies/zoo": "animal",
    "san/zoo": "creature",
    "tasks": "task",
    "tasks/tricks": "trick",
    "behavior/aquarium/species": "species",
    "behavior/aquarium/skills": "skill",
}
SUFFIXES = (".toml", ".json")
LOG_ENV = "ZOETIC_PROVENANCE_LOG"


def figures_dir() -> Path:
    """The folder an experiment writes its figures to: $ZOETIC_FIGURES, else docs/figures."""
    return Path(os.environ.get("ZOETIC_FIGURES") or REPO / "docs" / "figures")


def kind_of(path: str | os.PathLike) -> str | None:
    """Return 'animal', 'creature', 'task', ... for a data file of the package, else None."""
    p = Path(path)
    if p.suffix not in SUFFIXES:
        return None
    try:
        rel = p.resolve().relative_to(PACKAGE).parent.as_posix()
    except ValueError:
        return None
    best = max((k for k in KINDS if rel == k or rel.startswith(k + "/")), key=len, default=None)
    return None if best is None else KINDS[best]


def install(log: str | os.PathLike) -> None:
    """Note every package data file this process (and its forks) opens in ``log``."""
    fd = os.open(os.fspath(log), os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    os.environ[LOG_ENV] = os.fspath(log)
    seen: set[str] = set()
    busy = [False]

    def hook(event: str, args: tuple) -> None:
        if event != "open" or busy[0] or not isinstance(args[0], str | bytes | os.PathLike):
            return
        busy[0] = True
        try:
            path = os.fsdecode(args[0])
            if path.endswith(SUFFIXES) and path not in seen and kind_of(path):
                seen.add(path)
                os.write(fd, (str(Path(path).resolve()) + "\n").encode())
        finally:
            busy[0] = False

    sys.addaudithook(hook)


def loaded_files(log: str | os.PathLike) -> list[Path]:
    """Return the distinct data files named in ``log``, sorted."""
    p = Path(log)
    if not p.exists():
        return []
    return sorted({Path(line) for line in p.read_text().splitlines() if line.strip()})


def sha256(path: str | os.PathLike) -> str:
    """Return the hex sha256 of a file's bytes."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def relative(path: str | os.PathLike) -> str:
    """Return ``path`` relative to the checkout's root (POSIX), or as given if outside it."""
    p = Path(path).resolve()
    try:
        return p.relative_to(REPO).as_posix()
    except ValueError:
        return p.as_posix()


def file_hashes(paths: list[Path]) -> dict[str, dict[str, str]]:
    """Return {path relative to the checkout: {"kind", "sha256"}} for each file."""
    return {relative(p): {"kind": kind_of(p) or "file", "sha256": sha256(p)} for p in paths}


def changed_files(files: dict[str, dict[str, str]]) -> list[str]:
    """Return the recorded files that are missing now or whose content hash differs."""
    out = []
    for rel, entry in files.items():
        p = REPO / rel
        if not p.is_file() or sha256(p) != entry["sha256"]:
            out.append(rel)
    return out
