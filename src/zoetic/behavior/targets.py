"""Where tracking and planning go: targets, goals and obstacles given as text or arrays.

Targets are (x, y, z): x forward, z to the animal's left, both m from the origin where the
animal starts, and y m above the depth it starts at (0: hold the start depth; negative:
deeper).
"""

from __future__ import annotations

import numpy as np

from zoetic.errors import ZoeticError


class TrackingError(ZoeticError):
    """A tracking or planning problem is ill-posed (no targets, bad radius, empty repertoire)."""


def parse_points(text: str, per: int, what: str) -> np.ndarray:
    """Return the points of ``"a,b;c,d;..."`` as an (M, per) array; a TrackingError if malformed."""
    try:
        rows = [[float(v) for v in chunk.split(",")] for chunk in text.split(";") if chunk.strip()]
    except ValueError:
        raise TrackingError(f"{what} {text!r}: numbers expected, like '2,0;4,1.5'") from None
    if not rows or any(len(r) != per for r in rows):
        raise TrackingError(f"{what} {text!r}: each item needs {per} comma-separated numbers")
    pts = np.array(rows, float)
    if not np.all(np.isfinite(pts)):
        raise TrackingError(f"{what} {text!r}: values must be finite")
    return pts


def parse_targets(text: str, what: str = "--targets") -> np.ndarray:
    """Return the targets of ``"x,z;x,y,z;..."`` as (M, 3) x, y, z: a two-number item is a
    point at the start depth (y = 0); a TrackingError if malformed."""
    rows = []
    for chunk in (c for c in text.split(";") if c.strip()):
        n = len(chunk.split(","))
        if n not in (2, 3):
            raise TrackingError(
                f"{what} {text!r}: item {chunk.strip()!r} needs 'x,z' or 'x,y,z' (m)"
            )
        p = parse_points(chunk, n, what)[0]
        rows.append(p if n == 3 else np.array([p[0], 0.0, p[1]]))
    if not rows:
        raise TrackingError(f"{what} {text!r}: give at least one target 'x,z' or 'x,y,z'")
    return np.array(rows)


def as_targets(targets) -> np.ndarray:
    """Return targets (M, 2) x, z or (M, 3) x, y, z as (M, 3), y = 0 for the 2-number form."""
    t = np.asarray(targets, float)
    t = t.reshape(-1, t.shape[-1] if t.ndim > 1 else 2)
    if t.shape[1] == 2:
        return np.column_stack([t[:, 0], np.zeros(len(t)), t[:, 1]])
    if t.shape[1] != 3:
        raise TrackingError(f"targets must be (x, z) or (x, y, z) points, got shape {t.shape}")
    return t
