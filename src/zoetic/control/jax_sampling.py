"""Controllers sampled in JAX: a learnable controller's activation table as a function of p.

Time-domain (linear or B-spline) and frequency-domain controllers are linear in their (A, M)
parameters, so their table is ``clip(B @ p.T, 0, 1)`` with a constant basis B (T, M).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from zoetic.control.controllers import (
    Controller,
    FrequencyDomainController,
    TimeDomainController,
)
from zoetic.errors import ControllerError

F32 = jnp.float32


def _tents(t: jax.Array, duration: float, nodes: int) -> jax.Array:
    """Return the (T, M) piecewise-linear interpolation basis on M even nodes over duration."""
    tc = jnp.clip(t, 0.0, duration)
    knots = jnp.linspace(0.0, duration, nodes, dtype=F32)
    h = duration / (nodes - 1)
    return jnp.maximum(1.0 - jnp.abs(tc[:, None] - knots[None, :]) / h, 0.0)


def _basis(ctrl: Controller, t: np.ndarray) -> jax.Array:
    """Return the (T, M) basis B of a controller linear in its (A, M) parameters."""
    tj = jnp.asarray(t, F32)
    if isinstance(ctrl, TimeDomainController) and ctrl.interp == "linear":
        return _tents(tj, float(ctrl.duration), ctrl.nodes)
    if isinstance(ctrl, FrequencyDomainController):
        om, ph = jnp.asarray(ctrl.omega, F32), jnp.asarray(ctrl.phase, F32)
        return jnp.cos(tj[:, None] * om[None, :] + ph[None, :])
    if isinstance(ctrl, TimeDomainController):  # B-spline: a constant basis, sampled once
        m = ctrl.nodes
        cols = [ctrl.with_params(np.tile(e, ctrl.n_actuators)).raw(t)[:, 0] for e in np.eye(m)]
        return jnp.asarray(np.stack(cols, axis=1), F32)
    raise ControllerError(
        f"no JAX sampling for a learnable {ctrl.kind!r} controller (time or frequency only)"
    )


def jax_table(ctrl: Controller, steps: int, dt: float, t0: float = 0.0):
    """Return ``p -> activations (steps, A)`` in [0, 1]: the controller's table, differentiable.

    A controller without learnable parameters gives its fixed table for any (empty) p.
    """
    t = t0 + np.arange(steps) * dt
    n_params = ctrl.params().size
    if n_params == 0:
        fixed = jnp.asarray(ctrl.table(steps, dt, t0), F32)
        return lambda p: fixed
    basis = _basis(ctrl, t)  # (T, M)
    shape = (ctrl.n_actuators, basis.shape[1])
    if shape[0] * shape[1] != n_params:
        raise ControllerError(f"{ctrl.kind} controller: {n_params} parameters, expected {shape}")

    def table(p: jax.Array) -> jax.Array:
        return jnp.clip(basis @ jnp.reshape(p, shape).T, 0.0, 1.0)

    return table
