"""Numba kernels of the SAN world: per control tick the world does little Python work.

One call reads all sensors, one checks for a fall, one maps commands to servo targets, and for
the top-view media one call per physics step applies the water drag or the crawler's floor
friction (see ``world`` for the physics they implement).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from zoetic.jitcache import fresh_numba_cache

fresh_numba_cache()

__all__ = [
    "ANGLE",
    "CRAWL_V0",
    "EYE",
    "LENGTH",
    "TOUCH",
    "command",
    "fallen",
    "medium_forces",
    "sense",
]

ANGLE, LENGTH, TOUCH, EYE = 0, 1, 2, 3  # sensor kinds in the sensor table
CRAWL_V0 = 0.02  # m/s, smoothing speed of the crawler's friction


@njit(cache=True)
def sense(qpos, xpos, xmat, itab, ftab, gx, gz, fp, lo, hi, raw, out):  # pragma: no cover
    """Fill ``out`` (S,) with the binary sensors; ``raw`` gets the readings."""
    for s in range(raw.size):
        raw[s] = np.inf
    for k in range(itab.shape[0]):
        kind, i, s = itab[k, 0], itab[k, 1], itab[k, 2]
        if kind == ANGLE:
            raw[s] = (qpos[i] + np.pi) % (2 * np.pi) - np.pi
        elif kind == LENGTH:
            raw[s] = qpos[i] + ftab[k, 3]
        elif kind == TOUCH:
            px, pz = ftab[k, 0], ftab[k, 1]
            z = xpos[i, 2] + xmat[i, 6] * px + xmat[i, 8] * pz - ftab[k, 2]
            if gx.size > 0:
                z -= np.interp(xpos[i, 0] + xmat[i, 0] * px + xmat[i, 2] * pz, gx, gz)
            if z < raw[s]:
                raw[s] = z
        elif fp.size == 2:  # eye; without a follow point it sees nothing
            at = ftab[k, 0]
            ex = xpos[i, 0] + xmat[i, 0] * at
            ez = xpos[i, 2] + xmat[i, 6] * at
            a = np.arctan2(fp[1] - ez, fp[0] - ex) - np.arctan2(xmat[i, 6], xmat[i, 0])
            raw[s] = (a + np.pi) % (2 * np.pi) - np.pi
    for s in range(raw.size):
        out[s] = lo[s] <= raw[s] and raw[s] <= hi[s]


@njit(cache=True)
def fallen(xpos, xmat, fbody, fpts, gx, gz, clear, root, angle0, tilt):  # pragma: no cover
    """Return True when a fall probe touches the ground or the root tilts past ``tilt``."""
    for k in range(fbody.size):
        i = fbody[k]
        px, pz = fpts[k, 0], fpts[k, 1]
        z = xpos[i, 2] + xmat[i, 6] * px + xmat[i, 8] * pz - fpts[k, 2]
        if gx.size > 0:
            z -= np.interp(xpos[i, 0] + xmat[i, 0] * px + xmat[i, 2] * pz, gx, gz)
        if z <= clear:
            return True
    if tilt > 0:
        a = np.arctan2(xmat[root, 6], xmat[root, 0]) - angle0
        if abs((a + np.pi) % (2 * np.pi) - np.pi) > tilt:
            return True
    return False


@njit(cache=True)
def command(u, lo, span, off, target, ctrl):  # pragma: no cover
    """Map commands u (clipped to [-2, 2], NaN as 0) onto [lo, hi]; servo ctrl = target - off."""
    for a in range(target.size):
        v = u[a]
        v = 0.0 if v != v else min(max(v, -2.0), 2.0)  # NaN -> the middle of the range
        target[a] = lo[a] + (v + 2.0) * 0.25 * span[a]
        ctrl[a] = target[a] - off[a]


@njit(cache=True)
def medium_forces(
    body, cvel, xipos, xmat, com, xfrc, water, wn, wt, wrot, root, load, mu
):  # pragma: no cover
    """Apply the water drag or the crawler's anisotropic floor friction to each link."""
    hx, hz = xmat[root, 0], xmat[root, 6]
    for k in range(body.size):
        b = body[k]
        w = cvel[b, 1]
        vx = cvel[b, 3] + w * (xipos[b, 2] - com[2])
        vz = cvel[b, 5] - w * (xipos[b, 0] - com[0])
        if water:
            tx, tz, nx, nz = xmat[b, 0], xmat[b, 6], xmat[b, 2], xmat[b, 8]
            vt = vx * tx + vz * tz
            vn = vx * nx + vz * nz
            xfrc[b, 0] = -wt[k] * vt * tx - wn[k] * vn * nx
            xfrc[b, 2] = -wt[k] * vt * tz - wn[k] * vn * nz
            xfrc[b, 4] = -wrot[k] * w
        else:
            va = vx * hx + vz * hz
            vl = -vx * hz + vz * hx
            fa = -(mu[0] if va > 0 else mu[1]) * load[k] * np.tanh(va / CRAWL_V0)
            fl = -mu[2] * load[k] * np.tanh(vl / CRAWL_V0)
            xfrc[b, 0] = fa * hx - fl * hz
            xfrc[b, 2] = fa * hz + fl * hx
