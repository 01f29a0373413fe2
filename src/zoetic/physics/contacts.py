"""Numba kernels for a world's passive objects: animal-object contacts and the balls' motion.

Contacts are penalty forces whose stiffness comes from the pair's reduced mass m and the
time step: k = m w^2 and damping 2 zeta m w with w = pi / (contact_steps dt), so a contact
lasts about ``contact_steps`` steps and stays stable whatever the masses. Friction is Coulomb,
capped so that it can at most stop the sliding in one step. Every force acts on both sides
(node and ball get equal and opposite impulses); a fixed shape absorbs its side.

Layouts follow the animal kernel: node arrays (N, 3, B) float32, balls (K, 3, B) float64.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from zoetic.physics.kernel import DRAG, FLOOR, LEVEL, G


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
def _penalty(pen, vx, vy, vz, nx, ny, nz, m, w, zeta, mu, dt):
    """Contact force (on the side whose relative velocity is v) along normal n: spring-damper
    normal force plus capped Coulomb friction; zero when the pair separates fast enough."""
    vn = vx * nx + vy * ny + vz * nz
    fn = m * w * w * pen - 2.0 * zeta * m * w * vn
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
def _shape_force(s, skind, scenter, ssize, px, py, pz, radius, vx, vy, vz, m, w, zeta, mu, dt):
    """Contact force of fixed shape ``s`` on a sphere of ``radius`` at p moving at v (zero
    when they do not touch): one definition for the nodes and the balls."""
    d, nx, ny, nz = _sdf(
        skind[s], scenter[s, 0], scenter[s, 1], scenter[s, 2],
        ssize[s, 0], ssize[s, 1], ssize[s, 2], px, py, pz,
    )  # fmt: skip
    pen = radius - d
    if pen <= 0.0:
        return 0.0, 0.0, 0.0
    return _penalty(pen, vx, vy, vz, nx, ny, nz, m, w, zeta, mu, dt)


@njit(cache=True)
def node_contacts(
    pos, vel, mass, radius, bpos, bvel, bpar, skind, scenter, ssize,
    ball_obj, static_obj, dt, w, zeta, mu, bforce, impulse,
):  # fmt: skip
    """Apply one step's contact impulses between an animal's nodes and the objects.

    Node velocities change in place (v += dt F / m, the same as adding F to the step's
    forces); the balls' forces accumulate in ``bforce`` (K, 3, B); each node's impulse from
    each object accumulates in ``impulse`` (N, O, 3, B) at the object's index ``*_obj``.
    """
    n_nodes = pos.shape[0]
    nlanes = pos.shape[2]
    for b in range(nlanes):
        for i in range(n_nodes):
            m = mass[i]
            px, py, pz = pos[i, 0, b], pos[i, 1, b], pos[i, 2, b]
            if not (px == px):
                continue
            fxs = 0.0
            fys = 0.0
            fzs = 0.0
            for k in range(bpos.shape[0]):
                dx = px - bpos[k, 0, b]
                dy = py - bpos[k, 1, b]
                dz = pz - bpos[k, 2, b]
                d = math.sqrt(dx * dx + dy * dy + dz * dz) + 1e-12
                pen = bpar[k, 0] + radius - d
                if pen <= 0.0:
                    continue
                mb = bpar[k, 1]
                me = m * mb / (m + mb)
                fx, fy, fz = _penalty(
                    pen, vel[i, 0, b] - bvel[k, 0, b], vel[i, 1, b] - bvel[k, 1, b],
                    vel[i, 2, b] - bvel[k, 2, b], dx / d, dy / d, dz / d, me, w, zeta, mu, dt,
                )  # fmt: skip
                bforce[k, 0, b] -= fx
                bforce[k, 1, b] -= fy
                bforce[k, 2, b] -= fz
                o = ball_obj[k]
                impulse[i, o, 0, b] += dt * fx
                impulse[i, o, 1, b] += dt * fy
                impulse[i, o, 2, b] += dt * fz
                fxs += fx
                fys += fy
                fzs += fz
            for s in range(skind.shape[0]):
                fx, fy, fz = _shape_force(
                    s, skind, scenter, ssize, px, py, pz, radius, vel[i, 0, b], vel[i, 1, b],
                    vel[i, 2, b], m, w, zeta, mu, dt,
                )  # fmt: skip
                if fx == 0.0 and fy == 0.0 and fz == 0.0:
                    continue
                o = static_obj[s]
                impulse[i, o, 0, b] += dt * fx
                impulse[i, o, 1, b] += dt * fy
                impulse[i, o, 2, b] += dt * fz
                fxs += fx
                fys += fy
                fzs += fz
            h = dt / m
            vel[i, 0, b] += h * fxs
            vel[i, 1, b] += h * fys
            vel[i, 2, b] += h * fzs


@njit(cache=True)
def balls_step(
    bpos, bvel, bpar, bforce, med, current, skind, scenter, ssize, dt, steps, w, zeta, mu
):  # fmt: skip
    """Advance the balls ``steps`` steps: gravity, buoyancy of the submerged cap, drag
    against the current, floor and fixed shapes, plus the constant force ``bforce``."""
    g = med[G]
    level = med[LEVEL]
    water = med[DRAG] > 0.0 and level > -1e8
    floor = med[FLOOR] > 0.0
    drag = med[DRAG]
    for b in range(bpos.shape[2]):
        for k in range(bpos.shape[0]):
            r = bpar[k, 0]
            mb = bpar[k, 1]
            kd = bpar[k, 3] * drag * math.pi * r * r
            for _ in range(steps):
                x, y, z = bpos[k, 0, b], bpos[k, 1, b], bpos[k, 2, b]
                vx, vy, vz = bvel[k, 0, b], bvel[k, 1, b], bvel[k, 2, b]
                fx = bforce[k, 0, b]
                fy = bforce[k, 1, b] - mb * g
                fz = bforce[k, 2, b]
                frac = 0.0
                if water:
                    h = min(max(level - (y - r), 0.0), 2.0 * r)
                    frac = h * h * (3.0 * r - h) / (4.0 * r * r * r)
                    fy += frac * bpar[k, 2] * mb * g
                if floor:
                    pen = r - y
                    if pen > 0.0:
                        cx, cy, cz = _penalty(pen, vx, vy, vz, 0.0, 1.0, 0.0, mb, w, zeta, mu, dt)
                        fx += cx
                        fy += cy
                        fz += cz
                for s in range(skind.shape[0]):
                    cx, cy, cz = _shape_force(
                        s, skind, scenter, ssize, x, y, z, r, vx, vy, vz, mb, w, zeta, mu, dt
                    )  # fmt: skip
                    fx += cx
                    fy += cy
                    fz += cz
                vx += dt * fx / mb
                vy += dt * fy / mb
                vz += dt * fz / mb
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


@njit(cache=True)
def near(pos, vel, radius, bpos, bvel, bpar, skind, scenter, ssize, horizon):
    """Return True if any node could touch any ball or fixed shape within ``horizon`` s."""
    n_nodes = pos.shape[0]
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
        for i in range(n_nodes):
            px, py, pz = pos[i, 0, b], pos[i, 1, b], pos[i, 2, b]
            for k in range(bpos.shape[0]):
                dx = px - bpos[k, 0, b]
                dy = py - bpos[k, 1, b]
                dz = pz - bpos[k, 2, b]
                if dx * dx + dy * dy + dz * dz < (bpar[k, 0] + reach) ** 2:
                    return True
            for s in range(skind.shape[0]):
                d, _, _, _ = _sdf(
                    skind[s], scenter[s, 0], scenter[s, 1], scenter[s, 2],
                    ssize[s, 0], ssize[s, 1], ssize[s, 2], px, py, pz,
                )  # fmt: skip
                if d < reach:
                    return True
    return False


def empty_impulse(n_nodes: int, n_objects: int, batch: int) -> np.ndarray:
    """Return a zero impulse record (N, O, 3, B) for ``node_contacts``."""
    return np.zeros((n_nodes, n_objects, 3, batch))
