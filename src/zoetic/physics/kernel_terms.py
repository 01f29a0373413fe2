"""The Numba kernel's force terms and integrator, inlined into its entry points (``kernel``).

They are ``physics.law`` hand-tuned for the CPU: every per-node quantity is an array
(nodes, lanes) and the innermost loop runs over candidates ("lanes") with unit stride, so that
LLVM vectorises it; the conformance tests hold them equal to the law. Each term reads the
body from the ``model.Model`` by field name and adds into the force arrays fx, fy, fz.

Cost (shark): springs are about 3/4 of a step, water panels 1/4. Each spring moves about 25
lane-vectors through memory (positions, velocities, both nodes' forces, one activation); a
512-lane chunk's state spills from L1 to L2, and each lane loop pays LLVM's runtime overlap
tests on entry, so the kernel runs near the L2 bound and well below its arithmetic and
square-root bounds (the roofline is in docs/performance.md).
"""

from __future__ import annotations

import math

import llvmlite.binding as _llvm
import numpy as np
from numba import njit

from zoetic.jitcache import fresh_numba_cache

fresh_numba_cache()

# The inner loops read and write many node rows that LLVM cannot prove distinct; with the
# default limit of 8 runtime alias checks it gives up on vectorising the water-face loop.
# Raising the limits (process-wide, and only ever enabling more vectorisation) lets it check
# at run time and take the SIMD path: about 1.4x on the shark in water.
_llvm.set_option("", "-runtime-memory-check-threshold=128")
_llvm.set_option("", "-vectorize-memory-check-threshold=512")

# fast math without "no NaNs/infs" (the blow-up check must see NaN), and without "afn" and
# "reassoc": with either, the SIMD body and its scalar remainder loop round differently (with
# "reassoc" only in code loaded from the on-disk cache), so a candidate's result would depend
# on its place in the batch: 0.3 m apart for a snake after 3 s. Dropping them cost nothing.
FM = {"nsz", "arcp", "contract"}

# The kernel works in single precision: twice the SIMD lanes of double, and the papers'
# models need no more. Every literal goes through F so that nothing promotes to float64.
F = np.float32
ZERO = F(0.0)
ONE = F(1.0)
HALF = F(0.5)
TINY = F(1e-12)
TINY2 = F(1e-30)
SPLIT_LANES = 16  # from this many lanes a chunk, the water finds forces first, then adds


@njit(cache=True, fastmath=FM, inline="always")
def weight(y, fx, fy, fz, nb, m):
    """Set the forces to gravity and, below the water level, buoyancy."""
    mass = m.mass
    level = F(m.water_level)
    g = F(m.gravity)
    gb = g * F(m.buoyancy)
    for i in range(mass.shape[0]):
        wet = mass[i] * (gb - g)
        dry = -mass[i] * g
        for b in range(nb):
            fx[i, b] = ZERO
            fy[i, b] = wet if y[i, b] < level else dry
            fz[i, b] = ZERO


@njit(cache=True, fastmath=FM, inline="always")
def springs(x, y, z, vx, vy, vz, fx, fy, fz, arow, nb, m, sidx):
    """Add the forces of the springs listed in ``sidx`` (``arow`` (A, >= nb): this step's
    activations of the chunk's lanes)."""
    # springs and muscles: l = a*l_c + (1-a)*l_r = l_r + a*(l_c - l_r). Branch-free: a passive
    # spring reads column 0 and has l_c - l_r = 0 (``shorten``). A branch on "is it a muscle"
    # here kept LLVM from vectorising the loop: removing it made the shark 2x, the snake 3.4x.
    # (Each array is taken from the model once, outside the loops: a field read per spring
    # costs a reference count each time.)
    sa, sb, stiff, sdamp = m.spring_a, m.spring_b, m.stiffness, m.spring_damping
    relaxed, shorten, scol = m.relaxed, m.shorten, m.spring_col
    for q in range(sidx.shape[0]):
        s = sidx[q]
        i = sa[s]
        j = sb[s]
        k = stiff[s]
        c = sdamp[s]
        lr = relaxed[s]
        dl = shorten[s]
        col = scol[s]
        for b in range(nb):
            dx = x[j, b] - x[i, b]
            dy = y[j, b] - y[i, b]
            dz = z[j, b] - z[i, b]
            length = math.sqrt(dx * dx + dy * dy + dz * dz) + TINY
            inv = ONE / length
            ux = dx * inv
            uy = dy * inv
            uz = dz * inv
            rest = lr + arow[col, b] * dl
            edot = (
                (vx[j, b] - vx[i, b]) * ux + (vy[j, b] - vy[i, b]) * uy + (vz[j, b] - vz[i, b]) * uz
            )
            mag = k * (length - rest) + c * edot
            fx[i, b] += mag * ux
            fy[i, b] += mag * uy
            fz[i, b] += mag * uz
            fx[j, b] -= mag * ux
            fy[j, b] -= mag * uy
            fz[j, b] -= mag * uz


@njit(cache=True, fastmath=FM, inline="always")
def water(x, y, z, vx, vy, vz, fx, fy, fz, tmp, nb, m):
    """Hydrodynamic reaction on each surface panel (Tu & Terzopoulos): it opposes the normal
    velocity of a panel moving outward, -c * drag * A * |v| * (n.v) * n, shared by its nodes
    (c = ``panel_drag``, the panel's own coefficient).

    ``tmp`` (>= 4, nb) is scratch: a panel's normal and force magnitude per lane are found
    first and only then added to its nodes, so that the lane loop that finds them writes
    nothing it reads and vectorises without overlap tests. A triangle (its fourth slot repeats
    the third node with weight 0) adds to three nodes: with four, two of the rows written
    are one, and LLVM's overlap test sent the whole lane loop down its scalar path. Chunks
    of fewer than ``SPLIT_LANES`` lanes (one animal in a World) take ``_water_fused``, with
    the same result to the bit."""
    if nb < SPLIT_LANES:
        _water_fused(x, y, z, vx, vy, vz, fx, fy, fz, nb, m)
        return
    level = F(m.water_level)
    for f in range(m.panels.shape[0]):
        i0, i1, i2, i3, w0, w1, w2, w3, half_drag, mf_dt = _panel(m, f)
        nodes, weights = (i0, i1, i2, i3), (w0, w1, w2, w3)
        _panel_lanes(x, y, z, vx, vy, vz, tmp, nb, nodes, weights, half_drag, mf_dt, level)
        _panel_add(fx, fy, fz, tmp, nb, i0, w0)
        _panel_add(fx, fy, fz, tmp, nb, i1, w1)
        _panel_add(fx, fy, fz, tmp, nb, i2, w2)
        if i3 != i2:
            _panel_add(fx, fy, fz, tmp, nb, i3, w3)


@njit(cache=True, fastmath=FM, inline="always")
def _panel(m, f):
    """Return panel f's nodes i0 .. i3, their weights w0 .. w3 (1/n for its n distinct nodes),
    half its drag (drag/2 times its ``panel_drag``) and its own mass over dt, as one flat
    tuple (nodes and weights returned as tuples in a tuple failed numba's parallel array
    analysis of the kernel)."""
    panels, pw, mass = m.panels, m.panel_weights, m.mass
    i0, i1, i2, i3 = panels[f, 0], panels[f, 1], panels[f, 2], panels[f, 3]
    w0, w1, w2, w3 = pw[f, 0], pw[f, 1], pw[f, 2], pw[f, 3]
    half_drag = HALF * F(m.water_drag) * m.panel_drag[f]
    mf_dt = (w0 * mass[i0] + w1 * mass[i1] + w2 * mass[i2] + w3 * mass[i3]) / (w0 * F(m.dt))
    return i0, i1, i2, i3, w0, w1, w2, w3, half_drag, mf_dt


@njit(cache=True, fastmath=FM, inline="always")
def _panel_lanes(x, y, z, vx, vy, vz, tmp, nb, nodes, weights, half_drag, mf_dt, level):
    """Write a panel's force magnitude into tmp[0] and its unnormalised normal into tmp[1:4]
    for every lane (the panel as ``_panel`` gives it)."""
    for b in range(nb):
        mag, nx, ny, nz = _panel_force(
            x, y, z, vx, vy, vz, b, nodes, weights, half_drag, mf_dt, level
        )
        tmp[0, b] = mag
        tmp[1, b] = nx
        tmp[2, b] = ny
        tmp[3, b] = nz


@njit(cache=True, fastmath=FM, inline="always")
def _panel_force(x, y, z, vx, vy, vz, b, nodes, weights, half_drag, mf_dt, level):
    """Return lane b's force magnitude on a panel (nodes i0 .. i3 with weights w0 .. w3; 0
    above the water ``level``) and its unnormalised normal N (|N| = 2 area): the force is
    -mag * N, -(N.v)/|N|^2 * min(drag * |N|/2 * |v|, m_panel/dt) * N while N.v > 0, with v
    the panel's mean velocity, half_drag = drag/2 and mf_dt = m_panel/dt."""
    i0, i1, i2, i3 = nodes
    w0, w1, w2, w3 = weights
    d1x = x[i2, b] - x[i0, b]
    d1y = y[i2, b] - y[i0, b]
    d1z = z[i2, b] - z[i0, b]
    d2x = x[i3, b] - x[i1, b]
    d2y = y[i3, b] - y[i1, b]
    d2z = z[i3, b] - z[i1, b]
    nx = d1y * d2z - d1z * d2y
    ny = d1z * d2x - d1x * d2z
    nz = d1x * d2y - d1y * d2x
    nn = nx * nx + ny * ny + nz * nz + TINY2
    mvx = w0 * vx[i0, b] + w1 * vx[i1, b] + w2 * vx[i2, b] + w3 * vx[i3, b]
    mvy = w0 * vy[i0, b] + w1 * vy[i1, b] + w2 * vy[i2, b] + w3 * vy[i3, b]
    mvz = w0 * vz[i0, b] + w1 * vz[i1, b] + w2 * vz[i2, b] + w3 * vz[i3, b]
    q = nx * mvx + ny * mvy + nz * mvz
    q = q if q > ZERO else ZERO
    vv = mvx * mvx + mvy * mvy + mvz * mvz
    cy = w0 * y[i0, b] + w1 * y[i1, b] + w2 * y[i2, b] + w3 * y[i3, b]
    lim = half_drag * math.sqrt(nn * vv)
    lim = lim if lim < mf_dt else mf_dt
    mag = q / nn * lim
    return (mag if cy < level else ZERO), nx, ny, nz


@njit(cache=True, fastmath=FM, inline="always")
def _panel_add(fx, fy, fz, tmp, nb, i, w):
    """Add node i's share w of the panel force in tmp (``_panel_lanes``) to its force rows."""
    for b in range(nb):
        mag = tmp[0, b]
        fx[i, b] -= w * mag * tmp[1, b]
        fy[i, b] -= w * mag * tmp[2, b]
        fz[i, b] -= w * mag * tmp[3, b]


@njit(cache=True, fastmath=FM, inline="always")
def _water_fused(x, y, z, vx, vy, vz, fx, fy, fz, nb, m):
    """``water`` in one lane loop a panel, adding to its nodes as it goes: for a few lanes,
    where the loop overheads of the split form cost more than its vectorisation gains."""
    level = F(m.water_level)
    for f in range(m.panels.shape[0]):
        i0, i1, i2, i3, w0, w1, w2, w3, half_drag, mf_dt = _panel(m, f)
        nodes, weights = (i0, i1, i2, i3), (w0, w1, w2, w3)
        for b in range(nb):
            mag, nx, ny, nz = _panel_force(
                x, y, z, vx, vy, vz, b, nodes, weights, half_drag, mf_dt, level
            )
            fx[i0, b] -= w0 * mag * nx
            fy[i0, b] -= w0 * mag * ny
            fz[i0, b] -= w0 * mag * nz
            fx[i1, b] -= w1 * mag * nx
            fy[i1, b] -= w1 * mag * ny
            fz[i1, b] -= w1 * mag * nz
            fx[i2, b] -= w2 * mag * nx
            fy[i2, b] -= w2 * mag * ny
            fz[i2, b] -= w2 * mag * nz
            fx[i3, b] -= w3 * mag * nx
            fy[i3, b] -= w3 * mag * ny
            fz[i3, b] -= w3 * mag * nz


INV_TWO_PI = F(1.0 / (2.0 * math.pi))
TWO_PI = F(2.0 * math.pi)
S3, S5, S7, S9, S11, S13 = (F((-1) ** k / math.factorial(2 * k + 1)) for k in range(1, 7))
C2, C4, C6, C8, C10, C12 = (F((-1) ** k / math.factorial(2 * k)) for k in range(1, 7))


@njit(cache=True, fastmath=FM, inline="always")
def cos_sin(a):
    """Return cos(a) and sin(a) for a float32 angle, from polynomials of the half angle
    (Taylor to the 13th power, error below float32 rounding for |a| <= pi after the
    reduction): unlike math.cos, which is a call to libm, the lane loop vectorises."""
    r = a - np.floor(a * INV_TWO_PI + HALF) * TWO_PI  # |r| <= pi
    h = r * HALF
    h2 = h * h
    s = h * (ONE + h2 * (S3 + h2 * (S5 + h2 * (S7 + h2 * (S9 + h2 * (S11 + h2 * S13))))))
    c = ONE + h2 * (C2 + h2 * (C4 + h2 * (C6 + h2 * (C8 + h2 * (C10 + h2 * C12)))))
    return c * c - s * s, F(2.0) * s * c


@njit(cache=True, fastmath=FM, inline="always")
def fins(x, y, z, vx, vy, vz, fx, fy, fz, tmp, arow, nb, m):
    """Pectoral fins: flat plates at a controlled angle to the body, pushed on by the water.

    ``tmp`` (>= 3, nb) is scratch: each fin's force per lane is found first and only then
    added to its nodes, so that the lane loop stores into three rows rather than twelve
    that may alias what it reads (LLVM then vectorises it)."""
    fin_nodes, mass = m.fin_nodes, m.mass
    for k in range(fin_nodes.shape[0]):
        # a fin's 1-4 nodes as four slots (padding repeats the first node with weight 0), so
        # that the lane loop has no inner loop and vectorises
        cnt = 0
        mf = ZERO
        for q in range(4):
            if fin_nodes[k, q] >= 0:
                cnt += 1
                mf += mass[fin_nodes[k, q]]
        _fin_lanes(x, y, z, vx, vy, vz, tmp, arow, nb, m, k, cnt, mf)
        for q in range(cnt):
            i = fin_nodes[k, q]
            for b in range(nb):
                fx[i, b] -= tmp[0, b]
                fy[i, b] -= tmp[1, b]
                fz[i, b] -= tmp[2, b]


@njit(cache=True, fastmath=FM, inline="always")
def _fin_lanes(x, y, z, vx, vy, vz, tmp, arow, nb, m, k, cnt, mf):
    """Write fin k's force on each of its nodes into tmp[0:3] for every lane."""
    level = F(m.water_level)
    drag = F(m.water_drag)
    dt = F(m.dt)
    share = ONE / F(cnt)
    i0 = m.fin_nodes[k, 0]
    i1 = m.fin_nodes[k, 1] if cnt > 1 else i0
    i2 = m.fin_nodes[k, 2] if cnt > 2 else i0
    i3 = m.fin_nodes[k, 3] if cnt > 3 else i0
    w1 = share if cnt > 1 else ZERO
    w2 = share if cnt > 2 else ZERO
    w3 = share if cnt > 3 else ZERO
    fa, fb = m.fin_forward[k, 0], m.fin_forward[k, 1]
    sa_, sb_ = m.fin_span[k, 0], m.fin_span[k, 1]
    lo = m.fin_angle[k, 0]
    hi = m.fin_angle[k, 1]
    col = m.fin_actuator[k]
    area = m.fin_area[k]
    for b in range(nb):
        ax = x[fa, b] - x[fb, b]
        ay = y[fa, b] - y[fb, b]
        az = z[fa, b] - z[fb, b]
        inv = ONE / (math.sqrt(ax * ax + ay * ay + az * az) + TINY)
        ax *= inv
        ay *= inv
        az *= inv
        sx = x[sa_, b] - x[sb_, b]
        sy = y[sa_, b] - y[sb_, b]
        sz = z[sa_, b] - z[sb_, b]
        d = sx * ax + sy * ay + sz * az
        sx -= d * ax
        sy -= d * ay
        sz -= d * az
        inv = ONE / (math.sqrt(sx * sx + sy * sy + sz * sz) + TINY)
        sx *= inv
        sy *= inv
        sz *= inv
        # up = forward x span; the plate normal tilts from up toward forward by the angle
        ux = ay * sz - az * sy
        uy = az * sx - ax * sz
        uz = ax * sy - ay * sx
        ca, sn = cos_sin(lo + arow[col, b] * (hi - lo))
        nx = ca * ux + sn * ax
        ny = ca * uy + sn * ay
        nz = ca * uz + sn * az
        mvx = share * vx[i0, b] + w1 * vx[i1, b] + w2 * vx[i2, b] + w3 * vx[i3, b]
        mvy = share * vy[i0, b] + w1 * vy[i1, b] + w2 * vy[i2, b] + w3 * vy[i3, b]
        mvz = share * vz[i0, b] + w1 * vz[i1, b] + w2 * vz[i2, b] + w3 * vz[i3, b]
        cy = share * y[i0, b] + w1 * y[i1, b] + w2 * y[i2, b] + w3 * y[i3, b]
        vn = nx * mvx + ny * mvy + nz * mvz
        speed = math.sqrt(mvx * mvx + mvy * mvy + mvz * mvz)
        sub = ONE if cy < level else ZERO
        mag = drag * area * speed * vn
        cap = mf * abs(vn) / dt
        mag = max(min(mag, cap), -cap) * sub * share
        tmp[0, b] = mag * nx
        tmp[1, b] = mag * ny
        tmp[2, b] = mag * nz


@njit(cache=True, fastmath=FM, inline="always")
def floor_constants(m):
    """Return the floor's stiffness, damping and forward, backward and lateral friction as the
    float32 array ``ground`` reads. From memory, not registers: LLVM contracts the friction's
    multiply-adds into FMAs one way or the other depending on that, and the results (seeded
    runs on the ground) would change in the last bit."""
    out = np.empty(5, dtype=np.float32)
    out[0] = m.floor_stiffness
    out[1] = m.floor_damping
    out[2] = m.friction_forward
    out[3] = m.friction_backward
    out[4] = m.friction_lateral
    return out


@njit(cache=True, fastmath=FM, inline="always")
def ground(x, y, z, vx, vy, vz, fx, fy, fz, nb, m, floor):
    """Penalty floor at y = 0 and directional Coulomb friction, solved implicitly (``floor``:
    the model's ``floor_constants``)."""
    kc, cc, muf, mub, mul = floor[0], floor[1], floor[2], floor[3], floor[4]
    dt = F(m.dt)
    masses, front, back = m.mass, m.axis_front, m.axis_back
    for i in range(masses.shape[0]):
        mass = masses[i]
        fi = front[i]
        bi = back[i]
        for b in range(nb):
            pen = -y[i, b]
            normal = kc * pen - cc * vy[i, b]
            normal = normal if (pen > ZERO and normal > ZERO) else ZERO
            fy[i, b] += normal
            tx = x[fi, b] - x[bi, b]
            tz = z[fi, b] - z[bi, b]
            inv = ONE / (math.sqrt(tx * tx + tz * tz) + TINY)
            tx *= inv
            tz *= inv
            # velocity the other forces would give: friction opposes it, at most stopping it
            px = vx[i, b] + dt * fx[i, b] / mass
            pz = vz[i, b] + dt * fz[i, b] / mass
            vf = px * tx + pz * tz
            vl = pz * tx - px * tz
            mu = muf if vf > ZERO else mub
            ff = mu * normal
            cap = mass * abs(vf) / dt
            ff = ff if ff < cap else cap
            fl = mul * normal
            cap = mass * abs(vl) / dt
            fl = fl if fl < cap else cap
            ff = -ff if vf > ZERO else ff
            fl = -fl if vl > ZERO else fl
            fx[i, b] += ff * tx - fl * tz
            fz[i, b] += ff * tz + fl * tx


@njit(cache=True, fastmath=FM, inline="always")
def advance_nodes(x, y, z, vx, vy, vz, fx, fy, fz, nb, m, h, nodes):
    """Symplectic Euler over h of ``nodes``: velocities (nodal damping implicit), positions."""
    mass, ndamp = m.mass, m.node_damping
    for q in range(nodes.shape[0]):
        i = nodes[q]
        hm = h / mass[i]
        damp = ONE / (ONE + hm * ndamp[i])
        for b in range(nb):
            vx[i, b] = (vx[i, b] + hm * fx[i, b]) * damp
            vy[i, b] = (vy[i, b] + hm * fy[i, b]) * damp
            vz[i, b] = (vz[i, b] + hm * fz[i, b]) * damp
            x[i, b] += h * vx[i, b]
            y[i, b] += h * vy[i, b]
            z[i, b] += h * vz[i, b]
