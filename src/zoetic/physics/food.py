"""A world's food: particles drifting with the current, eaten by a head that passes close.

The world tests the food at the steps of its own grid (``world.MAX_SLICE``), never per call, so
that splitting a call's steps changes nothing: at each mark the food drifts with the current
since the last mark, and a particle is eaten when some head's path since then, relative to the
particle (a straight segment), came within its radius.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from zoetic.jitcache import fresh_numba_cache
from zoetic.physics.objects import Food

fresh_numba_cache()


@njit(cache=True)
def eaten_on_path(h0, h1, f0, f1, radius, eaten) -> None:
    """Mark eaten (B, F) the food particles (before f0, after f1: (B, F, 3)) that a head
    (before h0, after h1: (animals, B, 3)) came within ``radius`` (F,) of during the slice:
    the closest point of the head's path relative to the particle (a straight segment).

    Only the heads whose start lies within a particle's radius plus the farthest any path
    moved (along x, heads sorted by x) are tested: the closest point of a path moved no
    farther along x than that, so the others cannot come within the radius."""
    for b in range(f0.shape[0]):
        xs = h0[:, b, 0].copy()
        order = np.argsort(xs)
        xs = xs[order]
        move = 0.0  # the farthest any relative path moves along a coordinate (NaN: skipped)
        for a in range(h0.shape[0]):
            for k in range(3):
                m = abs(h1[a, b, k] - h0[a, b, k])
                move = m if m > move else move
        drift = 0.0
        for q in range(f0.shape[1]):
            for k in range(3):
                m = abs(f1[b, q, k] - f0[b, q, k])
                drift = m if m > drift else drift
        for q in range(f0.shape[1]):
            if eaten[b, q]:
                continue
            reach = radius[q] + move + drift + 1e-6
            lo = np.searchsorted(xs, f0[b, q, 0] - reach)
            hi = np.searchsorted(xs, f0[b, q, 0] + reach, side="right")
            for i in range(lo, hi):
                if _passes(h0, h1, f0, f1, radius, order[i], b, q):
                    eaten[b, q] = True
                    break


@njit(cache=True, inline="always")
def _passes(h0, h1, f0, f1, radius, a, b, q) -> bool:
    """Return True if head a's path in lane b came within radius[q] of particle q."""
    a0 = h0[a, b, 0] - f0[b, q, 0]
    a1 = h0[a, b, 1] - f0[b, q, 1]
    a2 = h0[a, b, 2] - f0[b, q, 2]
    d0 = (h1[a, b, 0] - f1[b, q, 0]) - a0
    d1 = (h1[a, b, 1] - f1[b, q, 1]) - a1
    d2 = (h1[a, b, 2] - f1[b, q, 2]) - a2
    s = -(a0 * d0 + a1 * d1 + a2 * d2) / ((d0 * d0 + d1 * d1 + d2 * d2) + 1e-12)
    s = min(max(s, 0.0), 1.0)
    c0 = a0 + s * d0
    c1 = a1 + s * d1
    c2 = a2 + s * d2
    closest = math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
    return math.isfinite(closest) and closest < radius[q]


class Pantry:
    """The food particles of B lanes: where they lay at the last mark (a step of the world's
    grid), drifting with ``current`` (m/s) since, and which have been eaten."""

    def __init__(self, foods: list[Food], batch: int, current: np.ndarray, dt: float) -> None:
        self.current = current
        self.dt = dt
        self.at_mark = np.zeros((batch, len(foods), 3))  # (B, F, 3) m
        self.radius = np.array([f.radius for f in foods], float)
        self.eaten = np.zeros((batch, len(foods)), dtype=bool)
        self.mark = 0  # the step of the last mark
        self.mark_heads: np.ndarray | None = None  # the heads there (animals, B, 3)

    def positions(self, step: int) -> np.ndarray:
        """Return the particles (B, F, 3) at ``step`` (a copy): as at the mark, drifted since."""
        if step == self.mark:
            return self.at_mark.copy()
        return self.at_mark + self.current * (step - self.mark) * self.dt

    def update(self, at: int, heads: np.ndarray) -> None:
        """Move the mark to step ``at`` of the world's grid, where the heads (animals, B, 3)
        now are: the food drifts there, and what the heads' paths since passed is eaten."""
        f0 = self.at_mark.copy()
        self.at_mark += self.current * (at - self.mark) * self.dt
        eaten_on_path(self.mark_heads, heads, f0, self.at_mark, self.radius, self.eaten)
        self.mark, self.mark_heads = at, heads

    def restore(self, positions, eaten, step: int, heads: np.ndarray) -> None:
        """Make particles (B, F, 3) and ``eaten`` (B, F) those of every lane at ``step``, where
        the mark moves (the heads there: (animals, B, 3))."""
        self.eaten[:] = eaten
        self.at_mark[:] = positions
        self.mark, self.mark_heads = step, heads

    def restore_lanes(self, sel, positions, eaten, step: int, heads: np.ndarray) -> None:
        """Make particles and ``eaten`` those of lanes ``sel`` at ``step`` (now); the mark stays,
        so their particles are held back by the drift since it (heads: the lanes' now)."""
        self.eaten[sel] = eaten
        drift = self.current * (step - self.mark) * self.dt
        self.at_mark[sel] = np.asarray(positions) - drift
        self.mark_heads[:, sel] = heads[:, sel]
