"""The force law and the step, written once for NumPy and JAX (an array-module argument ``xp``).

Every function takes the array module (``numpy`` or ``jax.numpy``), a ``model.Model`` and
positions and velocities shaped (..., N, 3) with activations (..., A): the NumPy reference
steps a batch (B, N, 3) in float64, the JAX mirror one candidate (N, 3) in float32 under
``vmap``. The terms are those of the Numba kernel (``kernel_terms``), its hand-tuned twin:
springs and muscles, gravity and buoyancy, water panels whose force can at most stop a panel's
normal motion in one step, fins, a penalty floor with implicit directional Coulomb friction,
implicit nodal damping, semi-implicit Euler with the stiff springs sub-stepped after one kick
of everything else (``multirate.split``). Conformance tests hold the three equal.

NumPy arrays are values here as JAX arrays are: nothing is changed in place. The two modules
differ only in how entries are written (``add_at``, ``set_at``). Terms are added where the JAX
mirror always added them: XLA fuses elementwise work and may contract a multiply and an add, so
the same sums written another way can round differently. Square roots and unit
vectors are guarded (the double-``where`` trick) so that JAX gradients stay finite at rest,
where velocities are exactly zero.
"""

from __future__ import annotations

import numpy as np

from zoetic.physics.model import Model

TINY = 1e-12  # the kernel's guard on lengths
TINY2 = 1e-30  # the kernel's guard on squared panel normals


def add_at(xp, out, index, values, unique: bool = False):
    """Return ``out`` with ``values`` added at ``out[index]``: repeated entries add up, unless
    the caller knows there are none (``unique``: NumPy then adds in one pass)."""
    if xp is np:
        out = out.copy()
        if unique:
            out[index] += values
        else:
            np.add.at(out, index, values)
        return out
    return out.at[index].add(values)


def set_at(xp, out, index, values):
    """Return ``out`` with ``out[index]`` replaced by ``values``."""
    if xp is np:
        out = out.copy()
        out[index] = values
        return out
    return out.at[index].set(values)


def rows(idx):
    """Return the index of node rows ``idx`` in an array (..., N, 3)."""
    return (..., idx, slice(None))


def _safe_sqrt(xp, s):
    """Return sqrt(s) for s >= 0 with a zero (not NaN) gradient at s = 0."""
    pos = s > 0
    return xp.where(pos, xp.sqrt(xp.where(pos, s, 1.0)), 0.0)


def _norm(xp, a):
    return _safe_sqrt(xp, xp.sum(a * a, axis=-1))


def _unit(xp, a):
    return a / (_norm(xp, a) + TINY)[..., None]


def springs(xp, m: Model, x, v, a, idx):
    """Return the nodal forces (..., N, 3) of the springs with indices ``idx`` (NumPy, fixed
    when JAX traces)."""
    sa, sb = m.spring_a[idx], m.spring_b[idx]
    d = x[..., sb, :] - x[..., sa, :]
    length = _norm(xp, d) + TINY
    u = d / length[..., None]
    rest = m.relaxed[idx] + a[..., m.spring_col[idx]] * (m.contracted[idx] - m.relaxed[idx])
    edot = xp.sum((v[..., sb, :] - v[..., sa, :]) * u, axis=-1)
    fs = (m.stiffness[idx] * (length - rest) + m.spring_damping[idx] * edot)[..., None] * u
    return add_at(xp, add_at(xp, xp.zeros_like(x), rows(sa), fs), rows(sb), -fs)


def weight(xp, m: Model, x):
    """Return gravity and, below the water level, buoyancy (..., N) along y."""
    g = m.gravity
    return xp.where(x[..., 1] < m.water_level, m.mass * (g * m.buoyancy - g), -m.mass * g)


def water(xp, m: Model, x, v):
    """Return the water's reaction on the surface panels (Tu & Terzopoulos), shared by each
    panel's nodes: it opposes a panel's outward normal velocity, c * drag * A * |v| (n.v),
    and at most stops the panel's normal motion in one step."""
    w = m.panel_weights  # (P, 4)
    p = x[..., m.panels, :]  # (..., P, 4, 3)
    nrm = xp.cross(p[..., 2, :] - p[..., 0, :], p[..., 3, :] - p[..., 1, :])  # 2 A n
    nn = xp.sum(nrm * nrm, axis=-1) + TINY2
    vm = xp.einsum("...pkd,pk->...pd", v[..., m.panels, :], w)
    q = xp.maximum(xp.sum(nrm * vm, axis=-1), 0.0)
    vv = xp.sum(vm * vm, axis=-1)
    lim = xp.minimum(0.5 * m.water_drag * m.panel_drag * _safe_sqrt(xp, nn * vv), m.panel_mass_dt)
    wet = xp.einsum("...pk,pk->...p", p[..., 1], w) < m.water_level
    mag = xp.where(wet, q / nn * lim, 0.0)
    fp = -(w * mag[..., None])[..., None] * nrm[..., None, :]  # (..., P, 4, 3)
    at = rows(m.panels.reshape(-1))
    return add_at(xp, xp.zeros_like(x), at, fp.reshape(*fp.shape[:-3], -1, 3))


def fins(xp, m: Model, x, v, a):
    """Return the fins' forces: flat plates at their actuator's angle to the body, pushed on
    by the water (at most stopping their normal motion in one step)."""
    fwd = _unit(xp, x[..., m.fin_forward[:, 0], :] - x[..., m.fin_forward[:, 1], :])
    span = x[..., m.fin_span[:, 0], :] - x[..., m.fin_span[:, 1], :]
    span = _unit(xp, span - xp.sum(span * fwd, -1, keepdims=True) * fwd)
    up = xp.cross(fwd, span)
    lo, hi = m.fin_angle[:, 0], m.fin_angle[:, 1]
    ang = lo + a[..., m.fin_actuator] * (hi - lo)
    nrm = xp.cos(ang)[..., None] * up + xp.sin(ang)[..., None] * fwd
    nodes = np.maximum(m.fin_nodes, 0)  # padding: node 0 at weight 0
    wts = m.fin_weights
    vm = xp.einsum("...kqd,kq->...kd", v[..., nodes, :], wts)
    cy = xp.einsum("...kq,kq->...k", x[..., nodes, 1], wts)
    vn = xp.sum(nrm * vm, axis=-1)
    cap = m.fin_mass * xp.abs(vn) / m.dt
    mag = xp.clip(m.water_drag * m.fin_area * _norm(xp, vm) * vn, -cap, cap)
    mag = xp.where(cy < m.water_level, mag, 0.0)
    fq = -(wts * mag[..., None])[..., None] * nrm[..., None, :]  # (..., K, 4, 3)
    return add_at(xp, xp.zeros_like(x), rows(nodes.reshape(-1)), fq.reshape(*fq.shape[:-3], -1, 3))


def ground(xp, m: Model, x, v, f_other):
    """Return the floor's forces: a penalty normal force at y = 0 and directional Coulomb
    friction along the local body axis, solved against the velocity ``f_other`` would give."""
    dt = m.dt
    pen = -x[..., 1]
    normal = m.floor_stiffness * pen - m.floor_damping * v[..., 1]
    normal = xp.where((pen > 0) & (normal > 0), normal, 0.0)
    t = _unit(xp, (x[..., m.axis_front, :] - x[..., m.axis_back, :])[..., np.array([0, 2])])
    tx, tz = t[..., 0], t[..., 1]
    px = v[..., 0] + dt * f_other[..., 0] / m.mass
    pz = v[..., 2] + dt * f_other[..., 2] / m.mass
    vf = px * tx + pz * tz
    vl = pz * tx - px * tz
    mu = xp.where(vf > 0, m.friction_forward, m.friction_backward)
    ff = xp.minimum(mu * normal, m.mass * xp.abs(vf) / dt)
    fl = xp.minimum(m.friction_lateral * normal, m.mass * xp.abs(vl) / dt)
    ff = xp.where(vf > 0, -ff, ff)
    fl = xp.where(vl > 0, -fl, fl)
    return xp.stack([ff * tx - fl * tz, normal, ff * tz + fl * tx], axis=-1)


def forces(xp, m: Model, x, v, a, idx):
    """Return the total nodal forces (..., N, 3) with the springs ``idx`` (the step passes the
    slow ones; every other term in full)."""
    f = springs(xp, m, x, v, a, idx)
    f = add_at(xp, f, (..., 1), weight(xp, m, x), unique=True)
    if m.water:
        f = f + water(xp, m, x, v)
        if m.fin_area.shape[0]:
            f = f + fins(xp, m, x, v, a)
    if m.floor:
        f = f + ground(xp, m, x, v, f)
    return f


def step(xp, m: Model, x, v, a):
    """Return (x, v) after one semi-implicit Euler step of dt (nodal damping implicit): every
    force but the stiff springs kicks once, then those drive ``m.substeps`` sub-steps of the
    nodes they touch (impulse multirate, ``multirate.split``)."""
    real = m.mass.dtype.type
    hm = (m.dt / m.mass)[:, None]
    damp = 1.0 / (1.0 + hm * m.node_damping[:, None])
    f = forces(xp, m, x, v, a, m.slow_springs)
    vs = (v + hm * f) * damp
    xs = x + m.dt * vs
    if m.fast_springs.shape[0] == 0:
        return xs, vs
    sn, fn = m.slow_nodes, m.fast_nodes  # nodes no stiff spring touches: as without a split
    x, v = set_at(xp, x, rows(sn), xs[..., sn, :]), set_at(xp, v, rows(sn), vs[..., sn, :])
    v = add_at(xp, v, rows(fn), hm[fn] * f[..., fn, :], unique=True)  # a kick, then sub-steps
    h = real(m.dt) / real(m.substeps)
    hms = (h / m.mass[fn])[:, None]
    damps = 1.0 / (1.0 + hms * m.node_damping[fn][:, None])
    for _ in range(m.substeps):
        fq = springs(xp, m, x, v, a, m.fast_springs)[..., fn, :]
        vq = (v[..., fn, :] + hms * fq) * damps
        x, v = add_at(xp, x, rows(fn), h * vq, unique=True), set_at(xp, v, rows(fn), vq)
    return x, v
