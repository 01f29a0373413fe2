"""The perception oracle: what each fish perceives of the world model, as distances.

A fish sees another fish, a food particle or an obstacle when it lies within its view volume
(``view_angle`` degrees about its heading, 300 by default, and ``view_range`` metres) and the
sight line from its eye (the nose) is not blocked by an obstacle; food is also smelled within
``smell_range`` whatever the view. Occlusion is tested by the obstacles' signed distance at
points along the sight line, at most ``STEP`` m apart. Obstacles themselves are perceived by
their nearest surface point (range and view only: a rock does not hide a rock).
Pure functions over arrays; positions (n, 3) in m with y up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from zoetic.behavior.aquarium.neighbours import near_pairs
from zoetic.jitcache import fresh_numba_cache
from zoetic.physics.shapes import half_extent

fresh_numba_cache()

STEP = 0.25  # m between occlusion probes along a sight line


@njit(cache=True)
def _sdf1(p0, p1, p2, kind, center, size, s) -> float:
    """Return the signed distance of the point (p0, p1, p2) to obstacle s."""
    q0 = p0 - center[s, 0]
    q1 = p1 - center[s, 1]
    q2 = p2 - center[s, 2]
    if kind[s] == 2:  # sphere
        return math.sqrt(q0 * q0 + q1 * q1 + q2 * q2) - size[s, 0]
    if kind[s] == 0:  # box: half sizes
        e0 = abs(q0) - size[s, 0]
        e1 = abs(q1) - size[s, 1]
        e2 = abs(q2) - size[s, 2]
        o = math.sqrt(max(e0, 0.0) ** 2 + max(e1, 0.0) ** 2 + max(e2, 0.0) ** 2)
        return o + min(max(e0, max(e1, e2)), 0.0)
    ax = int(size[s, 2])  # cylinder: radius, half length, axis
    if ax == 0:
        r, a = math.sqrt(q1 * q1 + q2 * q2), abs(q0)
    elif ax == 1:
        r, a = math.sqrt(q0 * q0 + q2 * q2), abs(q1)
    else:
        r, a = math.sqrt(q0 * q0 + q1 * q1), abs(q2)
    e0 = r - size[s, 0]
    e1 = a - size[s, 1]
    return math.sqrt(max(e0, 0.0) ** 2 + max(e1, 0.0) ** 2) + min(max(e0, e1), 0.0)


@njit(cache=True)
def _sdf(p, kind, center, size, out) -> None:
    """Fill out (P, S) with the signed distances of points p (P, 3) to the obstacles."""
    for i in range(p.shape[0]):
        for s in range(kind.shape[0]):
            out[i, s] = _sdf1(p[i, 0], p[i, 1], p[i, 2], kind, center, size, s)


@njit(cache=True)
def _bounds(kind, center, size):
    """Return (S, 3) lower and upper corners of boxes holding each obstacle (padded 1 mm)."""
    lo = np.empty((kind.shape[0], 3))
    hi = np.empty((kind.shape[0], 3))
    for s in range(kind.shape[0]):
        for c in range(3):
            h = half_extent(kind, size, s, c)
            lo[s, c] = center[s, c] - h - 1e-3
            hi[s, c] = center[s, c] + h + 1e-3
    return lo, hi


@njit(cache=True)
def _blocked(eyes, targets, ask, kind, center, size, step, out) -> None:
    """Set out[e, t] for the pairs asked (ask (n, m) bools) whose segment from eye e to
    target t is blocked (``_blocked_pairs``)."""
    rows, cols = np.nonzero(ask)
    hit = np.zeros(rows.shape[0], np.bool_)
    _blocked_pairs(eyes, targets, rows, cols, np.ones(rows.shape[0], np.bool_), kind, center,
                   size, step, hit)  # fmt: skip
    for q in range(rows.shape[0]):
        out[rows[q], cols[q]] = hit[q]


@njit(cache=True)
def _blocked_pairs(eyes, targets, rows, cols, ask, kind, center, size, step, out) -> None:
    """Set out[q] for the pairs q asked (eye rows[q], target cols[q]; ask (K,) bools) whose
    segment from the eye to the target passes inside an obstacle at one of the k - 1 inner
    points i/k (k from the longest segment asked, as ``blocked`` documents). Only the
    obstacles whose bounding box meets the segment's are probed (no point of the segment can
    lie inside the others); a segment stops at its first point inside."""
    longest = 0.0
    for q in range(rows.shape[0]):
        if ask[q]:
            e, t = rows[q], cols[q]
            a0 = targets[t, 0] - eyes[e, 0]
            a1 = targets[t, 1] - eyes[e, 1]
            a2 = targets[t, 2] - eyes[e, 2]
            longest = max(longest, math.sqrt(a0 * a0 + a1 * a1 + a2 * a2))
    k = max(2, int(math.ceil(longest / step)))
    lo, hi = _bounds(kind, center, size)
    near = np.empty(kind.shape[0], np.int64)
    # the obstacles whose bounding box comes within the longest segment of the eye (no
    # segment asked reaches farther; a margin over its rounding), for the eye asked last
    reach = longest * (1.0 + 1e-9) + 1e-9
    around, count, last = np.empty(kind.shape[0], np.int64), 0, -1
    for q in range(rows.shape[0]):
        if not ask[q]:
            continue
        e, t = rows[q], cols[q]
        if e != last:
            last, count = e, 0
            for s in range(kind.shape[0]):
                apart = False
                for c in range(3):
                    if eyes[e, c] + reach < lo[s, c] or eyes[e, c] - reach > hi[s, c]:
                        apart = True
                if not apart:
                    around[count] = s
                    count += 1
        m = 0
        for r in range(count):
            s = around[r]
            apart = False
            for c in range(3):
                if (
                    max(eyes[e, c], targets[t, c]) < lo[s, c]
                    or min(eyes[e, c], targets[t, c]) > hi[s, c]
                ):
                    apart = True
            if not apart:
                near[m] = s
                m += 1
        if m == 0:
            continue
        s0 = targets[t, 0] - eyes[e, 0]
        s1 = targets[t, 1] - eyes[e, 1]
        s2 = targets[t, 2] - eyes[e, 2]
        hit = False
        for i in range(1, k):
            u = i / k
            x0 = eyes[e, 0] + u * s0
            x1 = eyes[e, 1] + u * s1
            x2 = eyes[e, 2] + u * s2
            for r in range(m):
                if _sdf1(x0, x1, x2, kind, center, size, near[r]) < 0.0:
                    hit = True
                    break
            if hit:
                break
        out[q] = hit


@njit(cache=True)
def _deepest(p, kind, center, size) -> float:
    """Return ``deepest_inside`` of the points p (P, 3)."""
    lo, hi = _bounds(kind, center, size)
    out = 0.0
    for i in range(p.shape[0]):
        for s in range(kind.shape[0]):
            inside = True
            for c in range(3):
                if p[i, c] < lo[s, c] or p[i, c] > hi[s, c]:
                    inside = False
            if inside:
                out = max(out, -_sdf1(p[i, 0], p[i, 1], p[i, 2], kind, center, size, s))
    return out


def deepest_inside(points: np.ndarray, kind, center, size) -> float:
    """Return how deep (m) the deepest of the points (P, 3) lies inside an obstacle (0 when
    none does): minus the least signed distance (``obstacle_distance``) where it is below 0,
    the signed distances worked out only for the points within an obstacle's bounding box
    (a point outside every box is outside every obstacle)."""
    if len(kind) == 0 or len(points) == 0:
        return 0.0
    return _deepest(
        np.ascontiguousarray(points, float).reshape(-1, 3),
        np.asarray(kind, np.int64),
        np.ascontiguousarray(center, float),
        np.ascontiguousarray(size, float),
    )


def obstacle_distance(points: np.ndarray, kind, center, size) -> np.ndarray:
    """Return the signed distance (..., S) from points (..., 3) to each obstacle's surface
    (negative inside): boxes (kind 0, size = half sizes), cylinders (kind 1, size = radius,
    half length, axis index) and spheres (kind 2, size[0] = radius)."""
    pts = np.asarray(points, float)
    kind = np.asarray(kind, np.int64)
    flat = np.ascontiguousarray(pts.reshape(-1, 3))
    out = np.empty((len(flat), len(kind)))
    _sdf(flat, kind, np.ascontiguousarray(center, float), np.ascontiguousarray(size, float), out)
    return out.reshape(*pts.shape[:-1], len(kind))


def blocked(
    eyes: np.ndarray, targets: np.ndarray, kind, center, size, pairs: np.ndarray | None = None
) -> np.ndarray:
    """Return (n, m) bools: is the segment from each eye (n, 3) to each target (m, 3) blocked
    by an obstacle (probed every ``STEP`` m, the end points excluded)? Only the ``pairs``
    (n, m) asked about are tested (default all)."""
    n, m = len(eyes), len(targets)
    out = np.zeros((n, m), bool)
    if len(kind) == 0 or n == 0 or m == 0:
        return out
    ask = np.ones((n, m), bool) if pairs is None else np.ascontiguousarray(pairs, bool)
    # every pair's k - 1 points against the obstacles in one compiled loop
    _blocked(
        np.ascontiguousarray(eyes, float),
        np.ascontiguousarray(targets, float),
        ask,
        np.asarray(kind, np.int64),
        np.ascontiguousarray(center, float),
        np.ascontiguousarray(size, float),
        STEP,
        out,
    )
    return out


@njit(cache=True)
def _look(eyes, forwards, targets, i, j, cos_half, view_range):
    """Return the distance from eye i to target j and whether it lies within the eye's range
    and view cone (cos_half: the cosine of its half angle)."""
    r0 = targets[j, 0] - eyes[i, 0]
    r1 = targets[j, 1] - eyes[i, 1]
    r2 = targets[j, 2] - eyes[i, 2]
    dist = math.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
    cos = (r0 * forwards[i, 0] + r1 * forwards[i, 1] + r2 * forwards[i, 2]) / max(dist, 1e-9)
    return dist, dist <= view_range[i] and cos >= cos_half[i]


@njit(cache=True)
def _in_view(eyes, forwards, targets, cos_half, view_range, d, ok) -> None:
    """Fill d (n, m) with the distances from the eyes to the targets and ok with whether each
    lies within the eye's range and view cone (``_look``)."""
    for i in range(eyes.shape[0]):
        for j in range(targets.shape[0]):
            d[i, j], ok[i, j] = _look(eyes, forwards, targets, i, j, cos_half, view_range)


def in_view(eyes, forwards, targets, view_angle, view_range) -> tuple[np.ndarray, np.ndarray]:
    """Return (distances (n, m), visible (n, m)): within range and the view angle (degrees)."""
    eyes = np.ascontiguousarray(eyes, float).reshape(-1, 3)
    targets = np.ascontiguousarray(targets, float).reshape(-1, 3)
    n, m = len(eyes), len(targets)
    cos_half = np.broadcast_to(np.cos(np.radians(np.asarray(view_angle, float)) / 2), (n,))
    rng = np.broadcast_to(np.asarray(view_range, float), (n,))
    d, ok = np.empty((n, m)), np.empty((n, m), bool)
    _in_view(
        eyes,
        np.ascontiguousarray(np.broadcast_to(forwards, (n, 3)), float),
        targets,
        np.ascontiguousarray(cos_half),
        np.ascontiguousarray(rng),
        d,
        ok,
    )
    return d, ok


@dataclass(frozen=True)
class Percepts:
    """What every fish perceives: distances (inf where not perceived) to each fish (n, n),
    food particle (n, F) and obstacle surface (n, S)."""

    fish: np.ndarray
    food: np.ndarray
    obstacles: np.ndarray


def perceive(
    eyes: np.ndarray,
    forwards: np.ndarray,
    fish_centers: np.ndarray,
    alive: np.ndarray,
    food: np.ndarray,
    food_left: np.ndarray,
    kind,
    center,
    size,
    view_angle,
    view_range,
    smell_range,
) -> Percepts:
    """Return the oracle's percepts for n fishes (eyes, forwards, centres (n, 3)) of the live
    fishes, the food left (F, 3) and the obstacles (packed as ``physics.objects.pack_statics``,
    spheres as kind 2); view_angle, view_range, smell_range are per fish (n,) or scalars."""
    n = len(eyes)
    cos_half = np.cos(np.radians(np.broadcast_to(np.asarray(view_angle, float), (n,))) / 2)
    vr = np.broadcast_to(np.asarray(view_range, float), (n,))
    sr = np.broadcast_to(np.asarray(smell_range, float), (n,))
    food = np.asarray(food, float).reshape(-1, 3)
    fish, food_d = np.empty((n, len(fish_centers))), np.empty((n, len(food)))
    kind = np.asarray(kind, np.int64)
    obst = np.empty((n, len(kind)))
    eyes = np.ascontiguousarray(eyes, float)
    fish_centers = np.ascontiguousarray(fish_centers, float)
    # only the pairs within range: nothing farther is seen or smelled (``neighbours``)
    fish_pairs = near_pairs(eyes, fish_centers, float(vr.max(initial=0.0)))
    food_pairs = near_pairs(eyes, food, float(max(vr.max(initial=0.0), sr.max(initial=0.0))))
    _perceive(
        eyes,
        np.ascontiguousarray(forwards, float),
        fish_centers,
        np.asarray(alive, bool),
        food,
        np.asarray(food_left, bool).reshape(-1),
        fish_pairs,
        food_pairs,
        kind,
        np.ascontiguousarray(center, float).reshape(-1, 3),
        np.ascontiguousarray(size, float).reshape(-1, 3),
        np.ascontiguousarray(cos_half),
        np.ascontiguousarray(vr),
        np.ascontiguousarray(sr),
        STEP,
        fish,
        food_d,
        obst,
    )
    return Percepts(fish, food_d, obst)


@njit(cache=True)
def _seen(eyes, forwards, targets, present, rows, cols, kind, center, size, cos_half, vr, step):
    """Return for the pairs (eye rows[q], target cols[q]) the distances from the eye to the
    target and whether the target is seen: present, within the eye's range and view cone,
    and not hidden by an obstacle."""
    d, seen = np.empty(rows.shape[0]), np.empty(rows.shape[0], np.bool_)
    for q in range(rows.shape[0]):
        d[q], seen[q] = _look(eyes, forwards, targets, rows[q], cols[q], cos_half, vr)
        seen[q] = seen[q] and present[cols[q]]
    hid = np.zeros(rows.shape[0], np.bool_)
    _blocked_pairs(eyes, targets, rows, cols, seen, kind, center, size, step, hid)
    for q in range(rows.shape[0]):
        seen[q] = seen[q] and not hid[q]
    return d, seen


@njit(cache=True)
def _perceive(
    eyes,
    forwards,
    centers,
    alive,
    food,
    left,
    fish_pairs,
    food_pairs,
    kind,
    center,
    size,
    cos_half,
    vr,
    sr,
    step,
    fish,
    food_d,
    obst,
) -> None:
    """``perceive`` compiled: fill fish (n, n), food_d (n, F) and obst (n, S) with the
    distances perceived (inf where not), testing only the pairs ``fish_pairs`` and
    ``food_pairs`` (rows, cols: every pair within range among them)."""
    n = eyes.shape[0]
    rows, cols = fish_pairs
    df, vf = _seen(
        eyes, forwards, centers, alive, rows, cols, kind, center, size, cos_half, vr, step
    )
    fish[:, :] = np.inf
    for q in range(rows.shape[0]):
        if vf[q] and rows[q] != cols[q]:
            fish[rows[q], cols[q]] = df[q]
    food_d[:, :] = np.inf
    rows, cols = food_pairs
    if food.shape[0]:
        dd, vd = _seen(
            eyes, forwards, food, left, rows, cols, kind, center, size, cos_half, vr, step
        )
        for q in range(rows.shape[0]):
            i, j = rows[q], cols[q]
            if (vd[q] or dd[q] <= sr[i]) and left[j]:
                food_d[i, j] = dd[q]
    for i in range(n):
        for s in range(kind.shape[0]):
            # the nearest surface point of each obstacle, seen from the eye
            do = _sdf1(eyes[i, 0], eyes[i, 1], eyes[i, 2], kind, center, size, s)
            c0 = center[s, 0] - eyes[i, 0]
            c1 = center[s, 1] - eyes[i, 1]
            c2 = center[s, 2] - eyes[i, 2]
            cos = (c0 * forwards[i, 0] + c1 * forwards[i, 1] + c2 * forwards[i, 2]) / max(
                math.sqrt(c0 * c0 + c1 * c1 + c2 * c2), 1e-9
            )
            seen = do <= vr[i] and (cos >= cos_half[i] or do < 1.0)
            obst[i, s] = do if seen else np.inf
