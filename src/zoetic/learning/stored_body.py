"""The animal a run learns, stored in its run directory (``animal.npz``) as the Body's arrays.

A run keeps the body it was given, not the name it came by: a body changed in Python
(``dataclasses.replace(shark, mass=shark.mass * 20)``) is stored as changed, and a resumed run
learns it again as itself, whatever the zoo or the animal file holds by then.
"""

from __future__ import annotations

import hashlib
import io
import json
from dataclasses import fields
from pathlib import Path

import numpy as np

from zoetic.bodies import Body
from zoetic.errors import RunDirError
from zoetic.io import atomic_write_bytes

ANIMAL_FILE = "animal.npz"
_FORMAT = "zoetic-body-1"


def _arrays(body: Body) -> tuple[dict[str, np.ndarray], dict]:
    """Return the body's arrays (string tuples as string arrays) and its plain values."""
    arrays, plain = {}, {}
    for f in fields(body):
        value = getattr(body, f.name)
        if isinstance(value, np.ndarray):
            arrays[f.name] = value
        elif isinstance(value, tuple):
            arrays[f.name] = np.array(value, dtype=np.str_).reshape(len(value))
        elif isinstance(value, np.integer | np.floating):
            plain[f.name] = value.item()
        else:
            plain[f.name] = value
    return arrays, plain


def body_digest(body: Body) -> str:
    """Return a SHA-256 over every field of the body (names, dtypes, shapes, values)."""
    arrays, plain = _arrays(body)
    h = hashlib.sha256(json.dumps(plain, sort_keys=True).encode())
    for key in sorted(arrays):
        a = np.ascontiguousarray(arrays[key])
        h.update(f"{key}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def save_body(body: Body, path: str | Path) -> Path:
    """Write the body to an .npz file (atomically); ``load_body`` reads it back equal."""
    arrays, plain = _arrays(body)
    strings = sorted(k for k, v in arrays.items() if v.dtype.kind == "U")
    meta = json.dumps({"format": _FORMAT, "plain": plain, "strings": strings})
    buf = io.BytesIO()
    np.savez(buf, __meta__=np.frombuffer(meta.encode(), np.uint8), **arrays)
    return atomic_write_bytes(Path(path), buf.getvalue())


def load_body(path: str | Path) -> Body:
    """Return the Body stored by ``save_body``; RunDirError if the file is not one."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
        meta = json.loads(data.pop("__meta__").tobytes().decode())
        if meta.get("format") != _FORMAT:
            raise ValueError(f"format {meta.get('format')!r}, not {_FORMAT!r}")
        kw: dict = dict(meta["plain"])
        for key, value in data.items():
            if key in meta["strings"]:
                kw[key] = tuple(str(s) for s in value)
            else:
                value.setflags(write=False)
                kw[key] = value
        unknown = set(kw) - {f.name for f in fields(Body)}
        if unknown:
            raise ValueError(f"fields {sorted(unknown)} are not a Body's")
        body = Body(**kw)  # a missing field is a TypeError
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise RunDirError(f"{path}: not a stored animal ({type(exc).__name__}: {exc})") from None
    return body
