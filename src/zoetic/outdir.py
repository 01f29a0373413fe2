"""Run directories on disk: making one, and the ``--out`` convention every command keeps (a
new or empty directory; ``--force`` empties an earlier zoetic run there, never anything
else; ``--resume`` continues one).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from zoetic.errors import ZoeticError
from zoetic.io import abbrev


def check_out_dir(path: str | os.PathLike) -> Path:
    """Refuse an output directory that cannot be one (a file is in the way); creates nothing."""
    path = Path(path)
    for p in (path, *path.parents):
        if p.exists():
            if not p.is_dir():
                where = f"{path}: {p}" if p != path else f"{p}:"
                raise ZoeticError(f"{where} exists and is not a directory; choose another --out")
            break
    return path


DEMO_MARKER = ".zoetic-demo"  # the list of files zoetic demo made in its directory

# files and folders by which a directory is known as a zoetic run (record, summary, learning
# run, controllers, stunt, aquarium, SAN search): only such a directory is emptied by --force
RUN_FILES = (
    "record.npz",
    "summary.json",
    "config.toml",
    "checkpoint.npz",
    "controller.json",
    "sequence.json",
    "macro.json",
    "repertoire.json",
    "events.csv",
    "san.json",
    "sans",
    DEMO_MARKER,
)


def prepare_out(out: str | Path, force: bool = False, resume: str = "") -> Path:
    """Return ``out`` ready for a new run: a missing or empty directory is used as it is; a
    non-empty one is refused (naming what it holds, and ``resume``, the command that would
    continue it, if any) unless ``force``, which empties it when it is a zoetic run."""
    out = check_out_dir(out)
    held = sorted(p.name for p in out.iterdir()) if out.is_dir() else []
    if not held:
        return out
    if not force:
        go_on = f"continue it with {resume}, " if resume else ""
        raise ZoeticError(
            f"{out}: already holds {len(held)} file(s) ({abbrev(held)[1:-1]}); {go_on}add "
            "--force to replace them, or choose another --out"
        )
    _check_emptiable(out, held)
    for child in out.iterdir():
        if child.is_dir() and not child.is_symlink():
            shutil.rmtree(child)  # removes links inside, never what they point to
        else:
            child.unlink()
    return out


def _check_emptiable(out: Path, held: list[str]) -> None:
    """Refuse to empty a directory that is not a zoetic run, or that holds the working
    directory or the home directory (a mistyped --out must never cost a person their files)."""
    if out.is_symlink():
        raise ZoeticError(f"{out}: is a link; --force empties only a real run directory")
    where = out.resolve()
    for keep in (Path.cwd().resolve(), Path.home().resolve()):
        if keep == where or where in keep.parents:
            raise ZoeticError(f"{out}: holds {keep}; --force will not empty it")
    if not any(name in RUN_FILES for name in held):
        raise ZoeticError(
            f"{out}: does not look like a zoetic run (none of record.npz, summary.json, "
            "config.toml, checkpoint.npz), so --force will not empty it; choose another --out"
        )
