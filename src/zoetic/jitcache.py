"""Numba's on-disk kernel cache, kept fresh across modules.

Numba checks a cached kernel only against the source file that defines it, yet a kernel holds
compiled copies of what it calls or inlines from other modules (``kernel`` inlines
``kernel_terms``; ``broadphase.near`` inlines ``shapes.node_box``) and the values of the
module constants it reads (``media.G``). Edit one of those alone and Numba goes on serving the
old machine code. ``fresh_numba_cache`` closes that gap: one digest of every module that
defines compiled code and of every zoetic module they import (``SOURCES``) is kept in a stamp
file beside each kernel directory's Numba cache; when the sources no longer match it, that
cache's index (``.nbi``) and data (``.nbc``) files of the kernel modules are removed, so the
next call compiles afresh. Every module that imports Numba calls it before defining a kernel
(``tests/test_jitcache.py`` holds the list and the calls to the source tree).

The check never fails a run: a cache it cannot read or write is left to Numba. Two processes
starting at once can at worst both clear the cache (one more compile); stamps are written
whole (temporary file, then rename) and Numba tolerates a data file removed under it.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterable
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent

# Modules that import Numba at module level (they define compiled code), package-relative.
KERNELS = (
    "behavior/aquarium/neighbours.py",
    "behavior/aquarium/perception.py",
    "control/blend.py",
    "perception/kernels.py",
    "physics/balls.py",
    "physics/bodycontact.py",
    "physics/broadphase.py",
    "physics/contacts.py",
    "physics/food.py",
    "physics/kernel.py",
    "physics/kernel_terms.py",
    "physics/lane_memo.py",
    "physics/lanes.py",
    "physics/noalias.py",
    "physics/shapes.py",
    "physics/stepping.py",
    "render/raster.py",
    "san/kernels.py",
)
# The zoetic modules those import at module level: kernels read their constants, frozen into
# the machine code when it is compiled.
IMPORTED = (
    "bodies/__init__.py",
    "errors.py",
    "physics/media.py",
    "physics/model.py",
    "physics/objects.py",
    "physics/simulate.py",
)
SOURCES = KERNELS + IMPORTED
STAMP = "zoetic-sources.stamp"  # in each kernel directory's Numba cache: the sources' digest

_checked = False


def fresh_numba_cache() -> None:
    """Clear zoetic's cached Numba kernels if any covered source changed (once a process)."""
    global _checked
    if _checked:
        return
    _checked = True
    refresh([PACKAGE / p for p in SOURCES], [PACKAGE / p for p in KERNELS])


def refresh(sources: Iterable[Path], kernels: Iterable[Path]) -> list[Path]:
    """Return the Numba cache directories of ``kernels`` whose stamp did not match the digest
    of ``sources``, after removing those kernels' cached files there and stamping them anew."""
    try:
        digest = source_digest(sources)
    except OSError:  # a source unreadable: Numba's own per-file check is all there is
        return []
    by_dir: dict[Path, list[str]] = {}
    for kernel in kernels:
        by_dir.setdefault(kernel.parent, []).append(kernel.stem)
    cleared = []
    for source_dir, stems in sorted(by_dir.items()):
        cache = numba_cache_dir(source_dir)
        if cache is not None and _refresh_dir(cache, stems, digest):
            cleared.append(cache)
    return cleared


def source_digest(sources: Iterable[Path], salt: str = "") -> str:
    """Return the SHA-256 (hex) of ``salt`` and the named files' paths (relative to the
    package where they lie in it) and contents, in sorted order."""
    h = hashlib.sha256(salt.encode())
    for path in sorted(sources):
        data = path.read_bytes()
        name = path.relative_to(PACKAGE) if path.is_relative_to(PACKAGE) else path.name
        h.update(f"{name}\0{len(data)}\0".encode())
        h.update(data)
    return h.hexdigest()


def numba_cache_dir(source_dir: Path) -> Path | None:
    """Return the directory where Numba caches the kernels of modules in ``source_dir``, by
    Numba's own choice: NUMBA_CACHE_DIR when set, else the in-tree ``__pycache__`` when it is
    writable, else the user-wide cache; None when none can be written."""
    from numba.core import config

    source_dir = Path(os.path.abspath(source_dir))
    if config.CACHE_DIR:
        return _writable(Path(config.CACHE_DIR) / _subpath(source_dir))
    in_tree = _writable(source_dir / "__pycache__")
    if in_tree is not None:
        return in_tree
    from numba.misc.appdirs import AppDirs

    user_wide = Path(AppDirs(appname="numba", appauthor=False).user_cache_dir)
    return _writable(user_wide / _subpath(source_dir))


def _subpath(source_dir: Path) -> str:
    """Return Numba's name for a source directory's folder inside a shared cache directory."""
    digest = hashlib.sha1(str(source_dir).encode()).hexdigest()
    return f"{source_dir.name}_{digest}"


def _writable(path: Path) -> Path | None:
    """Return ``path`` once it exists as a directory this process may write, else None."""
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    return path if os.access(path, os.W_OK | os.X_OK) else None


def _refresh_dir(cache: Path, stems: list[str], digest: str) -> bool:
    """Return whether ``cache`` was stale: if its stamp is not ``digest``, remove the cached
    index and data files of the modules named ``stems`` and write the new stamp."""
    stamp = cache / STAMP
    try:
        if stamp.read_text() == digest:
            return False
    except (OSError, UnicodeDecodeError):
        pass  # no stamp yet (or unreadable): whatever is cached may be stale
    tmp = cache / f"{STAMP}.tmp.{os.urandom(8).hex()}"  # unique per writer
    try:
        for entry in os.scandir(cache):
            name = entry.name
            if name.endswith((".nbi", ".nbc")) and name.split(".", 1)[0] in stems:
                _remove(entry.path)
        tmp.write_text(digest)
        os.replace(tmp, stamp)
    except OSError:  # read-only or vanished: leave it to Numba
        _remove(str(tmp))
        return False
    return True


def _remove(path: str) -> None:
    """Remove a file if it is there (another process may have removed it first)."""
    try:
        os.unlink(path)
    except OSError:
        pass
