"""The fast CPU path: a Numba kernel that steps a batch of candidates, SIMD across the batch.

Layout: every per-node quantity is an array (nodes, lanes) so that the innermost loop runs
over candidates ("lanes") with unit stride and LLVM vectorises it; each thread owns a chunk
of lanes and runs all its steps with that chunk in cache. Activations arrive as a table
(steps, actuators, candidates); the kernel never knows which controller made it.

One step is semi-implicit (symplectic) Euler: forces from the current state, velocity
updated with nodal damping implicit, then positions from the new velocity. Ground friction is
solved last, against the velocity the other forces would produce (implicit Coulomb), and
water forces can at most stop a face's normal motion in one step, so stiff drag on light
nodes cannot blow up. A candidate whose state is non-finite or faster than ``vmax`` is marked
failed, reset to rest (so it cannot slow or poison the others) and reported. Springs too
stiff for the step (``multirate.split``) are integrated in sub-steps inside each step, after
one kick of every other force (impulse multirate), so a stiff caudal fin does not shrink the
whole body's step.

Cost (shark, AVX2 host): springs are about 3/4 of a step, water panels 1/4. Each spring moves
about 25 lane-vectors through memory (positions, velocities, both nodes' forces, one
activation), so the loop is bound by loads and stores rather than arithmetic; the batched
figure therefore scales with the host's SIMD width (twice on AVX-512).
"""

from __future__ import annotations

import math
import types as pytypes

import llvmlite.binding as _llvm
import numpy as np
from numba import njit, prange, types
from numba.experimental import structref
from numba.extending import typeof_impl

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

# error_model="numpy" on the entry points (every helper is inlined into them): with Python's
# error model each float division checks for zero and may raise, an early exit that keeps LLVM
# from vectorising a loop with two or more divisions (the fins ran scalar: 46 against 5 ns a
# lane-step). Every divisor here is a mass, the step, or a length plus TINY, never zero.

# The kernel works in single precision: twice the SIMD lanes of double, and the papers'
# models need no more. Every literal goes through F so that nothing promotes to float64.
F = np.float32
ZERO = F(0.0)
ONE = F(1.0)
HALF = F(0.5)
TINY = F(1e-12)
TINY2 = F(1e-30)

# medium array layout (see media.Medium.as_array)
G, LEVEL, BUOY, DRAG, FLOOR, FLOOR_K, FLOOR_C, MU_F, MU_B, MU_L = range(10)


@njit(cache=True, fastmath=FM, inline="always")
def _forces(
    x, y, z, vx, vy, vz, fx, fy, fz, act, t, b0, nb,
    mass, sa, sb, stiff, sdamp, relaxed, shorten, scol, med, sidx,
):  # fmt: skip
    """Gravity, buoyancy and the springs listed in ``sidx`` (the slow ones, see multirate)."""
    n_nodes = mass.shape[0]
    level = med[LEVEL]
    g = med[G]
    gb = g * med[BUOY]
    # start from gravity and buoyancy (buoyancy only below the water level)
    for i in range(n_nodes):
        m = mass[i]
        wet = m * (gb - g)
        dry = -m * g
        for b in range(nb):
            fx[i, b] = ZERO
            fy[i, b] = wet if y[i, b] < level else dry
            fz[i, b] = ZERO
    _springs(
        x, y, z, vx, vy, vz, fx, fy, fz, act, t, b0, nb,
        sa, sb, stiff, sdamp, relaxed, shorten, scol, sidx,
    )  # fmt: skip


@njit(cache=True, fastmath=FM, inline="always")
def _springs(
    x, y, z, vx, vy, vz, fx, fy, fz, act, t, b0, nb,
    sa, sb, stiff, sdamp, relaxed, shorten, scol, sidx,
):  # fmt: skip
    """Add the forces of the springs listed in ``sidx``."""
    # springs and muscles: l = a*l_c + (1-a)*l_r = l_r + a*(l_c - l_r). Branch-free: a passive
    # spring reads column 0 and has l_c - l_r = 0 (``shorten``). A branch on "is it a muscle"
    # here kept LLVM from vectorising the loop: removing it made the shark 2x, the snake 3.4x.
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
            rest = lr + act[t, col, b0 + b] * dl
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
def _water(x, y, z, vx, vy, vz, fx, fy, fz, nb, mass, panels, pw, pdrag, level, drag, dt):
    """Hydrodynamic reaction on each surface panel (Tu & Terzopoulos): it opposes the normal
    velocity of a panel moving outward, -c * drag * A * |v| * (n.v) * n, shared by its nodes
    (c = ``pdrag``, the panel's own coefficient)."""
    for f in range(panels.shape[0]):
        half_drag = HALF * drag * pdrag[f]
        i0 = panels[f, 0]
        i1 = panels[f, 1]
        i2 = panels[f, 2]
        i3 = panels[f, 3]
        w0 = pw[f, 0]
        w1 = pw[f, 1]
        w2 = pw[f, 2]
        w3 = pw[f, 3]
        # the panel's own mass (weights are 1/n for its n distinct nodes)
        mf_dt = (w0 * mass[i0] + w1 * mass[i1] + w2 * mass[i2] + w3 * mass[i3]) / (w0 * dt)
        for b in range(nb):
            d1x = x[i2, b] - x[i0, b]
            d1y = y[i2, b] - y[i0, b]
            d1z = z[i2, b] - z[i0, b]
            d2x = x[i3, b] - x[i1, b]
            d2y = y[i3, b] - y[i1, b]
            d2z = z[i3, b] - z[i1, b]
            nx = d1y * d2z - d1z * d2y
            ny = d1z * d2x - d1x * d2z
            nz = d1x * d2y - d1y * d2x
            # with N the unnormalised normal (|N| = 2 area), the panel force is
            # -(N.v)/|N|^2 * min(drag * |N|/2 * |v|, m_panel/dt) * N, only while N.v > 0
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
            mag = mag if cy < level else ZERO
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


@njit(cache=True, fastmath=FM, inline="always")
def _cos_sin(a):
    """Return cos(a) and sin(a) for a float32 angle, from polynomials of the half angle
    (Taylor to the 13th power, error below float32 rounding for |a| <= pi after the
    reduction): unlike math.cos, which is a call to libm, the lane loop vectorises."""
    r = a - np.floor(a * INV_TWO_PI + HALF) * TWO_PI  # |r| <= pi
    h = r * HALF
    h2 = h * h
    s = h * (ONE + h2 * (S3 + h2 * (S5 + h2 * (S7 + h2 * (S9 + h2 * (S11 + h2 * S13))))))
    c = ONE + h2 * (C2 + h2 * (C4 + h2 * (C6 + h2 * (C8 + h2 * (C10 + h2 * C12)))))
    return c * c - s * s, F(2.0) * s * c


INV_TWO_PI = F(1.0 / (2.0 * math.pi))
TWO_PI = F(2.0 * math.pi)
S3, S5, S7, S9, S11, S13 = (F((-1) ** k / math.factorial(2 * k + 1)) for k in range(1, 7))
C2, C4, C6, C8, C10, C12 = (F((-1) ** k / math.factorial(2 * k)) for k in range(1, 7))


@njit(cache=True, fastmath=FM, inline="always")
def _fins(
    x, y, z, vx, vy, vz, fx, fy, fz, tmp, act, t, b0, nb,
    mass, fin_nodes, fin_fwd, fin_span, fin_area, fin_angle, fin_act, level, drag, dt,
):  # fmt: skip
    """Pectoral fins: flat plates at a controlled angle to the body, pushed on by the water.

    ``tmp`` (>= 3, nb) is scratch: each fin's force per lane is found first and only then
    added to its nodes, so that the lane loop stores into three rows rather than twelve
    that may alias what it reads (LLVM then vectorises it)."""
    for k in range(fin_nodes.shape[0]):
        # a fin's 1-4 nodes as four slots (padding repeats the first node with weight 0), so
        # that the lane loop has no inner loop and vectorises
        cnt = 0
        mf = ZERO
        for q in range(4):
            if fin_nodes[k, q] >= 0:
                cnt += 1
                mf += mass[fin_nodes[k, q]]
        share = ONE / F(cnt)
        i0 = fin_nodes[k, 0]
        i1 = fin_nodes[k, 1] if cnt > 1 else i0
        i2 = fin_nodes[k, 2] if cnt > 2 else i0
        i3 = fin_nodes[k, 3] if cnt > 3 else i0
        w1 = share if cnt > 1 else ZERO
        w2 = share if cnt > 2 else ZERO
        w3 = share if cnt > 3 else ZERO
        fa, fb = fin_fwd[k, 0], fin_fwd[k, 1]
        sa_, sb_ = fin_span[k, 0], fin_span[k, 1]
        lo = fin_angle[k, 0]
        hi = fin_angle[k, 1]
        col = fin_act[k]
        area = fin_area[k]
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
            ca, sn = _cos_sin(lo + act[t, col, b0 + b] * (hi - lo))
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
        for q in range(cnt):
            i = fin_nodes[k, q]
            for b in range(nb):
                fx[i, b] -= tmp[0, b]
                fy[i, b] -= tmp[1, b]
                fz[i, b] -= tmp[2, b]


@njit(cache=True, fastmath=FM, inline="always")
def _ground(x, y, z, vx, vy, vz, fx, fy, fz, nb, mass, front, back, med, dt):
    """Penalty floor at y = 0 and directional Coulomb friction, solved implicitly."""
    kc = med[FLOOR_K]
    cc = med[FLOOR_C]
    muf = med[MU_F]
    mub = med[MU_B]
    mul = med[MU_L]
    for i in range(mass.shape[0]):
        m = mass[i]
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
            px = vx[i, b] + dt * fx[i, b] / m
            pz = vz[i, b] + dt * fz[i, b] / m
            vf = px * tx + pz * tz
            vl = pz * tx - px * tz
            mu = muf if vf > ZERO else mub
            ff = mu * normal
            cap = m * abs(vf) / dt
            ff = ff if ff < cap else cap
            fl = mul * normal
            cap = m * abs(vl) / dt
            fl = fl if fl < cap else cap
            ff = -ff if vf > ZERO else ff
            fl = -fl if vl > ZERO else fl
            fx[i, b] += ff * tx - fl * tz
            fz[i, b] += ff * tz + fl * tx


@njit(cache=True, fastmath=FM, inline="always")
def _advance(x, y, z, vx, vy, vz, fx, fy, fz, nb, mass, ndamp, h, nodes):
    """Symplectic Euler over h of ``nodes``: velocities (nodal damping implicit), positions."""
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


@njit(cache=True, fastmath=FM, inline="always")
def _chunk_steps(
    s, pos0, vel0, act, dt, record_every, vmax, b0, nb, body, med, rec, final_pos, final_vel,
    failed_step, multirate,
):  # fmt: skip
    """Step lanes b0 .. b0 + nb through all rows of ``act`` in s (twelve (nodes, >= nb) arrays):
    load them from pos0/vel0, record every ``record_every`` steps (never if 0), store the
    final state (NaN for failed lanes) in final_pos/final_vel. ``body``: the body's arrays as
    ``simulate_chunks`` takes them, ``multirate``: the split's five (as few arguments as
    possible: Python passes more than 30 as *args, which numba cannot inline)."""
    x, y, z, vx, vy, vz, fx, fy, fz, gx, gy, gz = (
        s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7], s[8], s[9], s[10], s[11]
    )  # fmt: skip
    (mass, ndamp, sa, sb, stiff, sdamp, relaxed, shorten, scol, panels, pw, pdrag, fin_nodes,
     fin_fwd, fin_span, fin_area, fin_angle, fin_act, front, back, rest_pos) = body  # fmt: skip
    slow_idx, fast_idx, substeps, slow_nodes, fast_nodes = multirate
    n_nodes = mass.shape[0]
    n_steps = act.shape[0]
    floor_on = med[FLOOR] > ZERO
    water_on = med[DRAG] > 0.0 and med[LEVEL] > -1e8
    level = med[LEVEL]
    drag = med[DRAG]
    hsub = dt / F(max(substeps, 1))
    for i in range(n_nodes):
        for b in range(nb):
            x[i, b] = pos0[i, 0, b0 + b]
            y[i, b] = pos0[i, 1, b0 + b]
            z[i, b] = pos0[i, 2, b0 + b]
            vx[i, b] = vel0[i, 0, b0 + b]
            vy[i, b] = vel0[i, 1, b0 + b]
            vz[i, b] = vel0[i, 2, b0 + b]
    r = 0
    for t in range(n_steps + 1):
        if record_every > 0 and t % record_every == 0:
            for i in range(n_nodes):
                for b in range(nb):
                    dead = failed_step[b0 + b] >= 0
                    rec[r, i, 0, b0 + b] = np.nan if dead else x[i, b]
                    rec[r, i, 1, b0 + b] = np.nan if dead else y[i, b]
                    rec[r, i, 2, b0 + b] = np.nan if dead else z[i, b]
            r += 1
        if t == n_steps:
            break
        _forces(
            x, y, z, vx, vy, vz, fx, fy, fz, act, t, b0, nb,
            mass, sa, sb, stiff, sdamp, relaxed, shorten, scol, med, slow_idx,
        )  # fmt: skip
        if water_on:
            _water(
                x, y, z, vx, vy, vz, fx, fy, fz, nb, mass, panels, pw, pdrag, level, drag, dt
            )  # fmt: skip
            if fin_nodes.shape[0] > 0:
                _fins(
                    x, y, z, vx, vy, vz, fx, fy, fz, gx, act, t, b0, nb, mass, fin_nodes,
                    fin_fwd, fin_span, fin_area, fin_angle, fin_act, level, drag, dt,
                )  # fmt: skip
        if floor_on:
            _ground(x, y, z, vx, vy, vz, fx, fy, fz, nb, mass, front, back, med, dt)
        if fast_idx.shape[0] == 0:
            _advance(x, y, z, vx, vy, vz, fx, fy, fz, nb, mass, ndamp, dt, slow_nodes)
        else:
            # impulse (RESPA) order: the slow forces kick the velocity once, then the
            # stiff springs drive sub-steps; holding the slow forces over the sub-steps
            # instead is not symplectic and grows energy (det of the step map > 1)
            # (nodes no fast spring touches step once, exactly as without a split)
            _advance(x, y, z, vx, vy, vz, fx, fy, fz, nb, mass, ndamp, dt, slow_nodes)
            for q in range(fast_nodes.shape[0]):
                i = fast_nodes[q]
                hm = dt / mass[i]
                for b in range(nb):
                    vx[i, b] += hm * fx[i, b]
                    vy[i, b] += hm * fy[i, b]
                    vz[i, b] += hm * fz[i, b]
            for _sub in range(substeps):
                for q in range(fast_nodes.shape[0]):
                    i = fast_nodes[q]
                    for b in range(nb):
                        gx[i, b] = ZERO
                        gy[i, b] = ZERO
                        gz[i, b] = ZERO
                _springs(
                    x, y, z, vx, vy, vz, gx, gy, gz, act, t, b0, nb,
                    sa, sb, stiff, sdamp, relaxed, shorten, scol, fast_idx,
                )  # fmt: skip
                _advance(x, y, z, vx, vy, vz, gx, gy, gz, nb, mass, ndamp, hsub, fast_nodes)
        if t % 8 == 7 or t == n_steps - 1:
            for b in range(nb):
                worst = ZERO
                for i in range(n_nodes):
                    s2 = vx[i, b] * vx[i, b] + vy[i, b] * vy[i, b] + vz[i, b] * vz[i, b]
                    worst = s2 if s2 > worst else worst
                if not (worst < vmax * vmax) and failed_step[b0 + b] < 0:
                    failed_step[b0 + b] = t + 1
                if failed_step[b0 + b] >= 0:
                    for i in range(n_nodes):
                        x[i, b] = rest_pos[i, 0]
                        y[i, b] = rest_pos[i, 1]
                        z[i, b] = rest_pos[i, 2]
                        vx[i, b] = ZERO
                        vy[i, b] = ZERO
                        vz[i, b] = ZERO
    for i in range(n_nodes):
        for b in range(nb):
            dead = failed_step[b0 + b] >= 0
            final_pos[i, 0, b0 + b] = np.nan if dead else x[i, b]
            final_pos[i, 1, b0 + b] = np.nan if dead else y[i, b]
            final_pos[i, 2, b0 + b] = np.nan if dead else z[i, b]
            final_vel[i, 0, b0 + b] = np.nan if dead else vx[i, b]
            final_vel[i, 1, b0 + b] = np.nan if dead else vy[i, b]
            final_vel[i, 2, b0 + b] = np.nan if dead else vz[i, b]


@njit(cache=True, inline="always")
def _scratch(n_nodes, nb):
    """Twelve fresh (nodes, nb) float32 arrays for one chunk's state and forces: separate
    allocations, not views of one block, so that LLVM knows they do not alias (one block
    measured 1.3x slower a step, one lane)."""
    return (
        np.empty((n_nodes, nb), dtype=np.float32), np.empty((n_nodes, nb), dtype=np.float32),
        np.empty((n_nodes, nb), dtype=np.float32), np.empty((n_nodes, nb), dtype=np.float32),
        np.empty((n_nodes, nb), dtype=np.float32), np.empty((n_nodes, nb), dtype=np.float32),
        np.empty((n_nodes, nb), dtype=np.float32), np.empty((n_nodes, nb), dtype=np.float32),
        np.empty((n_nodes, nb), dtype=np.float32), np.empty((n_nodes, nb), dtype=np.float32),
        np.empty((n_nodes, nb), dtype=np.float32), np.empty((n_nodes, nb), dtype=np.float32),
    )  # fmt: skip


@njit(cache=True, fastmath=FM, parallel=True, error_model="numpy")
def simulate_chunks(
    pos0, vel0, act, dt, record_every, chunk, vmax,
    mass, ndamp, sa, sb, stiff, sdamp, relaxed, shorten, scol, panels, pw, pdrag,
    fin_nodes, fin_fwd, fin_span, fin_area, fin_angle, fin_act, front, back, rest_pos, med,
    rec, final_pos, final_vel, failed_step, slow_idx, fast_idx, substeps, slow_nodes, fast_nodes,
):  # fmt: skip
    """Step every candidate through all activation rows; fills rec, final_* and failed_step.

    ``slow_idx`` / ``fast_idx`` split the springs (``multirate.split``): every other force
    kicks the velocities once, then the fast springs drive ``substeps`` sub-steps of
    dt / substeps (nodal damping implicit in each) of the ``fast_nodes`` they touch; the
    ``slow_nodes`` (all of them when there is no split) step once.
    """
    n_nodes = mass.shape[0]
    n_lanes = pos0.shape[2]
    n_chunks = (n_lanes + chunk - 1) // chunk
    body = (mass, ndamp, sa, sb, stiff, sdamp, relaxed, shorten, scol, panels, pw, pdrag,
            fin_nodes, fin_fwd, fin_span, fin_area, fin_angle, fin_act, front, back,
            rest_pos)  # fmt: skip
    multirate = (slow_idx, fast_idx, substeps, slow_nodes, fast_nodes)
    for c in prange(n_chunks):
        b0 = c * chunk
        nb = min(chunk, n_lanes - b0)
        s = _scratch(n_nodes, nb)
        _chunk_steps(
            s, pos0, vel0, act, dt, record_every, vmax, b0, nb, body, med, rec, final_pos,
            final_vel, failed_step, multirate,
        )  # fmt: skip


# ---- a stateful entry point: one animal's lanes stepped in place, slice after slice ----------
# A call through the dispatcher pays for typing and unboxing each argument (about 60 ns an
# array); ``simulate_chunks`` takes 37 of them: about 5 us a call, against about 15 us of work
# in a 1/30 s slice of one shark. A Stepper holds them all (the body's arrays and the state,
# stepped in place) in one struct that crosses into compiled code as one pointer, and
# ``advance_entry`` skips the dispatcher's typing: a slice costs its steps and about 1.5 us.

_F1 = types.Array(types.float32, 1, "C")
_F2 = types.Array(types.float32, 2, "C")
_F3 = types.Array(types.float32, 3, "C")
_I1 = types.Array(types.int64, 1, "C")
_I2 = types.Array(types.int64, 2, "C")
# the fields in the order of ``simulate_chunks``'s arguments, plus the state
STEPPER_FIELDS = (
    ("pos", _F3), ("vel", _F3), ("dt", types.float32), ("chunk", types.int64),
    ("vmax", types.float32), ("mass", _F1), ("ndamp", _F1), ("sa", _I1), ("sb", _I1),
    ("stiff", _F1), ("sdamp", _F1), ("relaxed", _F1), ("shorten", _F1), ("scol", _I1),
    ("panels", _I2), ("pw", _F2), ("pdrag", _F1), ("fin_nodes", _I2), ("fin_fwd", _I2),
    ("fin_span", _I2), ("fin_area", _F1), ("fin_angle", _F2), ("fin_act", _I1), ("front", _I1),
    ("back", _I1),
    ("rest_pos", _F2), ("med", _F1), ("fs", _I1), ("failed", _I1), ("slow_idx", _I1),
    ("fast_idx", _I1), ("substeps", types.int64), ("slow_nodes", _I1), ("fast_nodes", _I1),
)  # fmt: skip


@structref.register
class StepperType(types.StructRef):
    """Numba type of a Stepper."""


class Stepper(structref.StructRefProxy):
    """One animal's lanes and everything the kernel needs to step them in place.

    pos, vel: (N, 3, B) float32 state, stepped in place (the World's own arrays); fs: (B,)
    the kernel's failure marks (>= 0 a dead lane); failed: (B,) the step each lane blew up
    at (-1 if not), kept by ``advance``.
    """


structref.define_boxing(StepperType, Stepper)


@typeof_impl.register(Stepper)
def _typeof_stepper(val, c):
    # the generic typeof tries the buffer protocol first, and its exception costs more than
    # the rest of a call
    return val._type

_STEPPER = StepperType(list(STEPPER_FIELDS))


@njit(cache=True)
def _new_stepper(
    pos, vel, dt, chunk, vmax, mass, ndamp, sa, sb, stiff, sdamp, relaxed, shorten, scol,
    panels, pw, pdrag, fin_nodes, fin_fwd, fin_span, fin_area, fin_angle, fin_act, front, back,
    rest_pos, med, fs, failed, slow_idx, fast_idx, substeps, slow_nodes, fast_nodes,
):  # fmt: skip
    st = structref.new(_STEPPER)
    st.pos, st.vel, st.dt, st.chunk, st.vmax = pos, vel, dt, chunk, vmax
    st.mass, st.ndamp, st.sa, st.sb, st.stiff = mass, ndamp, sa, sb, stiff
    st.sdamp, st.relaxed, st.shorten, st.scol, st.panels = sdamp, relaxed, shorten, scol, panels
    st.pw, st.pdrag, st.fin_nodes, st.fin_fwd = pw, pdrag, fin_nodes, fin_fwd
    st.fin_span = fin_span
    st.fin_area, st.fin_angle, st.fin_act, st.front = fin_area, fin_angle, fin_act, front
    st.back, st.rest_pos, st.med, st.fs, st.failed = back, rest_pos, med, fs, failed
    st.slow_idx, st.fast_idx, st.substeps = slow_idx, fast_idx, substeps
    st.slow_nodes, st.fast_nodes = slow_nodes, fast_nodes
    return st


def make_stepper(pos, vel, fs, failed, dt, chunk, vmax, body_arrays, med, split) -> Stepper:
    """Return a Stepper over the state arrays pos/vel (N, 3, B), fs and failed (B,) (all
    stepped in place, so they must be C-contiguous float32 / int64), for a body's
    ``kernel_arrays``, the medium's array and its ``multirate.split``."""
    f32, i64 = np.float32, np.int64
    kinds = [f for _, f in STEPPER_FIELDS[5:27]]
    arrays = [
        np.array(a, dtype=f32 if k.dtype == types.float32 else i64, order="C", copy=True)
        for a, k in zip((*body_arrays, med), kinds, strict=True)
    ]
    slow, fast, substeps, slow_nodes, fast_nodes = (
        np.array(a, dtype=i64, copy=True) if isinstance(a, np.ndarray) else int(a) for a in split
    )
    return _new_stepper(
        pos, vel, f32(dt), int(chunk), f32(vmax), *arrays, fs, failed, slow, fast, substeps,
        slow_nodes, fast_nodes,
    )  # fmt: skip


@njit(cache=True, fastmath=FM, parallel=True, error_model="numpy")
def advance(st, table, t0, t1, base):
    """Step the Stepper's lanes in place through rows t0 .. t1 of ``table`` (T, A, B); a lane
    that blows up is marked in ``st.failed`` at step ``base`` plus its step in the call."""
    act = table[t0:t1]
    pos, vel, fs, failed = st.pos, st.vel, st.fs, st.failed
    body = (st.mass, st.ndamp, st.sa, st.sb, st.stiff, st.sdamp, st.relaxed, st.shorten,
            st.scol, st.panels, st.pw, st.pdrag, st.fin_nodes, st.fin_fwd, st.fin_span,
            st.fin_area, st.fin_angle, st.fin_act, st.front, st.back, st.rest_pos)  # fmt: skip
    multirate = (st.slow_idx, st.fast_idx, st.substeps, st.slow_nodes, st.fast_nodes)
    dt, chunk, vmax, med = st.dt, st.chunk, st.vmax, st.med
    n_lanes = pos.shape[2]
    n_nodes = pos.shape[0]
    no_rec = np.empty((0, n_nodes, 3, n_lanes), dtype=np.float32)  # record_every 0: none
    for c in prange((n_lanes + chunk - 1) // chunk):
        b0 = c * chunk
        nb = min(chunk, n_lanes - b0)
        s = _scratch(n_nodes, nb)  # fresh arrays, not a block kept in the Stepper
        _chunk_steps(
            s, pos, vel, act, dt, 0, vmax, b0, nb, body, med, no_rec, pos, vel, fs,
            multirate,
        )  # fmt: skip
    for b in range(n_lanes):
        if failed[b] < 0 and fs[b] >= 0:
            failed[b] = base + fs[b]


def serial(fn):
    """Return ``fn`` (an njit(parallel=True) function of this module) compiled for one thread
    (its ``prange`` runs as ``range``): no thread-pool launch, which costs more than a short
    slice of one animal. A copy under its own name, so that its on-disk cache entry is apart
    from the parallel one's (numba keys the cache by the function's qualified name)."""
    py = fn.py_func
    name = f"{py.__name__}_serial"
    copy = pytypes.FunctionType(py.__code__, py.__globals__, name, py.__defaults__,
                                py.__closure__)  # fmt: skip
    copy.__qualname__ = name
    return njit(cache=True, fastmath=FM, error_model="numpy")(copy)


def advance_entry(parallel: bool):
    """Return ``advance`` (threaded or serial) compiled for a Stepper and a float32 table, as
    its compiled entry point: calling that skips the dispatcher's typing of each argument
    (about 0.6 us of a 2 us call, which matters in 1/30 s slices of one animal). The
    arguments must then have exactly those types: (Stepper, float32 (T, A, B) C array, int,
    int, int)."""
    fn = advance if parallel else _serial_advance()
    return fn.compile((_STEPPER, _F3, types.int64, types.int64, types.int64))


_SERIAL_ADVANCE = []


def _serial_advance():
    if not _SERIAL_ADVANCE:
        _SERIAL_ADVANCE.append(serial(advance))
    return _SERIAL_ADVANCE[0]
