"""The JAX backend's speed: simulated seconds per wall second of a batch, compile time apart
(a first run's, and a later run's that finds the program in the persistent cache), beside the
Numba kernel on the same activations in the same run."""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable
from contextlib import contextmanager

import jax
import jax.numpy as jnp
import numpy as np

from zoetic.physics.jax_backend import F32, blown_up, lanes, make_rollout


def _activations(body, steps: int, batch: int) -> jax.Array:
    """Return (batch, steps, A) float32 activations: the wave controller's table, shifted in
    time and scaled per candidate, built on the JAX device (a 64k batch never sits in NumPy)."""
    from zoetic.control import wave_controller

    rng = np.random.default_rng(0)
    wave = jnp.asarray(wave_controller(body).table(steps, body.dt), F32)
    shifts = jnp.asarray(rng.integers(0, steps, batch))
    gains = jnp.asarray(rng.uniform(0.5, 1.0, (batch, 1, body.n_actuators)), F32)
    rows = (jnp.arange(steps)[None, :] - shifts[:, None]) % steps
    return wave[rows] * gains


@contextmanager
def compilation_cache_in(directory: str | None):
    """Run with JAX's persistent compilation cache in ``directory`` (None: no cache at all),
    the cache directory in use before restored after."""
    from jax.experimental.compilation_cache import compilation_cache as cc

    before = jax.config.jax_compilation_cache_dir
    jax.config.update("jax_compilation_cache_dir", directory)
    cc.reset_cache()
    try:
        yield
    finally:
        jax.config.update("jax_compilation_cache_dir", before)
        cc.reset_cache()


@contextmanager
def fresh_compilation_cache():
    """Run with JAX's persistent compilation cache in an empty temporary directory, so that
    the first compile is cold and a repeat reads what it wrote; the user's cache is restored
    after (and left untouched)."""
    with tempfile.TemporaryDirectory(prefix="zoetic-jax-") as tmp, compilation_cache_in(tmp):
        yield


def compile_cold_and_cached(make: Callable[[], Callable[[], object]]) -> tuple[float, float]:
    """Return the wall seconds of the first call of ``make()`` (trace, XLA compile, one run)
    in an empty persistent cache, and of a second ``make()``'s first call, which finds the
    compiled program there (a later process's start)."""
    seconds = []
    with fresh_compilation_cache():
        for _ in range(2):
            fn = make()
            t0 = time.perf_counter()
            jax.block_until_ready(fn())
            seconds.append(time.perf_counter() - t0)
    return seconds[0], seconds[1]


def _best(fn, repeats: int) -> tuple[float, object]:
    best, out = float("inf"), None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def benchmark(
    animal: str = "shark",
    seconds: float = 10.0,
    batch: int = 256,
    repeats: int = 2,
    numba: bool = False,
) -> dict:
    """Return simulated seconds per wall second of the JAX batch, compile time apart; with
    ``numba`` also the Numba kernel's on the same activations, timed alternately with it."""
    from zoetic.bodies import load_animal
    from zoetic.physics.simulate import rest_state, simulate

    body = load_animal(animal)
    steps = int(round(seconds / body.dt))
    acts = _activations(body, steps, batch)
    st = rest_state(body, batch)
    x0, v0 = jnp.asarray(st.positions, F32), jnp.asarray(st.velocities, F32)
    rolls = []

    def make():
        rolls.append(make_rollout(body, record_every=steps))
        return lambda: rolls[-1](x0, v0, acts)

    first, cached = compile_cold_and_cached(make)
    roll = rolls[-1]
    best, out = _best(lambda: jax.block_until_ready(roll(x0, v0, acts)), repeats)
    row = {
        "animal": animal,
        "device": str(jax.devices()[0]),
        "backend": jax.default_backend(),
        "lanes_per_chunk": lanes(),
        "batch": batch,
        "horizon_seconds": seconds,
        "steps": steps,
        "compile_seconds": round(max(first - best, 0.0), 2),
        "compile_seconds_cached": round(max(cached - best, 0.0), 2),
        "run_seconds": round(best, 3),
        "sim_seconds_per_second_batched": round(batch * seconds / best, 1),
        "blown_up": int(np.asarray(blown_up(out[1], out[2])).sum()),
    }
    if numba:
        table = np.asarray(acts)
        simulate(body, table[:2, :4], record_every=4)  # compile outside the clock
        t_nb, tr = _best(lambda: simulate(body, table, record_every=steps), repeats)
        row["numba_sim_seconds_per_second_batched"] = round(batch * seconds / t_nb, 1)
        row["numba_over_jax"] = round(best / t_nb, 2)
        row["max_position_difference_m"] = float(
            np.nanmax(np.abs(np.asarray(out[1]) - tr.final.positions))
        )
    return row
