"""Environment steps per second: the native vector env against SyncVectorEnv, side by side."""

from __future__ import annotations

import time

import gymnasium
import numpy as np

import zoetic.gym  # noqa: F401  (registers the environments)


def _steps_per_second(env, actions: np.ndarray, repeats: int) -> float:
    env.reset(seed=0)
    env.step(actions[0])  # warm-up (compilation, caches)
    best = float("inf")
    for _ in range(repeats):
        env.reset(seed=0)
        t0 = time.perf_counter()
        for a in actions:
            env.step(a)
        best = min(best, time.perf_counter() - t0)
    return actions.shape[0] * actions.shape[1] / best


def bench_gym(
    env_id: str = "zoetic/SharkSwim-v0", num_envs: int = 64, steps: int = 100, repeats: int = 3
) -> dict:
    """Return env steps per second of the native vector env and of SyncVectorEnv, same
    actions, and their ratio."""
    native = gymnasium.make_vec(env_id, num_envs, vectorization_mode="vector_entry_point")
    sync = gymnasium.make_vec(env_id, num_envs, vectorization_mode="sync")
    rng = np.random.default_rng(0)
    shape = (steps, *native.action_space.shape)
    actions = rng.random(shape).astype(np.float32)
    sps_native = _steps_per_second(native, actions, repeats)
    sps_sync = _steps_per_second(sync, actions, max(1, repeats - 1))
    native.close()
    sync.close()
    period = native.unwrapped.core.period if hasattr(native, "unwrapped") else 0.05
    return {
        "env": env_id,
        "num_envs": num_envs,
        "steps": steps,
        "control_period_s": period,
        "native_env_steps_per_second": round(sps_native, 1),
        "sync_env_steps_per_second": round(sps_sync, 1),
        "speedup_native_vs_sync": round(sps_native / sps_sync, 1),
        "native_sim_seconds_per_second": round(sps_native * period, 1),
    }
