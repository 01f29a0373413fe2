"""A world's broad phase: which animals may touch what in the coming slice, and so how it is
stepped.

Contacts are resolved every time step, but only while some node is within reach of an object
or of another animal; far from everything the animals run whole slices through the kernel at
full speed. The decision for a slice of the world's grid is taken once, at the first step of
the slice stepped, and kept however the calls split the slice (``World.step``): ``lockstep``
(every animal one step at a time with its contacts: balls couple everything, or some node is
near a shape), ``apart`` (no balls couple the animals: each near a fixed shape, or near another
animal, steps one step at a time, the others the whole slice at once) or ``free``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from zoetic.jitcache import fresh_numba_cache
from zoetic.physics.bodycontact import close_among, close_pairs
from zoetic.physics.objects import Solids
from zoetic.physics.shapes import node_box, shape_apart, shape_sdf

fresh_numba_cache()

Plan = tuple[str, list[tuple[int, int]], np.ndarray | None]


@njit(cache=True)
def near(pos, vel, radius, bpos, bvel, bpar, skind, scenter, ssize, horizon):
    """Return True if any node could touch any ball or fixed shape within ``horizon`` s.

    A shape whose bounding box lies farther than the reach from the box of the animal's
    nodes along some axis is not tested node by node (no node can come within reach of it)."""
    n_nodes = pos.shape[0]
    some = np.empty(skind.shape[0], np.int64)  # the shapes tested node by node
    for b in range(pos.shape[2]):
        vmax = 0.0
        for i in range(n_nodes):
            v2 = vel[i, 0, b] ** 2 + vel[i, 1, b] ** 2 + vel[i, 2, b] ** 2
            vmax = max(vmax, v2)
        bmax = 0.0
        for k in range(bpos.shape[0]):
            v2 = bvel[k, 0, b] ** 2 + bvel[k, 1, b] ** 2 + bvel[k, 2, b] ** 2
            bmax = max(bmax, v2)
        # twice the current speeds over the horizon, plus a few cm: a conservative reach
        reach = 2.0 * (math.sqrt(vmax) + math.sqrt(bmax)) * horizon + radius + 0.05
        n_some = _shapes_within(pos, b, skind, scenter, ssize, reach, some)
        if n_some == 0 and bpos.shape[0] == 0:
            continue
        for i in range(n_nodes):
            px, py, pz = pos[i, 0, b], pos[i, 1, b], pos[i, 2, b]
            for k in range(bpos.shape[0]):
                dx = px - bpos[k, 0, b]
                dy = py - bpos[k, 1, b]
                dz = pz - bpos[k, 2, b]
                if dx * dx + dy * dy + dz * dz < (bpar[k, 0] + reach) ** 2:
                    return True
            for q in range(n_some):
                d, _, _, _ = shape_sdf(some[q], skind, scenter, ssize, px, py, pz)
                if d < reach:
                    return True
    return False


@njit(cache=True, inline="always")
def _shapes_within(pos, b, skind, scenter, ssize, reach, out) -> int:
    """Put into ``out`` the fixed shapes whose bounding box comes within ``reach`` (plus a
    micrometre, against rounding) of the box of the nodes pos (N, 3, B) in lane b along every
    axis; return how many. A point farther than that from a shape's box along one axis is
    farther from the shape (its signed distance is at least the gap)."""
    box = node_box(pos, b, 0.0)
    pad = reach + 1e-6
    k = 0
    for s in range(skind.shape[0]):
        if shape_apart(box, s, skind, scenter, ssize, pad):
            continue
        out[k] = s
        k += 1
    return k


@njit(cache=True)
def near_each(pos, vel, off, radius, bpos, bvel, bpar, skind, scenter, ssize, horizon, out):
    """Fill out (animals,) with ``near`` of each animal (rows off[a]:off[a + 1] of
    pos and vel): could any of its nodes touch a ball or fixed shape within ``horizon`` s."""
    for a in range(off.shape[0] - 1):
        o0, o1 = off[a], off[a + 1]
        out[a] = near(
            pos[o0:o1], vel[o0:o1], radius, bpos, bvel, bpar, skind, scenter, ssize, horizon
        )


class BroadPhase:
    """The decisions of a world's broad phase over its animals' state (pos, vel (N_total, 3,
    B), animal a in rows off[a]:off[a + 1], its ``views[a]``) and its ``solids``; ``reach``:
    each animal's ``bodycontact.surface_reach``; ``touchy``: animals push each other."""

    def __init__(
        self,
        pos,
        vel,
        off,
        views,
        reach: list[float],
        node_radius: float,
        dt: float,
        solids: Solids,
        touchy: bool,
    ) -> None:
        self.pos, self.vel, self.off, self.views = pos, vel, off, views
        self.reach = reach
        self.reach_arr = np.array(reach, float)
        self.node_radius = node_radius
        self.dt = dt
        self.solids = solids
        self.touchy = touchy
        self.plan: tuple[int, Plan] | None = None  # the slice ending at plan[0] and its plan
        self.sub: tuple[int, np.ndarray] | None = None  # the sub-slice ending at sub[0], its pairs

    def forget(self) -> None:
        """Decide afresh from here (after a restore)."""
        self.plan = self.sub = None

    def decide(self, end: int, now: int) -> Plan:
        """Return the plan for the world's slice that ends at step ``end`` (the world is at
        step ``now``): how it is stepped (``lockstep``, ``apart`` or ``free``), the pairs of
        animals that may touch, and which animals are near a ball or a fixed shape (for
        ``apart``). Decided once, at the first step of the slice stepped (its start, or where
        a restore left the clock), and kept however the calls split the slice."""
        if self.plan is not None and self.plan[0] == end:
            return self.plan[1]
        horizon = (end - now) * self.dt
        pairs = self.close_pairs(horizon) if self.touchy else []
        near_now = None
        balls = len(self.solids.balls)
        if pairs and balls:
            mode = "lockstep"
        elif pairs or (self.solids.any and not balls and len(self.views) > 1):
            # no balls couple the animals: only those near a fixed shape step one step at a
            # time with contacts, the others the whole slice in one kernel call
            mode = "apart"
            near_now = np.zeros(len(self.views), bool)
            s = self.solids
            near_each(
                self.pos,
                self.vel,
                self.off,
                self.node_radius,
                s.pos,
                s.vel,
                s.par,
                s.kind,
                s.center,
                s.size,
                horizon,
                near_now,
            )
        elif self.solids.any and self.any_near(horizon):
            mode = "lockstep"
        else:
            mode = "free"
        self.plan = (end, (mode, pairs, near_now))
        return self.plan[1]

    def close_now(self, pairs: list[tuple[int, int]], end: int, now: int) -> np.ndarray:
        """Return those of ``pairs`` (as rows (P, 2), in order) that may touch before step
        ``end`` of the sub-slice that ends there (the world at step ``now``), decided once
        per sub-slice (``close`` for each, in one call)."""
        if self.sub is None or self.sub[0] != end:
            horizon = (end - now) * self.dt
            rows = np.array(pairs, np.int64).reshape(-1, 2)
            keep = close_among(
                self.pos, self.vel, self.off, rows, self.reach_arr, self.node_radius, horizon
            )
            self.sub = (end, rows[keep])
        return self.sub[1]

    def close_pairs(self, horizon: float) -> list[tuple[int, int]]:
        """Return the pairs of animals that may touch within ``horizon`` s (every pair in one
        kernel call, ``close`` for each)."""
        found = close_pairs(self.pos, self.vel, self.off, self.reach_arr, self.node_radius, horizon)
        return [(int(a), int(c)) for a, c in found]

    def any_near(self, horizon: float) -> bool:
        """Return True if some node of some animal could touch a ball or a fixed shape within
        ``horizon`` s."""
        s = self.solids
        for p, v in self.views:
            if near(p, v, self.node_radius, s.pos, s.vel, s.par, s.kind, s.center, s.size, horizon):
                return True
        return False
