"""The differentiable path: the JAX mirror of the physics step, float32, on any device JAX sees.

The step is ``physics.law``'s, the very functions the NumPy reference runs, evaluated with
``jax.numpy`` on the body's float32 ``Model`` (the arrays the Numba kernel reads). The model is
held as constants of the traced step; ``jit`` and ``vmap`` are applied only at the edge
(``make_rollout``; losses in ``learning.gradient``), brax-style.

Unlike the Numba kernel, a candidate that blows up is not reset to rest: its state simply
becomes large or non-finite, and ``blown_up`` tells which ones did.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from zoetic.bodies import Body
from zoetic.errors import SimulationError
from zoetic.physics import law
from zoetic.physics.media import Medium
from zoetic.physics.model import compile_model
from zoetic.physics.simulate import VMAX

F32 = jnp.float32


def make_step(body: Body, medium: str | Medium | None = None, dt: float | None = None):
    """Return the pure step ``(x (N,3), v (N,3), a (A,)) -> (x, v)`` of one candidate."""
    m = compile_model(body, medium, dt)

    def step(x: jax.Array, v: jax.Array, a: jax.Array) -> tuple[jax.Array, jax.Array]:
        return law.step(jnp, m, x, v, a)

    return step


def rollout_fn(body: Body, medium=None, dt: float | None = None, record_every: int = 1):
    """Return the un-jitted single-candidate rollout ``(x0, v0, act (T,A)) -> (rec, x, v)``.

    ``rec`` holds the positions (R, N, 3) at steps 0, k, 2k, ... (R = T // k + 1) exactly as
    ``simulate`` records them; activations are clipped to [0, 1] as ``simulate`` does.
    """
    if record_every < 1:
        raise SimulationError("record_every must be at least 1")
    step = make_step(body, medium, dt)

    def inner(carry, a):
        return step(*carry, a), None

    def outer(carry, chunk):
        carry, _ = jax.lax.scan(inner, carry, chunk)
        return carry, carry[0]

    def rollout(x0: jax.Array, v0: jax.Array, act: jax.Array):
        act = jnp.clip(jnp.asarray(act, F32), 0.0, 1.0)
        x0, v0 = jnp.asarray(x0, F32), jnp.asarray(v0, F32)
        n_rec = act.shape[0] // record_every
        main = act[: n_rec * record_every].reshape(n_rec, record_every, act.shape[1])
        carry, recs = jax.lax.scan(outer, (x0, v0), main)
        carry, _ = jax.lax.scan(inner, carry, act[n_rec * record_every :])
        return jnp.concatenate([x0[None], recs]), carry[0], carry[1]

    return rollout


def make_rollout(body: Body, medium=None, dt: float | None = None, record_every: int = 1):
    """Return the jitted batch rollout ``(pos0 (B,N,3), vel0, act (B,T,A)) -> (rec, x, v)``.

    ``rec`` is (B, R, N, 3); the final positions and velocities are (B, N, 3). It compiles
    once per shape; a second call with the same shapes reuses the compiled code.
    """
    return jax.jit(jax.vmap(rollout_fn(body, medium, dt, record_every)))


def blown_up(positions: jax.Array, velocities: jax.Array) -> jax.Array:
    """Return a (B,) bool array: True where a candidate's state is non-finite or too fast."""
    speed2 = jnp.sum(velocities * velocities, axis=-1).max(axis=-1)
    finite = jnp.isfinite(positions).all(axis=(-1, -2)) & jnp.isfinite(speed2)
    return ~finite | (speed2 >= VMAX * VMAX)
