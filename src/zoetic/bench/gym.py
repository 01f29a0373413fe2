"""Environment steps per second: the native vector env against SyncVectorEnv, side by side."""

from __future__ import annotations

import time

import gymnasium
import numpy as np

import zoetic.gym  # noqa: F401  (registers the environments)


def _run(env, actions: np.ndarray) -> tuple[float, float]:
    """Return (wall, CPU time of this thread) for stepping through ``actions``."""
    env.reset(seed=0)
    w0, c0 = time.perf_counter(), time.thread_time()
    for a in actions:
        env.step(a)
    return time.perf_counter() - w0, time.thread_time() - c0


def bench_gym(
    env_id: str = "zoetic/SharkSwim-v0", num_envs: int = 64, steps: int = 100, repeats: int = 3
) -> dict:
    """Return env steps per second of the native vector env and of SyncVectorEnv on the same
    actions, and their ratio by wall time and by this thread's CPU time."""
    native = gymnasium.make_vec(env_id, num_envs, vectorization_mode="vector_entry_point")
    sync = gymnasium.make_vec(env_id, num_envs, vectorization_mode="sync")
    rng = np.random.default_rng(0)
    shape = (steps, *native.action_space.shape)
    actions = rng.random(shape).astype(np.float32)
    _run(native, actions[:2]), _run(sync, actions[:2])  # warm-up (compilation, caches)
    best = {"native": [np.inf, np.inf], "sync": [np.inf, np.inf]}
    for _ in range(repeats):  # interleaved, best of each
        for name, env in (("native", native), ("sync", sync)):
            best[name] = np.minimum(best[name], _run(env, actions))
    n = actions.shape[0] * actions.shape[1]
    sps_native, sps_sync = n / best["native"][0], n / best["sync"][0]
    cpu_native, cpu_sync = n / best["native"][1], n / best["sync"][1]
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
        # both run on this one thread (64 lanes x 10 steps stay under the threaded kernel's
        # threshold), so CPU time per env step compares them without the other processes
        "speedup_native_vs_sync_cpu": round(cpu_native / cpu_sync, 1),
        "native_sim_seconds_per_second": round(sps_native * period, 1),
    }
