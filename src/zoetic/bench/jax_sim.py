"""The JAX backend's speed: simulated seconds per wall second of a batch, compile time apart."""

from __future__ import annotations

import time

import jax
import jax.numpy as jnp
import numpy as np

from zoetic.physics.jax_backend import F32, blown_up, make_rollout


def benchmark(
    animal: str = "shark", seconds: float = 10.0, batch: int = 256, repeats: int = 2
) -> dict:
    """Return simulated seconds per wall second of the JAX batch, compile time apart."""
    from zoetic.bodies import load_animal
    from zoetic.control import wave_controller
    from zoetic.physics.simulate import rest_state

    body = load_animal(animal)
    steps = int(round(seconds / body.dt))
    rng = np.random.default_rng(0)
    wave = wave_controller(body).table(steps, body.dt)
    gains = rng.uniform(0.5, 1.0, (batch, 1, body.n_actuators))
    shifts = rng.integers(0, steps, batch)
    acts = jnp.asarray(np.stack([np.roll(wave, s, axis=0) for s in shifts]) * gains, F32)
    st = rest_state(body, batch)
    x0, v0 = jnp.asarray(st.positions, F32), jnp.asarray(st.velocities, F32)
    roll = make_rollout(body, record_every=steps)
    t0 = time.perf_counter()
    jax.block_until_ready(roll(x0, v0, acts))
    first = time.perf_counter() - t0
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = jax.block_until_ready(roll(x0, v0, acts))
        best = min(best, time.perf_counter() - t0)
    return {
        "animal": animal,
        "device": str(jax.devices()[0]),
        "backend": jax.default_backend(),
        "batch": batch,
        "horizon_seconds": seconds,
        "steps": steps,
        "compile_seconds": round(max(first - best, 0.0), 2),
        "run_seconds": round(best, 3),
        "sim_seconds_per_second_batched": round(batch * seconds / best, 1),
        "blown_up": int(np.asarray(blown_up(out[1], out[2])).sum()),
    }
