"""The NumPy reference: ``physics.law`` in float64, the yardstick for the kernel.

It exists to be read and to be compared against: the conformance tests check the Numba kernel
against it, and the benchmark reports the kernel's speed as a ratio to it. Its step is the JAX
mirror's, the same functions evaluated with NumPy on the body's float64 ``Model``.
"""

from __future__ import annotations

import numpy as np

from zoetic.bodies import Body
from zoetic.physics import law
from zoetic.physics.media import Medium, get_medium
from zoetic.physics.model import Model, compile_model
from zoetic.physics.simulate import State, rest_state


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
    if act.shape[2] == 0:  # a body without actuators: one zero column, as the kernel reads
        act = np.zeros((*act.shape[:2], 1))
    m = compile_model(body, medium, dt, dtype=np.float64)
    state = state or rest_state(body, act.shape[0])
    x = law.to_soa(np, state.positions.astype(np.float64))
    v = law.to_soa(np, state.velocities.astype(np.float64))
    for t in range(act.shape[1]):
        x, v = law.step_soa(np, m, x, v, act[:, t].T)
    batch = state.positions.shape[:1]
    return State(*(np.ascontiguousarray(law.from_soa(np, q, batch)) for q in (x, v)))


def _spring_jacobians(m: Model, x: np.ndarray, a: np.ndarray):
    """Return dF/dx and dF/dv (B, 3N, 3N) of the spring forces (compression stiffness >= 0)."""
    bsz, n = x.shape[0], m.mass.shape[0]
    sa, sb = m.spring_a, m.spring_b
    d = x[:, sb] - x[:, sa]
    length = np.linalg.norm(d, axis=-1) + 1e-12
    u = d / length[..., None]
    rest = m.relaxed + a[:, m.spring_col] * (m.contracted - m.relaxed)
    uu = u[..., :, None] * u[..., None, :]
    geo = np.clip(1.0 - rest / length, 0.0, None)[..., None, None]
    ks = m.stiffness[None, :, None, None] * (uu + geo * (np.eye(3) - uu))
    cs = m.spring_damping[None, :, None, None] * uu
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
    m = compile_model(body, get_medium(med), dt, dtype=np.float64)
    bsz, n = x.shape[0], body.n_nodes
    f = law.forces(np, m, x, v, a, np.arange(body.n_springs))
    jx, jv = _spring_jacobians(m, x, a)
    mass = np.repeat(m.mass, 3)
    gam = np.repeat(m.node_damping, 3)
    lhs = np.diag(mass + dt * gam)[None] - dt * jv - dt * dt * jx
    vf = v.reshape(bsz, 3 * n)
    rhs = dt * (f.reshape(bsz, 3 * n) - gam * vf + np.einsum("bij,bj->bi", jx, vf) * dt)
    dv = np.linalg.solve(lhs, rhs[..., None])[..., 0].reshape(bsz, n, 3)
    v = v + dv
    return x + dt * v, v
