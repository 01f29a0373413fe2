"""A plain vectorised NumPy implementation of the same step: the yardstick for the kernel.

It exists to be read and to be compared against: the conformance test checks the Numba kernel
against it, and the benchmark reports the kernel's speed as a ratio to it.
"""

from __future__ import annotations

import numpy as np

from zoetic.bodies import Body
from zoetic.physics.media import Medium, get_medium
from zoetic.physics.multirate import split
from zoetic.physics.simulate import State, rest_state


def _scatter(n: int, idx: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Sum values (B, K, 3) into (B, n, 3) at node indices idx (K,)."""
    out = np.zeros((values.shape[0], n, 3))
    np.add.at(out, (slice(None), idx), values)
    return out


def spring_forces(body: Body, x: np.ndarray, v: np.ndarray, a: np.ndarray, springs=None):
    """Return the nodal forces (B, N, 3) of the springs with indices ``springs`` (default all)."""
    idx = np.arange(body.n_springs) if springs is None else np.asarray(springs)
    n = body.n_nodes
    sa, sb = body.spring_a[idx], body.spring_b[idx]
    d = x[:, sb] - x[:, sa]
    length = np.linalg.norm(d, axis=-1) + 1e-12
    u = d / length[..., None]
    muscle = body.spring_actuator[idx]
    act = np.where(muscle >= 0, a[:, muscle], 0.0)
    rest = body.relaxed[idx] + act * (body.contracted[idx] - body.relaxed[idx])
    edot = np.einsum("bsk,bsk->bs", v[:, sb] - v[:, sa], u)
    mag = body.stiffness[idx] * (length - rest) + body.spring_damping[idx] * edot
    fs = mag[..., None] * u
    return _scatter(n, sa, fs) - _scatter(n, sb, fs)


def forces(
    body: Body, x: np.ndarray, v: np.ndarray, a: np.ndarray, med: Medium, dt: float, springs=None
):
    """Return the total nodal forces (B, N, 3) for positions, velocities and activations (B, A)
    with the springs ``springs`` (default all; ``step`` passes the slow ones)."""
    f = spring_forces(body, x, v, a, springs)
    wet = x[..., 1] < med.water_level
    f[..., 1] += body.mass * med.gravity * (med.buoyancy * wet - 1.0)
    if med.water_drag > 0 and med.water_level > -1e8:
        f += _water(body, x, v, med, dt)
        if len(body.fin_area):
            f += _fins(body, x, v, a, med, dt)
    if med.floor:
        f += _ground(body, x, v, f, med, dt)
    return f


def _water(body: Body, x, v, med: Medium, dt: float) -> np.ndarray:
    idx, w = body.panels, body.panel_weights
    p = x[:, idx]  # (B, P, 4, 3)
    nrm = np.cross(p[:, :, 2] - p[:, :, 0], p[:, :, 3] - p[:, :, 1])
    twice_area = np.linalg.norm(nrm, axis=-1) + 1e-12
    nhat = nrm / twice_area[..., None]
    vm = np.einsum("bpkd,pk->bpd", v[:, idx], w)
    vn = np.maximum(np.einsum("bpk,bpk->bp", nhat, vm), 0.0)
    speed = np.linalg.norm(vm, axis=-1)
    wet = np.einsum("bpk,pk->bp", x[:, idx, 1], w) < med.water_level
    mf = np.einsum("pk,pk->p", body.mass[idx], w) / w[:, 0]
    c = med.water_drag * body.panel_drag
    mag = np.minimum(c * 0.5 * twice_area * speed * vn, mf * vn / dt) * wet
    out = np.zeros_like(x)
    for k in range(4):
        out += _scatter(body.n_nodes, idx[:, k], -(mag * w[:, k])[..., None] * nhat)
    return out


def _unit(a: np.ndarray) -> np.ndarray:
    return a / (np.linalg.norm(a, axis=-1, keepdims=True) + 1e-12)


def _fins(body: Body, x, v, a, med: Medium, dt: float) -> np.ndarray:
    out = np.zeros_like(x)
    for k in range(len(body.fin_area)):
        nodes = body.fin_nodes[k][body.fin_nodes[k] >= 0]
        fwd = _unit(x[:, body.fin_forward[k, 0]] - x[:, body.fin_forward[k, 1]])
        span = x[:, body.fin_span[k, 0]] - x[:, body.fin_span[k, 1]]
        span = _unit(span - np.sum(span * fwd, -1, keepdims=True) * fwd)
        up = np.cross(fwd, span)
        lo, hi = body.fin_angle[k]
        ang = lo + a[:, body.fin_actuator[k]] * (hi - lo)
        nrm = np.cos(ang)[:, None] * up + np.sin(ang)[:, None] * fwd
        vm = v[:, nodes].mean(axis=1)
        vn = np.sum(nrm * vm, -1)
        wet = x[:, nodes, 1].mean(axis=1) < med.water_level
        cap = body.mass[nodes].sum() * np.abs(vn) / dt
        mag = np.clip(med.water_drag * body.fin_area[k] * np.linalg.norm(vm, axis=-1) * vn,
                      -cap, cap) * wet / len(nodes)  # fmt: skip
        out[:, nodes] -= (mag[:, None] * nrm)[:, None, :]
    return out


def _ground(body: Body, x, v, f_other, med: Medium, dt: float) -> np.ndarray:
    m = body.mass[None, :]
    pen = -x[..., 1]
    normal = np.where(pen > 0, np.maximum(med.floor_stiffness * pen - med.floor_damping * v[..., 1],
                                          0.0), 0.0)  # fmt: skip
    t = x[:, body.axis_front][..., [0, 2]] - x[:, body.axis_back][..., [0, 2]]
    t = _unit(t)
    pred = v[..., [0, 2]] + dt * f_other[..., [0, 2]] / m[..., None]
    vf = np.sum(pred * t, -1)
    vl = pred[..., 1] * t[..., 0] - pred[..., 0] * t[..., 1]
    mu = np.where(vf > 0, med.friction_forward, med.friction_backward)
    ff = -np.sign(vf) * np.minimum(mu * normal, m * np.abs(vf) / dt)
    fl = -np.sign(vl) * np.minimum(med.friction_lateral * normal, m * np.abs(vl) / dt)
    out = np.zeros_like(x)
    out[..., 0] = ff * t[..., 0] - fl * t[..., 1]
    out[..., 2] = ff * t[..., 1] + fl * t[..., 0]
    out[..., 1] = normal
    return out


def step(body: Body, x, v, a, med: Medium, dt: float):
    """Return (x, v) after one semi-implicit Euler step of the same scheme as the kernel: the
    springs too stiff for dt (``multirate.split``) in sub-steps after one kick of the rest."""
    sp = split(body, dt)
    f = forces(body, x, v, a, med, dt, sp.slow_springs)
    x, v = x.copy(), v.copy()
    s, q = sp.slow_nodes, sp.fast_nodes
    x[:, s], v[:, s] = _advance(body, s, x[:, s], v[:, s], f[:, s], dt)
    if len(q) == 0:
        return x, v
    v[:, q] += dt * f[:, q] / body.mass[None, q, None]  # one kick of the rest (impulse order)
    for _ in range(sp.substeps):
        g = spring_forces(body, x, v, a, sp.fast_springs)[:, q]
        x[:, q], v[:, q] = _advance(body, q, x[:, q], v[:, q], g, dt / sp.substeps)
    return x, v


def _advance(body: Body, nodes, x, v, f, h: float):
    hm = h / body.mass[None, nodes, None]
    v = (v + hm * f) / (1.0 + hm * body.node_damping[None, nodes, None])
    return x + h * v, v


def simulate_reference(
    body: Body,
    activations: np.ndarray,
    medium: str | Medium | None = None,
    dt: float | None = None,
    state: State | None = None,
) -> State:
    """Return the final State after stepping every candidate through its activation table."""
    act = np.clip(np.asarray(activations, dtype=np.float64), 0.0, 1.0)
    if act.ndim == 2:
        act = act[None]
    med = get_medium(medium or body.medium)
    dt = float(dt or body.dt)
    state = state or rest_state(body, act.shape[0])
    x, v = state.positions.astype(np.float64), state.velocities.astype(np.float64)
    for t in range(act.shape[1]):
        x, v = step(body, x, v, act[:, t], med, dt)
    return State(x, v)


def _spring_jacobians(body: Body, x: np.ndarray, a: np.ndarray):
    """Return dF/dx and dF/dv (B, 3N, 3N) of the spring forces (compression stiffness >= 0)."""
    bsz, n = x.shape[0], body.n_nodes
    sa, sb = body.spring_a, body.spring_b
    d = x[:, sb] - x[:, sa]
    length = np.linalg.norm(d, axis=-1) + 1e-12
    u = d / length[..., None]
    act = np.where(body.spring_actuator >= 0, a[:, body.spring_actuator], 0.0)
    rest = body.relaxed + act * (body.contracted - body.relaxed)
    uu = u[..., :, None] * u[..., None, :]
    geo = np.clip(1.0 - rest / length, 0.0, None)[..., None, None]
    ks = body.stiffness[None, :, None, None] * (uu + geo * (np.eye(3) - uu))
    cs = body.spring_damping[None, :, None, None] * uu
    jx = np.zeros((bsz, 3 * n, 3 * n))
    jv = np.zeros((bsz, 3 * n, 3 * n))
    for s, (i, j) in enumerate(zip(sa, sb, strict=True)):
        for J, blk in ((jx, ks[:, s]), (jv, cs[:, s])):
            ii, jj = slice(3 * i, 3 * i + 3), slice(3 * j, 3 * j + 3)
            J[:, ii, ii] -= blk
            J[:, jj, jj] -= blk
            J[:, ii, jj] += blk
            J[:, jj, ii] += blk
    return jx, jv


def step_semi_implicit(body: Body, x, v, a, med: Medium, dt: float):
    """Return (x, v) after one step of the papers' scheme: implicit in the internal (spring and
    nodal damping) forces, explicit in the external ones (linearised backward Euler)."""
    bsz, n = x.shape[0], body.n_nodes
    f = forces(body, x, v, a, med, dt)
    jx, jv = _spring_jacobians(body, x, a)
    m = np.repeat(body.mass, 3)
    gam = np.repeat(body.node_damping, 3)
    lhs = np.diag(m + dt * gam)[None] - dt * jv - dt * dt * jx
    vf = v.reshape(bsz, 3 * n)
    rhs = dt * (f.reshape(bsz, 3 * n) - gam * vf + np.einsum("bij,bj->bi", jx, vf) * dt)
    dv = np.linalg.solve(lhs, rhs[..., None])[..., 0].reshape(bsz, n, 3)
    v = v + dv
    return x + dt * v, v
