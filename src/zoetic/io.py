"""Small file helpers shared by every run directory: atomic writes, JSON and TOML."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any

import tomli_w

from zoetic.errors import ZoeticError


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file and a rename; returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name + ".", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the usual permissions
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def write_json(path: str | os.PathLike, obj: Any) -> Path:
    """Write ``obj`` as indented JSON, atomically; returns the path."""
    return atomic_write_bytes(path, (json.dumps(obj, indent=2) + "\n").encode())


def read_json(path: str | os.PathLike, what: str = "file", error=ZoeticError) -> Any:
    """Return the parsed JSON in ``path``, read safely (zoetic.reader); errors are ``error``."""
    from zoetic.reader import load_json

    return load_json(path, what, error)


def write_toml(path: str | os.PathLike, obj: dict[str, Any]) -> Path:
    """Write ``obj`` as TOML, atomically; returns the path."""
    return atomic_write_bytes(path, tomli_w.dumps(obj).encode())


def read_toml(path: str | os.PathLike, what: str = "file", error=ZoeticError) -> dict[str, Any]:
    """Return the parsed TOML in ``path``, read safely (zoetic.reader); errors are ``error``."""
    from zoetic.reader import load_toml

    return load_toml(path, what, error)
