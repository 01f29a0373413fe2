"""The fixed shapes of a world (boxes and cylinders: rocks, walls, the hurdle's bar, the post)
as Numba functions: signed distance and outward normal at a point, and the penalty force a
shape puts on a node that overlaps it (spring-damper normal force and capped Coulomb friction,
``contacts``' model for nodes against fixed shapes). Packed shapes: ``objects.pack_statics``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from zoetic.jitcache import fresh_numba_cache

fresh_numba_cache()

SEPARATION_SPEED = 0.5  # m/s: the fastest a shape's push makes a node separate


@njit(cache=True, inline="always")
def _sdf(kind, cx, cy, cz, s0, s1, s2, px, py, pz):
    """Signed distance from a point to a box (kind 0) or cylinder (kind 1), and the outward
    unit normal at the nearest surface point."""
    dx = px - cx
    dy = py - cy
    dz = pz - cz
    if kind == 0:
        qx = abs(dx) - s0
        qy = abs(dy) - s1
        qz = abs(dz) - s2
        if qx < 0.0 and qy < 0.0 and qz < 0.0:
            # inside: push out through the nearest face
            if qx >= qy and qx >= qz:
                return qx, math.copysign(1.0, dx), 0.0, 0.0
            if qy >= qz:
                return qy, 0.0, math.copysign(1.0, dy), 0.0
            return qz, 0.0, 0.0, math.copysign(1.0, dz)
        ox = math.copysign(max(qx, 0.0), dx)
        oy = math.copysign(max(qy, 0.0), dy)
        oz = math.copysign(max(qz, 0.0), dz)
        d = math.sqrt(ox * ox + oy * oy + oz * oz) + 1e-12
        return d, ox / d, oy / d, oz / d
    # cylinder: s0 radius, s1 half length, s2 axis index
    ax = int(s2)
    if ax == 0:
        da, r1, r2 = dx, dy, dz
    elif ax == 1:
        da, r1, r2 = dy, dz, dx
    else:
        da, r1, r2 = dz, dx, dy
    rho = math.sqrt(r1 * r1 + r2 * r2) + 1e-12
    qr = rho - s0
    qa = abs(da) - s1
    if qr < 0.0 and qa < 0.0:
        if qr >= qa:
            na, n1, n2 = 0.0, r1 / rho, r2 / rho
            d = qr
        else:
            na, n1, n2 = math.copysign(1.0, da), 0.0, 0.0
            d = qa
    else:
        orr = max(qr, 0.0)
        oa = math.copysign(max(qa, 0.0), da)
        d = math.sqrt(orr * orr + oa * oa) + 1e-12
        na, n1, n2 = oa / d, orr * r1 / rho / d, orr * r2 / rho / d
    if ax == 0:
        return d, na, n1, n2
    if ax == 1:
        return d, n2, na, n1
    return d, n1, n2, na


@njit(cache=True, inline="always")
def half_extent(kind, size, s, c):
    """Return shape s's half-extent (m) along world axis c: a box's half-size, a cylinder's
    half length along its axis (``size[s, 2]``) and its radius across it, a sphere's (kind 2,
    the aquarium's obstacles) radius."""
    if kind[s] == 0:
        return size[s, c]
    if kind[s] == 2:
        return size[s, 0]
    return size[s, 1] if c == int(size[s, 2]) else size[s, 0]


@njit(cache=True, inline="always")
def node_box(pos, b, pad):
    """Return the bounding box (lo x, y, z, hi x, y, z) of the nodes pos (N, 3, B) in lane b,
    padded by pad (m) on every side."""
    lx = ly = lz = np.inf
    hx = hy = hz = -np.inf
    for i in range(pos.shape[0]):
        x, y, z = pos[i, 0, b], pos[i, 1, b], pos[i, 2, b]
        lx, ly, lz = min(lx, x), min(ly, y), min(lz, z)
        hx, hy, hz = max(hx, x), max(hy, y), max(hz, z)
    return lx - pad, ly - pad, lz - pad, hx + pad, hy + pad, hz + pad


@njit(cache=True, inline="always")
def box_apart(box, c0, c1, c2, h0, h1, h2, pad):
    """Return True if the box (lo x, y, z, hi x, y, z; ``node_box``) lies farther than pad
    (m) along some axis from the box of centre c and half-extents h. Every point of the one
    is then farther than pad from every point of the other. A NaN corner is never apart."""
    lx, ly, lz, hx, hy, hz = box
    return (
        lx > c0 + h0 + pad
        or hx < c0 - h0 - pad
        or ly > c1 + h1 + pad
        or hy < c1 - h1 - pad
        or lz > c2 + h2 + pad
        or hz < c2 - h2 - pad
    )


@njit(cache=True, inline="always")
def shape_apart(box, s, skind, scenter, ssize, pad):
    """``box_apart`` of a box and fixed shape s's bounding box (``half_extent``)."""
    return box_apart(
        box,
        scenter[s, 0],
        scenter[s, 1],
        scenter[s, 2],
        half_extent(skind, ssize, s, 0),
        half_extent(skind, ssize, s, 1),
        half_extent(skind, ssize, s, 2),
        pad,
    )


@njit(cache=True, inline="always")
def shape_sdf(s, skind, scenter, ssize, px, py, pz):
    """``_sdf`` of the fixed shape s of the packed shapes (``objects.pack_statics``)."""
    return _sdf(
        skind[s],
        scenter[s, 0],
        scenter[s, 1],
        scenter[s, 2],
        ssize[s, 0],
        ssize[s, 1],
        ssize[s, 2],
        px,
        py,
        pz,
    )


@njit(cache=True, inline="always")
def _penalty(pen, vx, vy, vz, nx, ny, nz, m, w, zeta, mu, dt):
    """Contact force (on the side whose relative velocity is v) along normal n: spring-damper
    normal force plus capped Coulomb friction; zero when the pair separates fast enough. The
    push never makes the side separate faster than SEPARATION_SPEED: a node that a heavy body
    drove deep into a thin shape is let out, not shot out."""
    vn = vx * nx + vy * ny + vz * nz
    fn = min(m * w * w * pen - 2.0 * zeta * m * w * vn, m * (SEPARATION_SPEED - vn) / dt)
    if fn <= 0.0:
        return 0.0, 0.0, 0.0
    tx = vx - vn * nx
    ty = vy - vn * ny
    tz = vz - vn * nz
    vt = math.sqrt(tx * tx + ty * ty + tz * tz)
    ft = min(mu * fn, m * vt / dt)
    s = ft / (vt + 1e-12)
    return fn * nx - s * tx, fn * ny - s * ty, fn * nz - s * tz


@njit(cache=True, inline="always")
def shape_force(s, skind, scenter, ssize, px, py, pz, radius, vx, vy, vz, m, w, zeta, mu, dt):
    """Penalty force of fixed shape ``s`` on a node (a sphere of ``radius`` at p moving at v;
    zero when they do not touch)."""
    d, nx, ny, nz = shape_sdf(s, skind, scenter, ssize, px, py, pz)
    pen = radius - d
    if pen <= 0.0:
        return 0.0, 0.0, 0.0
    return _penalty(pen, vx, vy, vz, nx, ny, nz, m, w, zeta, mu, dt)
