"""Numba kernel for the balls' own motion: gravity, the buoyancy of the submerged cap, drag
against the current and the force the animals put on them, then their contacts with the floor
and the fixed shapes (``contacts.solve``). Layout as ``contacts``: balls (K, 3, B) float64.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from zoetic.jitcache import fresh_numba_cache
from zoetic.physics.contacts import contact_rows, restitution, solve
from zoetic.physics.lane_memo import recalled, remember
from zoetic.physics.media import DRAG, FLOOR, LEVEL, G

fresh_numba_cache()


@njit(cache=True)
def balls_step(
    bpos, bvel, bpar, bforce, med, current, skind, scenter, ssize, dt, steps, w, zeta, mu
):
    """Advance the balls ``steps`` steps: gravity, buoyancy of the submerged cap, drag
    against the current and the constant force ``bforce``, then their contacts with the
    floor and the fixed shapes (``solve``; w and zeta as in ``node_contacts``).

    A lane's ball whose position, velocity and force are those of a lane stepped before it,
    to the bit, takes that lane's new position and velocity (``recalled``)."""
    g = med[G]
    level = med[LEVEL]
    water = med[DRAG] > 0.0 and level > -1e8
    floor = med[FLOOR] > 0.0
    drag = med[DRAG]
    e = restitution(zeta)
    rate = w * dt / math.pi
    rows = contact_rows(0, skind.shape[0])
    nothing = (  # no nodes: a ball's own step solves it with the fixed shapes alone
        np.zeros((0, 3, 1), dtype=np.float32), np.zeros(0), np.zeros((0, 1, 3, 1)),
    )  # fmt: skip
    # each ball's states and forces in the lanes stepped, and their new states (``recalled``)
    memo = np.empty((bpos.shape[0], bpos.shape[2], 15))
    seen = np.zeros(bpos.shape[0], np.int64)
    for b in range(bpos.shape[2]):
        for k in range(bpos.shape[0]):
            was = (
                bpos[k, 0, b], bpos[k, 1, b], bpos[k, 2, b],
                bvel[k, 0, b], bvel[k, 1, b], bvel[k, 2, b],
                bforce[k, 0, b], bforce[k, 1, b], bforce[k, 2, b],
            )  # fmt: skip
            q = recalled(memo, k, seen, was)
            if q >= 0:
                for j in range(3):
                    bpos[k, j, b] = memo[k, q, 9 + j]
                    bvel[k, j, b] = memo[k, q, 12 + j]
                continue
            _lane_steps(
                bpos, bvel, bpar, bforce, k, b, g, level, water, floor, drag, current, skind,
                scenter, ssize, e, rate, dt, steps, mu, rows, nothing,
            )  # fmt: skip
            q = remember(memo, k, seen, was)
            for j in range(3 if q >= 0 else 0):
                memo[k, q, 9 + j] = bpos[k, j, b]
                memo[k, q, 12 + j] = bvel[k, j, b]


@njit(cache=True, inline="always")
def _lane_steps(
    bpos, bvel, bpar, bforce, k, b, g, level, water, floor, drag, current, skind, scenter,
    ssize, e, rate, dt, steps, mu, rows, nothing,
):  # fmt: skip
    """Ball k of lane b through ``steps`` steps (``balls_step``)."""
    no_pos, no_mass, no_impulse = nothing
    r = bpar[k, 0]
    mb = bpar[k, 1]
    kd = bpar[k, 3] * drag * math.pi * r * r
    for _ in range(steps):
        x, y, z = bpos[k, 0, b], bpos[k, 1, b], bpos[k, 2, b]
        fy = bforce[k, 1, b] - mb * g
        frac = 0.0
        if water:
            h = min(max(level - (y - r), 0.0), 2.0 * r)
            frac = h * h * (3.0 * r - h) / (4.0 * r * r * r)
            fy += frac * bpar[k, 2] * mb * g
        vx = bvel[k, 0, b] + dt * bforce[k, 0, b] / mb
        vy = bvel[k, 1, b] + dt * fy / mb
        vz = bvel[k, 2, b] + dt * bforce[k, 2, b] / mb
        vx, vy, vz, _ = solve(
            x,
            y,
            z,
            r,
            mb,
            vx,
            vy,
            vz,
            0,
            0,
            no_pos,
            no_pos,
            no_mass,
            0.0,
            skind,
            scenter,
            ssize,
            floor,
            e,
            rate,
            dt,
            mu,
            no_impulse,
            0,
            rows,
        )
        if water and frac > 0.0:
            # quadratic drag of the submerged part, at most stopping the relative motion
            rx = vx - current[0]
            ry = vy - current[1]
            rz = vz - current[2]
            c = min(dt * kd * frac * math.sqrt(rx * rx + ry * ry + rz * rz) / mb, 1.0)
            vx -= c * rx
            vy -= c * ry
            vz -= c * rz
        bvel[k, 0, b] = vx
        bvel[k, 1, b] = vy
        bvel[k, 2, b] = vz
        bpos[k, 0, b] = x + dt * vx
        bpos[k, 1, b] = y + dt * vy
        bpos[k, 2, b] = z + dt * vz
