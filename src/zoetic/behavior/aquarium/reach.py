"""The way a fish must swim to reach a point: what the focuser weighs food by.

A fish turns no tighter than its sharpest turn (its turning radius times ``RADIUS_MARGIN``),
so a particle ahead is nearer by the way than a particle beside it that needs a loop. The
ways are computed over arrays: for every fish of a tank and every particle it perceives in
one step (``reach_costs``), so that a crowd of a thousand fishes weighs its food at once.
"""

from __future__ import annotations

import math

import numpy as np

RADIUS_MARGIN = 1.1  # the turning circle a fish plans with, over its calibrated sharpest turn


def hypot(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Return ``math.hypot`` of the arrays elementwise: its rounding, which ``np.hypot``'s
    differs from in the last bit now and then; the focuser picks between near-equal ways by
    these bits, so a tank's run (its record) depends on them."""
    x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
    flat = map(math.hypot, x.ravel().tolist(), y.ravel().tolist())
    return np.fromiter(flat, float, x.size).reshape(x.shape)


def frame(
    nose: np.ndarray, forward: np.ndarray, points: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Return each point relative to its fish's nose in that fish's horizontal frame: how far
    ahead, how far to the left (m). nose, forward, points (..., 3), broadcast together."""
    fx, fz = forward[..., 0], forward[..., 2]
    n = hypot(fx, fz)
    n = np.where(n == 0.0, 1.0, n)  # no horizontal heading: the raw components
    fx, fz = fx / n, fz / n
    dx, dz = points[..., 0] - nose[..., 0], points[..., 2] - nose[..., 2]
    return dx * fx + dz * fz, dz * fx - dx * fz


def way(x: np.ndarray, qy: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Return the lengths (m) of the ways to points ``x`` m ahead and ``qy`` m beside the
    centre of a turning circle of radius ``r`` on the fish's side (the fish starts at -pi/2
    on it): the arc turned to the tangent through the point, then straight on; inf inside
    the circle. Arrays broadcast together."""
    rho = hypot(x, qy)
    theta = np.arctan2(qy, x) - np.arccos(np.minimum(r / np.maximum(rho, 1e-9), 1.0))
    arc = (theta + np.pi / 2) % (2 * np.pi)
    out = r * arc + np.sqrt(np.maximum(rho * rho - r * r, 0.0))
    return np.where(rho < r, np.inf, out)


def turn_paths(
    nose: np.ndarray, forward: np.ndarray, radius: float, points: np.ndarray
) -> np.ndarray:
    """Return the lengths (m) of the shortest ways from a fish's nose (3,) heading
    ``forward`` (3,) to each point (P, 3) in the horizontal plane for a fish that turns no
    tighter than ``radius`` (times ``RADIUS_MARGIN``), as (2, P): a turn to the left, then
    straight on (row 0), and the same turning right first (row 1). A point inside the left
    turning circle cannot be reached by a left turn (inf): the fish would circle it."""
    ahead, left = frame(nose, forward, np.atleast_2d(points))
    r = RADIUS_MARGIN * radius
    return np.stack([way(ahead, left - r, r), way(ahead, -left - r, r)])


def reach_costs(
    nose: np.ndarray,
    forward: np.ndarray,
    radius: np.ndarray,
    points: np.ndarray,
    distances: np.ndarray,
) -> np.ndarray:
    """Return (n, P): how far (m) each of n fishes must swim to reach each point (P, 3)
    (``reach_pairs``), inf where ``distances`` (n, P) is (not perceived). nose, forward
    (n, 3); radius (n,) the fishes' sharpest turns (m)."""
    out = np.full(np.shape(distances), np.inf)
    ii, pp = np.nonzero(np.asarray(distances) < np.inf)  # only the pairs perceived
    out[ii, pp] = reach_pairs(nose, forward, radius, points, ii, pp)
    return out


def reach_pairs(
    nose: np.ndarray,
    forward: np.ndarray,
    radius: np.ndarray,
    points: np.ndarray,
    fish: np.ndarray,
    point: np.ndarray,
) -> np.ndarray:
    """Return (m,): how far (m) fish ``fish[k]`` must swim to reach point ``point[k]``
    (``turn_paths``' shorter way), for m pairs: what a focuser weighs, so that a particle
    ahead wins over a nearer one beside the fish that needs a loop. nose, forward (n, 3);
    radius (n,) the fishes' sharpest turns (m); points (P, 3)."""
    if not len(fish):
        return np.zeros(0)
    ahead, left = frame(nose[fish], forward[fish], points[point])
    r = RADIUS_MARGIN * np.asarray(radius, float)[fish]
    return np.minimum(way(ahead, left - r, r), way(ahead, -left - r, r))
