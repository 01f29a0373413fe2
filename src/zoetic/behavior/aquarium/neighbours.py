"""Which targets may lie within a fish's range: a grid of square cells in the horizontal plane.

A fish perceives nothing beyond its view and smell ranges, so of a crowd's (n, m) pairs of
eyes and targets only those near each other need their distances and sight lines worked out.
The targets are binned into cells at least the range wide (x and z; height is not binned), and
each eye takes the targets of its own cell and the eight around it: every target within the
range horizontally (so every one within it in 3-D) is among them, with some farther ones that
the caller's own exact test drops. The cells are a little wider than the range, so no
rounding of a cell's index can lose a pair at the range's very edge.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from zoetic.jitcache import fresh_numba_cache

fresh_numba_cache()

SLACK = 1e-3  # m (and a thousandth of the range) the cells are wider than the range
MAX_CELLS = 256  # cells along a side of the grid at most (2 km of 8 m cells)


@njit(cache=True)
def _cells(points, x0, z0, width, nx, nz):
    """Return each point's cell (x index, z index), clipped to the grid."""
    cx = np.empty(points.shape[0], np.int64)
    cz = np.empty(points.shape[0], np.int64)
    for k in range(points.shape[0]):
        cx[k] = min(max(int(math.floor((points[k, 0] - x0) / width)), 0), nx - 1)
        cz[k] = min(max(int(math.floor((points[k, 2] - z0) / width)), 0), nz - 1)
    return cx, cz


@njit(cache=True)
def _grid_pairs(eyes, targets, width):
    """Return (rows, cols): the pairs of eye ``rows[k]`` and target ``cols[k]`` in the same or
    neighbouring cells of a grid of ``width`` m squares, each eye's targets in ascending order."""
    n, m = eyes.shape[0], targets.shape[0]
    x0 = min(eyes[:, 0].min(), targets[:, 0].min())
    z0 = min(eyes[:, 2].min(), targets[:, 2].min())
    x1 = max(eyes[:, 0].max(), targets[:, 0].max())
    z1 = max(eyes[:, 2].max(), targets[:, 2].max())
    # at most MAX_CELLS a side: a point flung far away clips to the edge cells (clipping
    # brings no two cells' indices farther apart, so no pair within range is lost)
    nx = int(min((x1 - x0) / width, MAX_CELLS - 1)) + 1
    nz = int(min((z1 - z0) / width, MAX_CELLS - 1)) + 1
    tx, tz = _cells(targets, x0, z0, width, nx, nz)
    ex, ez = _cells(eyes, x0, z0, width, nx, nz)
    # the targets sorted by cell (a stable sort: ascending within a cell), and each cell's start
    key = tx * nz + tz
    order = np.argsort(key, kind="mergesort")
    start = np.zeros(nx * nz + 1, np.int64)
    for j in range(m):
        start[key[j] + 1] += 1
    for c in range(nx * nz):
        start[c + 1] += start[c]
    count = np.zeros(n, np.int64)
    for i in range(n):
        for a in range(max(ex[i] - 1, 0), min(ex[i] + 2, nx)):
            for b in range(max(ez[i] - 1, 0), min(ez[i] + 2, nz)):
                count[i] += start[a * nz + b + 1] - start[a * nz + b]
    rows = np.empty(count.sum(), np.int64)
    cols = np.empty(count.sum(), np.int64)
    k = 0
    for i in range(n):
        k0 = k
        for a in range(max(ex[i] - 1, 0), min(ex[i] + 2, nx)):
            for b in range(max(ez[i] - 1, 0), min(ez[i] + 2, nz)):
                for q in range(start[a * nz + b], start[a * nz + b + 1]):
                    rows[k] = i
                    cols[k] = order[q]
                    k += 1
        cols[k0:k] = np.sort(cols[k0:k])
    return rows, cols


def near_pairs(
    eyes: np.ndarray, targets: np.ndarray, reach: float
) -> tuple[np.ndarray, np.ndarray]:
    """Return (rows, cols): pairs of an eye (n, 3) and a target (m, 3), every pair within
    ``reach`` m of each other among them (and some farther), by eye then target ascending.
    An infinite reach gives all the pairs."""
    eyes = np.ascontiguousarray(eyes, float).reshape(-1, 3)
    targets = np.ascontiguousarray(targets, float).reshape(-1, 3)
    n, m = len(eyes), len(targets)
    width = reach * (1.0 + SLACK) + SLACK
    finite = np.isfinite(eyes).all() and np.isfinite(targets).all()
    if n and m and math.isfinite(width) and finite:
        return _grid_pairs(eyes, targets, width)
    rows, cols = np.divmod(np.arange(n * m), max(m, 1))
    return rows, cols
