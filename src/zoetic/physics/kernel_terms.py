"""The Numba kernel's force terms and integrator, inlined into its entry points (``kernel``).

They are ``physics.law`` hand-tuned for the CPU: every per-node quantity is an array
(nodes, lanes) and the innermost loop runs over candidates ("lanes") with unit stride, so that
LLVM vectorises it; the conformance tests hold them equal to the law. Each term reads the
body from the ``model.Model`` by field name and adds into the force arrays fx, fy, fz.

Cost (shark, AVX2 host): springs are about 3/4 of a step, water panels 1/4. Each spring moves
about 25 lane-vectors through memory (positions, velocities, both nodes' forces, one
activation), so the loop is bound by loads and stores rather than arithmetic; the batched
figure therefore scales with the host's SIMD width (twice on AVX-512).
"""

from __future__ import annotations

import math

import llvmlite.binding as _llvm
import numpy as np
from numba import njit

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


# The state of one block of lanes is one array s (nodes, NF, lanes): each node's fields (its
# position, velocity, force and the sub-steps' force, each a row of lanes) lie together, and
# the lane count is a compile-time constant (the entry point allocates s). Then every access
# of one node is one base pointer plus a constant offset, so LLVM proves that a force row
# written never overlaps a position or velocity row read in the same node, and it checks the
# two (or four) nodes of a spring (panel) against each other with one test each at run time;
# with a row per quantity it needed about a hundred such tests per spring and lost the SIMD
# path on short rows. A block of 16 lanes (about 18 kB for the shark) stays in L1.
X, Y, Z, VX, VY, VZ, FX, FY, FZ, GX, GY, GZ = range(12)
NF = 12  # fields a node holds


@njit(cache=True, fastmath=FM, inline="always")
def weight(s, m):
    """Set the forces to gravity and, below the water level, buoyancy."""
    mass = m.mass
    level = F(m.water_level)
    g = F(m.gravity)
    gb = g * F(m.buoyancy)
    for n in range(mass.shape[0]):
        i = np.uint64(n)
        wet = mass[i] * (gb - g)
        dry = -mass[i] * g
        for b in range(s.shape[2]):
            s[i, FX, b] = ZERO
            s[i, FY, b] = wet if s[i, Y, b] < level else dry
            s[i, FZ, b] = ZERO


@njit(cache=True, fastmath=FM, inline="always")
def springs(s, fo, arow, m, sidx):
    """Add the forces of the springs listed in ``sidx`` to the force fields fo, fo + 1,
    fo + 2 (FX or GX) (``arow`` (A, lanes): this step's activations of the block's lanes)."""
    # springs and muscles: l = a*l_c + (1-a)*l_r = l_r + a*(l_c - l_r). Branch-free: a passive
    # spring reads column 0 and has l_c - l_r = 0 (``shorten``). A branch on "is it a muscle"
    # here kept LLVM from vectorising the loop: removing it made the shark 2x, the snake 3.4x.
    # (Each array is taken from the model once, outside the loops: a field read per spring
    # costs a reference count each time.)
    sa, sb, stiff, sdamp = m.spring_a, m.spring_b, m.stiffness, m.spring_damping
    relaxed, shorten, scol = m.relaxed, m.shorten, m.spring_col
    for q in range(sidx.shape[0]):
        e = sidx[q]
        i = np.uint64(sa[e])  # unsigned: no wrap-around select per address
        j = np.uint64(sb[e])
        k = stiff[e]
        c = sdamp[e]
        lr = relaxed[e]
        dl = shorten[e]
        col = scol[e]
        for b in range(s.shape[2]):
            dx = s[j, X, b] - s[i, X, b]
            dy = s[j, Y, b] - s[i, Y, b]
            dz = s[j, Z, b] - s[i, Z, b]
            length = math.sqrt(dx * dx + dy * dy + dz * dz) + TINY
            inv = ONE / length
            ux = dx * inv
            uy = dy * inv
            uz = dz * inv
            rest = lr + arow[col, b] * dl
            edot = (
                (s[j, VX, b] - s[i, VX, b]) * ux
                + (s[j, VY, b] - s[i, VY, b]) * uy
                + (s[j, VZ, b] - s[i, VZ, b]) * uz
            )
            mag = k * (length - rest) + c * edot
            s[i, fo, b] += mag * ux
            s[i, fo + 1, b] += mag * uy
            s[i, fo + 2, b] += mag * uz
            s[j, fo, b] -= mag * ux
            s[j, fo + 1, b] -= mag * uy
            s[j, fo + 2, b] -= mag * uz


@njit(cache=True, fastmath=FM, inline="always")
def water(s, m):
    """Hydrodynamic reaction on each surface panel (Tu & Terzopoulos): it opposes the normal
    velocity of a panel moving outward, -c * drag * A * |v| * (n.v) * n, shared by its nodes
    (c = ``panel_drag``, the panel's own coefficient)."""
    mass, panels, pw, pdrag = m.mass, m.panels, m.panel_weights, m.panel_drag
    drag = F(m.water_drag)
    dt = F(m.dt)
    for f in range(panels.shape[0]):
        half_drag = HALF * drag * pdrag[f]
        i0 = np.uint64(panels[f, 0])
        i1 = np.uint64(panels[f, 1])
        i2 = np.uint64(panels[f, 2])
        i3 = np.uint64(panels[f, 3])
        w = (pw[f, 0], pw[f, 1], pw[f, 2], pw[f, 3])
        # the panel's own mass (weights are 1/n for its n distinct nodes)
        mf_dt = (w[0] * mass[i0] + w[1] * mass[i1] + w[2] * mass[i2] + w[3] * mass[i3]) / (
            w[0] * dt
        )
        # a triangle repeats its third node with weight 0: its own loop, which neither reads
        # nor writes that node twice, so that the node cannot alias itself and stop the SIMD
        if i3 == i2:
            _panel_lanes(s, m, i0, i1, i2, i2, w, half_drag, mf_dt, True)
        else:
            _panel_lanes(s, m, i0, i1, i2, i3, w, half_drag, mf_dt, False)


@njit(cache=True, fastmath=FM, inline="always")
def _panel_lanes(s, m, i0, i1, i2, i3, w, half_drag, mf_dt, tri):
    """One panel's force on its nodes in every lane (``water``); ``tri``: i3 is i2 again."""
    level = F(m.water_level)
    w0, w1, w2, w3 = w
    for b in range(s.shape[2]):
        d1x = s[i2, X, b] - s[i0, X, b]
        d1y = s[i2, Y, b] - s[i0, Y, b]
        d1z = s[i2, Z, b] - s[i0, Z, b]
        d2x = s[i3, X, b] - s[i1, X, b]
        d2y = s[i3, Y, b] - s[i1, Y, b]
        d2z = s[i3, Z, b] - s[i1, Z, b]
        nx = d1y * d2z - d1z * d2y
        ny = d1z * d2x - d1x * d2z
        nz = d1x * d2y - d1y * d2x
        # with N the unnormalised normal (|N| = 2 area), the panel force is
        # -(N.v)/|N|^2 * min(drag * |N|/2 * |v|, m_panel/dt) * N, only while N.v > 0
        nn = nx * nx + ny * ny + nz * nz + TINY2
        mvx = w0 * s[i0, VX, b] + w1 * s[i1, VX, b] + w2 * s[i2, VX, b]
        mvy = w0 * s[i0, VY, b] + w1 * s[i1, VY, b] + w2 * s[i2, VY, b]
        mvz = w0 * s[i0, VZ, b] + w1 * s[i1, VZ, b] + w2 * s[i2, VZ, b]
        cy = w0 * s[i0, Y, b] + w1 * s[i1, Y, b] + w2 * s[i2, Y, b]
        if not tri:  # a triangle's fourth weight is 0, and + 0 * v changes no bit
            mvx += w3 * s[i3, VX, b]
            mvy += w3 * s[i3, VY, b]
            mvz += w3 * s[i3, VZ, b]
            cy += w3 * s[i3, Y, b]
        q = nx * mvx + ny * mvy + nz * mvz
        q = q if q > ZERO else ZERO
        vv = mvx * mvx + mvy * mvy + mvz * mvz
        lim = half_drag * math.sqrt(nn * vv)
        lim = lim if lim < mf_dt else mf_dt
        mag = q / nn * lim
        mag = mag if cy < level else ZERO
        s[i0, FX, b] -= w0 * mag * nx
        s[i0, FY, b] -= w0 * mag * ny
        s[i0, FZ, b] -= w0 * mag * nz
        s[i1, FX, b] -= w1 * mag * nx
        s[i1, FY, b] -= w1 * mag * ny
        s[i1, FZ, b] -= w1 * mag * nz
        s[i2, FX, b] -= w2 * mag * nx
        s[i2, FY, b] -= w2 * mag * ny
        s[i2, FZ, b] -= w2 * mag * nz
        if not tri:
            s[i3, FX, b] -= w3 * mag * nx
            s[i3, FY, b] -= w3 * mag * ny
            s[i3, FZ, b] -= w3 * mag * nz


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
def fins(s, tmp, arow, m):
    """Pectoral fins: flat plates at a controlled angle to the body, pushed on by the water.

    ``tmp`` (>= 3, lanes) is scratch: each fin's force per lane is found first and only then
    added to its nodes, so that the lane loop reads up to eight nodes and writes one row."""
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
        _fin_lanes(s, tmp, arow, m, k, cnt, mf)
        for q in range(cnt):
            i = fin_nodes[k, q]
            for b in range(s.shape[2]):
                s[i, FX, b] -= tmp[0, b]
                s[i, FY, b] -= tmp[1, b]
                s[i, FZ, b] -= tmp[2, b]


@njit(cache=True, fastmath=FM, inline="always")
def _fin_lanes(s, tmp, arow, m, k, cnt, mf):
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
    for b in range(s.shape[2]):
        ax = s[fa, X, b] - s[fb, X, b]
        ay = s[fa, Y, b] - s[fb, Y, b]
        az = s[fa, Z, b] - s[fb, Z, b]
        inv = ONE / (math.sqrt(ax * ax + ay * ay + az * az) + TINY)
        ax *= inv
        ay *= inv
        az *= inv
        sx = s[sa_, X, b] - s[sb_, X, b]
        sy = s[sa_, Y, b] - s[sb_, Y, b]
        sz = s[sa_, Z, b] - s[sb_, Z, b]
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
        mvx = share * s[i0, VX, b] + w1 * s[i1, VX, b] + w2 * s[i2, VX, b] + w3 * s[i3, VX, b]
        mvy = share * s[i0, VY, b] + w1 * s[i1, VY, b] + w2 * s[i2, VY, b] + w3 * s[i3, VY, b]
        mvz = share * s[i0, VZ, b] + w1 * s[i1, VZ, b] + w2 * s[i2, VZ, b] + w3 * s[i3, VZ, b]
        cy = share * s[i0, Y, b] + w1 * s[i1, Y, b] + w2 * s[i2, Y, b] + w3 * s[i3, Y, b]
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
def ground(s, m, floor):
    """Penalty floor at y = 0 and directional Coulomb friction, solved implicitly (``floor``:
    the model's ``floor_constants``)."""
    kc, cc, muf, mub, mul = floor[0], floor[1], floor[2], floor[3], floor[4]
    dt = F(m.dt)
    masses, front, back = m.mass, m.axis_front, m.axis_back
    for i in range(masses.shape[0]):
        mass = masses[i]
        fi = front[i]
        bi = back[i]
        for b in range(s.shape[2]):
            pen = -s[i, Y, b]
            normal = kc * pen - cc * s[i, VY, b]
            normal = normal if (pen > ZERO and normal > ZERO) else ZERO
            s[i, FY, b] += normal
            tx = s[fi, X, b] - s[bi, X, b]
            tz = s[fi, Z, b] - s[bi, Z, b]
            inv = ONE / (math.sqrt(tx * tx + tz * tz) + TINY)
            tx *= inv
            tz *= inv
            # velocity the other forces would give: friction opposes it, at most stopping it
            px = s[i, VX, b] + dt * s[i, FX, b] / mass
            pz = s[i, VZ, b] + dt * s[i, FZ, b] / mass
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
            s[i, FX, b] += ff * tx - fl * tz
            s[i, FZ, b] += ff * tz + fl * tx


@njit(cache=True, fastmath=FM, inline="always")
def advance_nodes(s, fo, m, h, nodes):
    """Symplectic Euler over h of ``nodes`` under the forces in fields fo .. fo + 2 (FX or
    GX): velocities (nodal damping implicit), then positions."""
    mass, ndamp = m.mass, m.node_damping
    for q in range(nodes.shape[0]):
        i = np.uint64(nodes[q])
        hm = h / mass[i]
        damp = ONE / (ONE + hm * ndamp[i])
        for b in range(s.shape[2]):
            s[i, VX, b] = (s[i, VX, b] + hm * s[i, fo, b]) * damp
            s[i, VY, b] = (s[i, VY, b] + hm * s[i, fo + 1, b]) * damp
            s[i, VZ, b] = (s[i, VZ, b] + hm * s[i, fo + 2, b]) * damp
            s[i, X, b] += h * s[i, VX, b]
            s[i, Y, b] += h * s[i, VY, b]
            s[i, Z, b] += h * s[i, VZ, b]
