"""Numba kernels for a world's passive objects: animal-object contacts (the balls' own motion:
``balls``).

Two contact models, each chosen so that a contact never hands out more energy than it took:

* **Balls** (against nodes, fixed shapes and the floor) are resolved at the velocity level,
  by impulses. Each step, a ball's contacts (the nodes of an animal that overlap it, the
  shapes it touches) are solved together by projected Gauss-Seidel (``solve``): no pair
  approaches any more, a pair that closed faster than ``REST_SPEED`` separates at e times its
  approach speed, with e the restitution of a spring-damper of the world's damping ratio
  (``restitution``: 0.37 at 0.3), and an overlap is removed over about ``contact_steps``
  steps at no more than ``CORRECTION_SPEED``. Each pair's impulse takes 1 - e^2 of the pair's
  normal kinetic energy, so a struck ball leaves at most at (1 + e) M / (M + m) times the
  striking speed, plus the correction speed, whatever pins it.
* **Nodes against fixed shapes** (a rock, a wall, the hurdle's bar, the post) stay penalty
  forces, because a node is held by the stiff springs of its body. An impulse would stop
  the node alone, and the springs would pull it on through the wall. The stiffness comes
  from the node's mass and the time step: k = m w^2 and damping 2 zeta m w with
  w = pi / (contact_steps dt), so a contact lasts about ``contact_steps`` steps and stays
  stable whatever the masses. The push never makes a node separate faster than
  ``shapes.SEPARATION_SPEED`` (a node driven deep into a thin post is let out, not shot out).
  Why these two models: docs/animals.md, "Contacts".

Friction is Coulomb in both models, capped so that it can at most stop the sliding in one step.
Every force acts on both sides (node and ball get equal and opposite impulses); a fixed shape
absorbs its side.

Layouts follow the animal kernel: node arrays (N, 3, B) float32, balls (K, 3, B) float64.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from zoetic.jitcache import fresh_numba_cache
from zoetic.physics.lane_memo import recalled, remember
from zoetic.physics.shapes import box_apart, node_box, shape_apart, shape_force, shape_sdf

fresh_numba_cache()

REST_SPEED = 0.1  # m/s: a pair closing slower just stops (a resting ball does not chatter)
SLOP = 0.002  # m: an overlap beyond it is removed at no more than CORRECTION_SPEED (m/s)
CORRECTION_SPEED = 0.3
SWEEPS = 8  # projected Gauss-Seidel sweeps over a body's contacts per step
GAP = 1e-6  # m added to a contact's reach before a lane's box is judged apart (rounding)


@njit(cache=True)
def restitution(zeta):
    """Return the restitution of a linear spring-damper contact of damping ratio zeta,
    exp(-zeta pi / sqrt(1 - zeta^2)): the fraction of its approach speed a pair keeps
    (0.37 at the World's default 0.3; 0 from critical damping on)."""
    return 0.0 if zeta >= 1.0 else math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta * zeta))


@njit(cache=True)
def contact_rows(n_nodes, n_statics):
    """Return the scratch rows (contacts, 16) ``solve`` writes its contacts into."""
    return np.zeros((n_nodes + n_statics + 1, 16))


@njit(cache=True)
def solve(
    cx,
    cy,
    cz,
    r,
    mc,
    ux,
    uy,
    uz,
    b,
    nodes,
    pos,
    vel,
    mass,
    radius,
    skind,
    scenter,
    ssize,
    floor,
    e,
    rate,
    dt,
    mu,
    impulse,
    o,
    rows,
):
    """Resolve the contacts of a sphere (centre c, radius r, mass mc, velocity u) in lane b
    at the velocity level; return its new velocity and the number of contacts.

    Its partners are those of the first ``nodes`` nodes (pos, vel, mass, radius) that
    overlap it, the fixed shapes and, with ``floor``, the plane y = 0. Every pair that was
    closing faster than REST_SPEED leaves at ``e`` times its approach speed, slower ones stop;
    an overlap is removed at ``rate`` of its depth per step (at most CORRECTION_SPEED); the
    impulses are solved together (projected Gauss-Seidel, Coulomb friction ``mu`` within its
    cone). Node velocities change in place and each node's impulse adds to ``impulse[i, o]``.
    rows: scratch from ``contact_rows``, a row per contact: partner (node index, or -1 - s
    for fixed shape s, -1 - S for the floor), normal from the partner (3), 1 / partner mass,
    target normal speed, reduced mass, normal impulse, tangential impulse (3), the
    partner's velocity (3); the impulse on the sphere is (normal impulse) n + (tangential).
    """
    c = _node_rows(cx, cy, cz, r, b, nodes, pos, vel, mass, radius, rows)
    c = _shape_rows(cx, cy, cz, r, skind, scenter, ssize, floor, rows, c)
    if c == 0:
        return ux, uy, uz, 0
    _targets(ux, uy, uz, mc, e, rate, dt, rows, c)
    ux, uy, uz = _sweeps(ux, uy, uz, mc, mu, rows, c)
    for j in range(c):
        i = int(rows[j, 0])
        if i < 0:
            continue
        vel[i, 0, b] = rows[j, 13]
        vel[i, 1, b] = rows[j, 14]
        vel[i, 2, b] = rows[j, 15]
        impulse[i, o, 0, b] -= rows[j, 7] * rows[j, 1] + rows[j, 8]
        impulse[i, o, 1, b] -= rows[j, 7] * rows[j, 2] + rows[j, 9]
        impulse[i, o, 2, b] -= rows[j, 7] * rows[j, 3] + rows[j, 10]
    return ux, uy, uz, c


@njit(cache=True, inline="always")
def _node_rows(cx, cy, cz, r, b, nodes, pos, vel, mass, radius, rows):
    """Write a row (``solve``) for each of the first ``nodes`` nodes that overlaps the sphere;
    return their count."""
    c = 0
    for i in range(nodes):
        dx = cx - pos[i, 0, b]
        dy = cy - pos[i, 1, b]
        dz = cz - pos[i, 2, b]
        d2 = dx * dx + dy * dy + dz * dz
        if not (d2 < (r + radius + GAP) ** 2):  # apart, or a failed (NaN) node
            continue
        d = math.sqrt(d2) + 1e-12
        pen = r + radius - d
        if not (pen > 0.0):
            continue
        rows[c, 0] = i
        rows[c, 1], rows[c, 2], rows[c, 3] = dx / d, dy / d, dz / d
        rows[c, 4] = 1.0 / mass[i]
        rows[c, 5] = pen
        rows[c, 13], rows[c, 14], rows[c, 15] = vel[i, 0, b], vel[i, 1, b], vel[i, 2, b]
        c += 1
    return c


@njit(cache=True, inline="always")
def _shape_rows(cx, cy, cz, r, skind, scenter, ssize, floor, rows, c):
    """Write a row (``solve``) after the first c for each fixed shape (and, with ``floor``,
    the floor) the sphere touches; return the count of rows."""
    n_static = skind.shape[0]
    for s in range(n_static + (1 if floor else 0)):
        if s < n_static:
            d, nx, ny, nz = shape_sdf(s, skind, scenter, ssize, cx, cy, cz)
        else:
            d, nx, ny, nz = cy, 0.0, 1.0, 0.0
        pen = r - d
        if not (pen > 0.0):
            continue
        rows[c, 0] = -1 - s
        rows[c, 1], rows[c, 2], rows[c, 3] = nx, ny, nz
        rows[c, 4] = 0.0
        rows[c, 5] = pen
        rows[c, 13], rows[c, 14], rows[c, 15] = 0.0, 0.0, 0.0
        c += 1
    return c


@njit(cache=True, inline="always")
def _targets(ux, uy, uz, mc, e, rate, dt, rows, c):
    """Set each contact's target normal speed (a bounce of ``e`` times the approach, or the
    overlap's correction), reduced mass, and zero impulses."""
    for j in range(c):
        vn = (
            (ux - rows[j, 13]) * rows[j, 1]
            + (uy - rows[j, 14]) * rows[j, 2]
            + (uz - rows[j, 15]) * rows[j, 3]
        )
        bounce = -e * vn if vn < -REST_SPEED else 0.0
        fix = min(rate * max(rows[j, 5] - SLOP, 0.0) / dt, CORRECTION_SPEED)
        rows[j, 5] = max(bounce, fix)
        rows[j, 6] = 1.0 / (1.0 / mc + rows[j, 4])
        rows[j, 7] = 0.0
        rows[j, 8], rows[j, 9], rows[j, 10] = 0.0, 0.0, 0.0


@njit(cache=True, inline="always")
def _sweeps(ux, uy, uz, mc, mu, rows, c):
    """Projected Gauss-Seidel over the contacts (one sweep for one contact, else SWEEPS):
    return the sphere's velocity; the partners' velocities change in rows."""
    for _ in range(1 if c == 1 else SWEEPS):
        for j in range(c):
            nx, ny, nz = rows[j, 1], rows[j, 2], rows[j, 3]
            rx = ux - rows[j, 13]
            ry = uy - rows[j, 14]
            rz = uz - rows[j, 15]
            vn = rx * nx + ry * ny + rz * nz
            lam = max(rows[j, 7] + rows[j, 6] * (rows[j, 5] - vn), 0.0)
            dl = lam - rows[j, 7]
            rows[j, 7] = lam
            # friction: the impulse that stops the sliding, kept within mu times the normal one
            ax = rows[j, 8] - rows[j, 6] * (rx - vn * nx)
            ay = rows[j, 9] - rows[j, 6] * (ry - vn * ny)
            az = rows[j, 10] - rows[j, 6] * (rz - vn * nz)
            at = math.sqrt(ax * ax + ay * ay + az * az)
            if at > mu * lam:
                q = mu * lam / at
                ax, ay, az = ax * q, ay * q, az * q
            jx = dl * nx + ax - rows[j, 8]
            jy = dl * ny + ay - rows[j, 9]
            jz = dl * nz + az - rows[j, 10]
            rows[j, 8], rows[j, 9], rows[j, 10] = ax, ay, az
            # the sphere gets +J, the partner -J
            ux += jx / mc
            uy += jy / mc
            uz += jz / mc
            inv = rows[j, 4]
            rows[j, 13] -= jx * inv
            rows[j, 14] -= jy * inv
            rows[j, 15] -= jz * inv
    return ux, uy, uz


@njit(cache=True)
def node_contacts(
    pos,
    vel,
    mass,
    radius,
    bpos,
    bvel,
    bpar,
    skind,
    scenter,
    ssize,
    ball_obj,
    static_obj,
    dt,
    w,
    zeta,
    mu,
    bforce,
    impulse,
):
    """Apply one step's contacts between an animal's nodes and the objects.

    Each ball is solved with the nodes that overlap it and the fixed shapes it touches
    (``solve``, impulses); its velocity change adds to ``bforce`` (K, 3, B) as the force that
    makes it over one step (applied by ``balls_step``). Then each fixed shape a node overlaps
    pushes it with a penalty force (v += dt F / m). Node velocities change in place; each
    node's impulse from each object accumulates in ``impulse`` (N, C, 3, B) at the column
    ``ball_obj``, ``static_obj`` give it among the balls and fixed shapes (``Solids.ball_col``,
    ``static_col``; food has none). w = pi / (contact_steps dt): the penalty's frequency, and a
    ball's overlap is removed over about contact_steps steps; zeta: the penalty's damping
    ratio, which also sets the balls' restitution (``restitution``).

    A lane whose nodes' bounding box lies farther than a node radius from a ball or from
    every fixed shape along some axis (``box_apart``) has no contact with it: its nodes are
    not tested against that ball, nor against any shape (the same bits as testing them).
    """
    e = restitution(zeta)
    rate = w * dt / math.pi
    rows = contact_rows(pos.shape[0], skind.shape[0])
    # each ball's states in lanes no node reached, and their results (``_ball_contacts``)
    memo = np.empty((bpos.shape[0], pos.shape[2], 9))
    seen = np.zeros(bpos.shape[0], np.int64)
    for b in range(pos.shape[2]):
        box = node_box(pos, b, 0.0)
        _ball_contacts(
            b,
            box,
            pos,
            vel,
            mass,
            radius,
            bpos,
            bvel,
            bpar,
            skind,
            scenter,
            ssize,
            ball_obj,
            dt,
            mu,
            bforce,
            impulse,
            e,
            rate,
            rows,
            memo,
            seen,
        )
        for s in range(skind.shape[0]):
            if not shape_apart(box, s, skind, scenter, ssize, radius + GAP):
                _shape_contacts(
                    b, pos, vel, mass, radius, skind, scenter, ssize, static_obj, dt, w, zeta, mu,
                    impulse,
                )  # fmt: skip
                break


@njit(cache=True, inline="always")
def _ball_contacts(
    b,
    box,
    pos,
    vel,
    mass,
    radius,
    bpos,
    bvel,
    bpar,
    skind,
    scenter,
    ssize,
    ball_obj,
    dt,
    mu,
    bforce,
    impulse,
    e,
    rate,
    rows,
    memo,
    seen,
):
    """Lane b: each ball solved with the nodes and fixed shapes it touches (``solve``); its
    velocity change added to ``bforce`` as the force that makes it over one step. The nodes
    are tested only when their box (``node_box``) is not apart from the ball's.

    A ball no node reaches is solved against the fixed shapes alone, a function of its centre
    and velocity: ``memo[k]`` keeps such lanes' (centre, velocity, solved velocity), and a
    lane whose ball is in a kept state to the bit takes that result (in a batch, most lanes'
    balls rest on their support alike until an animal strikes one)."""
    for k in range(bpos.shape[0]):
        cx, cy, cz, r = bpos[k, 0, b], bpos[k, 1, b], bpos[k, 2, b], bpar[k, 0]
        apart = box_apart(box, cx, cy, cz, r, r, r, radius + GAP)
        mb = bpar[k, 1]
        h = dt / mb
        ux = bvel[k, 0, b] + h * bforce[k, 0, b]
        uy = bvel[k, 1, b] + h * bforce[k, 1, b]
        uz = bvel[k, 2, b] + h * bforce[k, 2, b]
        q = recalled(memo, k, seen, (cx, cy, cz, ux, uy, uz)) if apart else -1
        if q >= 0:
            bforce[k, 0, b] += (memo[k, q, 6] - ux) / h
            bforce[k, 1, b] += (memo[k, q, 7] - uy) / h
            bforce[k, 2, b] += (memo[k, q, 8] - uz) / h
            continue
        nx, ny, nz, _ = solve(
            cx,
            cy,
            cz,
            r,
            mb,
            ux,
            uy,
            uz,
            b,
            0 if apart else pos.shape[0],
            pos,
            vel,
            mass,
            radius,
            skind,
            scenter,
            ssize,
            False,
            e,
            rate,
            dt,
            mu,
            impulse,
            ball_obj[k],
            rows,
        )
        if apart:
            remember(memo, k, seen, (cx, cy, cz, ux, uy, uz, nx, ny, nz))
        bforce[k, 0, b] += (nx - ux) / h
        bforce[k, 1, b] += (ny - uy) / h
        bforce[k, 2, b] += (nz - uz) / h


@njit(cache=True, inline="always")
def _shape_contacts(
    b, pos, vel, mass, radius, skind, scenter, ssize, static_obj, dt, w, zeta, mu, impulse
):
    """Lane b: each fixed shape a node overlaps pushes it with a penalty force (v += dt F /
    m); each push's impulse accumulates in ``impulse`` at the shape's object index."""
    n_nodes = pos.shape[0]
    for i in range(n_nodes):
        m = mass[i]
        px, py, pz = pos[i, 0, b], pos[i, 1, b], pos[i, 2, b]
        if not (px == px):
            continue
        fxs = 0.0
        fys = 0.0
        fzs = 0.0
        for s in range(skind.shape[0]):
            if shape_apart((px, py, pz, px, py, pz), s, skind, scenter, ssize, radius + GAP):
                continue  # the node is farther than its radius from the shape's box
            fx, fy, fz = shape_force(
                s,
                skind,
                scenter,
                ssize,
                px,
                py,
                pz,
                radius,
                vel[i, 0, b],
                vel[i, 1, b],
                vel[i, 2, b],
                m,
                w,
                zeta,
                mu,
                dt,
            )
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
