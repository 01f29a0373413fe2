"""The differentiable path: the JAX mirror of the physics step, float32, on any device JAX sees.

The step is ``physics.law``'s, the very functions the NumPy reference runs, evaluated with
``jax.numpy`` on the body's float32 ``Model`` (the arrays the Numba kernel reads). The model is
held as constants of the traced step. The law steps a whole batch at once with the batch as the
innermost axis (positions (N, 3, B)), so a rollout needs no ``vmap``: XLA sees rows of B lanes
and vectorises over candidates, as the Numba kernel does. One candidate is a batch of one.

Unlike the Numba kernel, a candidate that blows up is not reset to rest: its state simply
becomes large or non-finite, and ``blown_up`` tells which ones did.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import jax
import jax.numpy as jnp

from zoetic.bodies import Body
from zoetic.errors import SimulationError
from zoetic.physics import law
from zoetic.physics.jax_programs import StoredProgram, fingerprint
from zoetic.physics.media import Medium
from zoetic.physics.model import compile_model
from zoetic.physics.simulate import VMAX

F32 = jnp.float32
CPU_LANES = 128  # candidates stepped together on a CPU (measured: 64-256 alike, 1024 slower)
CACHE_ENV = "ZOETIC_JAX_CACHE"  # where compiled programs persist; set empty for none


def cache_dir() -> Path | None:
    """Return where zoetic keeps JAX's compiled programs between runs: $ZOETIC_JAX_CACHE
    (empty: nowhere), else $XDG_CACHE_HOME/zoetic/jax, else ~/.cache/zoetic/jax."""
    given = os.environ.get(CACHE_ENV)
    if given is not None:
        return Path(given).expanduser() if given.strip() else None
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "zoetic" / "jax"


def use_compilation_cache() -> str | None:
    """Point JAX's persistent compilation cache at ``cache_dir()`` unless one is set already
    (``JAX_COMPILATION_CACHE_DIR`` or ``jax.config``), so that a later process skips XLA's
    compile of the same program (the gradient's takes seconds); return the directory in use."""
    current = jax.config.jax_compilation_cache_dir
    if current:
        return current
    where = cache_dir()
    if where is None:
        return None
    jax.config.update("jax_compilation_cache_dir", str(where))
    return str(where)


use_compilation_cache()


def make_step(body: Body, medium: str | Medium | None = None, dt: float | None = None):
    """Return the pure step ``(x (N,3,B), v (N,3,B), a (A,B)) -> (x, v)`` of a batch in the
    law's layout (B = 1 for one candidate)."""
    m = compile_model(body, medium, dt)

    def step(x: jax.Array, v: jax.Array, a: jax.Array) -> tuple[jax.Array, jax.Array]:
        return law.step_soa(jnp, m, x, v, a)

    return step


def lanes() -> int | None:
    """Return how many candidates the rollout steps together on this JAX backend: on a CPU a
    chunk whose arrays stay in the core's cache (larger batches run as several chunks, on
    all cores in ``make_rollout``, one after another inside ``rollout_fn``), on an
    accelerator the whole batch (None)."""
    return CPU_LANES if jax.default_backend() == "cpu" else None


def rollout_fn(body: Body, medium=None, dt: float | None = None, record_every: int = 1):
    """Return the un-jitted rollout ``(x0, v0, act) -> (rec, x, v)``.

    One candidate: x0, v0 (N, 3), act (T, A); rec (R, N, 3). A batch: x0, v0 (B, N, 3) and
    act (B, T, A), or (T, A) shared by every candidate (a task's start states); rec
    (B, R, N, 3). ``rec`` holds the positions at steps 0, k, 2k, ... (R = T // k + 1) exactly
    as ``simulate`` records them; activations are clipped to [0, 1] as ``simulate`` does.
    """
    if record_every < 1:
        raise SimulationError("record_every must be at least 1")
    run = _soa_rollout(make_step(body, medium, dt), record_every)

    def rollout(x0: jax.Array, v0: jax.Array, act: jax.Array):
        x0, v0 = jnp.asarray(x0, F32), jnp.asarray(v0, F32)
        batch = x0.shape[:-2]
        act = jnp.clip(jnp.asarray(act, F32), 0.0, 1.0)
        # (T, A, B): a row of activations per step, the batch innermost (1: shared)
        act = jnp.moveaxis(act, 0, -1) if act.ndim == 3 else act[..., None]
        recs, x, v = _in_chunks(run, law.to_soa(jnp, x0), law.to_soa(jnp, v0), act, lanes())
        rec = jnp.transpose(recs, (3, 0, 1, 2))  # (B, R, N, 3)
        rec = jnp.reshape(rec, (*batch, *rec.shape[1:]))
        return rec, law.from_soa(jnp, x, batch), law.from_soa(jnp, v, batch)

    return rollout


def _soa_rollout(step, record_every: int):
    """Return ``(x, v (N,3,B), act (T,A,B)) -> (rec (R,N,3,B), x, v)`` in the law's layout."""

    # rematerialised under differentiation: the backward pass keeps only each step's state and
    # recomputes the step's intermediates, instead of stacking every one of them over the
    # horizon (half the compile time and half the gradient's run time, measured on the shark)
    step = jax.checkpoint(step, prevent_cse=False)

    def inner(carry, a):
        return step(*carry, a), None

    def outer(carry, chunk):
        carry, _ = jax.lax.scan(inner, carry, chunk)
        return carry, carry[0]

    def run(x, v, act):
        n_rec = act.shape[0] // record_every
        main = act[: n_rec * record_every].reshape(n_rec, record_every, *act.shape[1:])
        carry, recs = jax.lax.scan(outer, (x, v), main)
        if act.shape[0] > n_rec * record_every:  # the steps after the last record
            carry, _ = jax.lax.scan(inner, carry, act[n_rec * record_every :])
        return jnp.concatenate([x[None], recs]), carry[0], carry[1]

    return run


def _in_chunks(run, x, v, act, chunk: int | None):
    """Return ``run(x, v, act)`` computed ``chunk`` lanes at a time (the batch padded with
    copies of its last candidate to a whole number of chunks), or at once."""
    b = x.shape[-1]
    if chunk is None or b <= chunk:
        return run(x, v, act)
    n = -(-b // chunk)
    shared = act.shape[-1] == 1

    def split(q):  # (..., B) -> (C, ..., chunk)
        q = jnp.concatenate([q, jnp.repeat(q[..., -1:], n * chunk - b, axis=-1)], axis=-1)
        return jnp.moveaxis(q.reshape(*q.shape[:-1], n, chunk), -2, 0)

    def one(args):
        return run(args[0], args[1], act if shared else args[2])

    out = jax.lax.map(one, (split(x), split(v)) + (() if shared else (split(act),)))

    def join(q):  # (C, ..., chunk) -> (..., B)
        q = jnp.moveaxis(q, 0, -2)
        return q.reshape(*q.shape[:-2], n * chunk)[..., :b]

    return tuple(join(q) for q in out)


def make_rollout(body: Body, medium=None, dt: float | None = None, record_every: int = 1):
    """Return the compiled batch rollout ``(pos0 (B,N,3), vel0, act (B,T,A)) -> (rec, x, v)``.

    ``rec`` is (B, R, N, 3); the final positions and velocities are (B, N, 3). It compiles
    once per shape; a second call with the same shapes reuses the compiled code, and a later
    process loads the compiled program (``jax_programs.StoredProgram``, keyed on the model).
    On a CPU a batch wider than ``lanes()`` runs as chunks of that many candidates, several
    at once (``ChunksAtOnce``).
    """
    key = fingerprint("rollout", compile_model(body, medium, dt), record_every, lanes())
    program = StoredProgram(lambda: rollout_fn(body, medium, dt, record_every), key)
    chunk = lanes()
    return program if chunk is None else ChunksAtOnce(program, chunk)


class ChunksAtOnce:
    """A CPU batch rollout: ``program`` run ``chunk`` candidates at a time (the last chunk
    padded with copies of its last candidate), as many chunks in flight as the host has
    cores: XLA runs each call on a thread of its own pool, so the chunks share the cores,
    where one program's ``lax.map`` runs them one after another on one."""

    def __init__(self, program: StoredProgram, chunk: int) -> None:
        self.program, self.chunk = program, chunk

    @property
    def programs(self) -> dict:
        """The compiled programs, one per shape of the arguments (``StoredProgram``)."""
        return self.program.programs

    def __call__(self, x0, v0, act):
        x0, v0, chunk = jnp.asarray(x0, F32), jnp.asarray(v0, F32), self.chunk
        if x0.ndim != 3 or x0.shape[0] <= chunk:
            return self.program(x0, v0, act)
        act = jnp.asarray(act, F32)
        shared = act.ndim == 2 or act.shape[0] == 1  # (T, A) or (1, T, A): one row for all
        b = x0.shape[0]
        starts = range(0, b, chunk)

        def part(q, k):
            q = q[k : k + chunk]
            return jnp.concatenate([q, jnp.repeat(q[-1:], chunk - q.shape[0], axis=0)])

        def one(k):
            args = (part(x0, k), part(v0, k), act if shared else part(act, k))
            return jax.block_until_ready(self.program(*args))

        with ThreadPoolExecutor(min(len(starts), _cores())) as pool:
            outs = list(pool.map(one, starts))
        return tuple(jnp.concatenate(q)[:b] for q in zip(*outs, strict=True))


def _cores() -> int:
    """Return how many cores this process may run on."""
    affinity = getattr(os, "sched_getaffinity", None)
    return len(affinity(0)) if affinity else os.cpu_count() or 1


def blown_up(positions: jax.Array, velocities: jax.Array) -> jax.Array:
    """Return a (B,) bool array: True where a candidate's state is non-finite or too fast."""
    speed2 = jnp.sum(velocities * velocities, axis=-1).max(axis=-1)
    finite = jnp.isfinite(positions).all(axis=(-1, -2)) & jnp.isfinite(speed2)
    return ~finite | (speed2 >= VMAX * VMAX)
