"""Simulation throughput, measured side by side: one candidate, a batch, the NumPy reference."""

from __future__ import annotations

import time

import numpy as np

from zoetic.bodies import load_animal
from zoetic.control import wave_controller
from zoetic.physics.reference import simulate_reference
from zoetic.physics.simulate import cores, simulate


def host_cpu() -> dict:
    """Return the CPU that Numba compiles for and its float32 SIMD width (8 AVX2, 16 AVX-512):
    the batched figure scales with it, so a number is only comparable with the same host."""
    import llvmlite.binding as llvm

    features = llvm.get_host_cpu_features()
    lanes = 16 if features.get("avx512f", False) else 8 if features.get("avx", False) else 4
    return {"cpu": llvm.get_host_cpu_name(), "simd_float32_lanes": lanes}


def host_peak(repeats: int = 5) -> dict:
    """Return this core's float32 FMA rate (GFLOP/s, a vectorised loop in L1) and the kernel's
    square root plus division rate (G lanes/s), by this thread's CPU time (so that other
    jobs on the host do not lower them): the ceilings of docs/performance.md's roofline."""
    from numba import njit

    @njit(fastmath={"nsz", "arcp", "contract"}, error_model="numpy")
    def fma(a, reps, b, c):  # 16 dependent multiply-adds per element, elements independent
        for _ in range(reps):
            for k in range(a.shape[0]):
                x = a[k]
                for _ in range(16):
                    x = x * b + c
                a[k] = x

    @njit(fastmath={"nsz", "arcp", "contract"}, error_model="numpy")
    def sqrt_div(a, reps, c):  # a spring's 1 / (length + TINY)
        for _ in range(reps):
            for k in range(a.shape[0]):
                a[k] = np.float32(1.0) / (np.sqrt(a[k]) + c)

    a = np.ones(1024, dtype=np.float32)
    b, c = np.float32(0.999), np.float32(1e-3)
    fma(a, 1, b, c), sqrt_div(a, 1, c)
    reps = 4000
    t_fma = _best_time(lambda: fma(a, reps, b, c), repeats, time.thread_time)
    a[:] = 1.5
    t_sd = _best_time(lambda: sqrt_div(a, reps, c), repeats, time.thread_time)
    return {
        "peak_fma_gflops_per_core": round(a.size * reps * 32 / t_fma / 1e9, 1),
        "peak_sqrt_div_glanes_per_core": round(a.size * reps / t_sd / 1e9, 2),
    }


def _best_time(fn, repeats: int, clock=time.perf_counter) -> float:
    best = float("inf")
    for _ in range(repeats):
        t0 = clock()
        fn()
        best = min(best, clock() - t0)
    return best


def closed_loop_overhead(
    body, table: np.ndarray, period: float = 1 / 30, window: float = 1.0, repeats: int = 31
) -> dict[str, float]:
    """Return the cost of stepping one animal through a World in ``period`` slices against
    the same rows open loop, each the best of interleaved runs.

    ``closed_loop_overhead``: CPU time of this thread for ``window`` simulated seconds, slices
    against one kernel call (the open-loop path through the same compiled kernel); both run
    on this thread, and short windows that nothing disturbed decide.
    ``closed_loop_overhead_wall``: the same by wall clock.
    ``closed_loop_over_simulate_wall``: wall time over the whole table, slices against
    ``simulate`` (threaded kernel, as the learning path runs it; its thread-pool launch
    makes this one depend on how busy the host is).
    """
    from zoetic.physics.world import World

    world = World([body])
    start = world.state

    def sliced(rows):
        world.restore(start)
        steps = rows.shape[1]
        while world.step_count < steps:
            n = min(world.steps_for(period), steps - world.step_count)
            k = world.step_count
            world.step(n * world.dt, rows[:, k : k + n])

    def whole(rows):
        world.restore(start)
        world.step(rows.shape[1] * world.dt, rows)

    def timed(clock, fn, rows) -> float:
        t0 = clock()
        fn(rows)
        return clock() - t0

    short = table[None, : max(1, int(round(window / body.dt)))]
    full = table[None]
    sliced(full), whole(full), simulate(body, full)
    best = dict.fromkeys(
        ("cpu_sliced", "cpu_whole", "wall_sliced", "wall_whole", "full", "sim"), np.inf
    )
    for r in range(repeats):
        for key, clock, fn in (
            ("cpu_sliced", time.thread_time, sliced),
            ("cpu_whole", time.thread_time, whole),
            ("wall_sliced", time.perf_counter, sliced),
            ("wall_whole", time.perf_counter, whole),
        ):
            best[key] = min(best[key], timed(clock, fn, short))
        if r % 4 == 0:
            best["full"] = min(best["full"], _best_time(lambda: sliced(full), 1))
            best["sim"] = min(
                best["sim"], _best_time(lambda: simulate(body, full, record_every=full.shape[1]), 1)
            )
    return {
        "closed_loop_overhead": round(best["cpu_sliced"] / best["cpu_whole"], 3),
        "closed_loop_overhead_wall": round(best["wall_sliced"] / best["wall_whole"], 3),
        "closed_loop_over_simulate_wall": round(best["full"] / best["sim"], 3),
    }


def bench_simulate(
    animal: str = "shark", seconds: float = 10.0, batch: int = 512, repeats: int = 3
) -> dict:
    """Return simulated seconds per wall second for one candidate, a batch and NumPy."""
    body = load_animal(animal)
    dt = body.dt
    steps = int(round(seconds / dt))
    rng = np.random.default_rng(0)
    wave = wave_controller(body).table(steps, dt)
    # a batch of different smooth candidates: the wave with random phase shifts and gains
    gains = rng.uniform(0.5, 1.0, (batch, 1, body.n_actuators))
    shifts = rng.integers(0, steps, batch)
    acts = np.stack([np.roll(wave, s, axis=0) for s in shifts]) * gains
    t0 = time.perf_counter()
    simulate(body, acts[:2, :4], record_every=1000)
    compile_s = time.perf_counter() - t0
    single = _best_time(lambda: simulate(body, acts[:1], record_every=steps), repeats)
    batched = _best_time(lambda: simulate(body, acts, record_every=steps), repeats)
    ref_batch, ref_steps = min(batch, 64), max(20, steps // 20)
    ref = _best_time(lambda: simulate_reference(body, acts[:ref_batch, :ref_steps]), 1)
    out = {
        "animal": animal,
        "dt": dt,
        "batch": batch,
        "horizon_seconds": seconds,
        "sim_seconds_per_second_single": round(seconds / single, 1),
        "sim_seconds_per_second_batched": round(batch * seconds / batched, 1),
        "numpy_reference_batch": ref_batch,
        "numpy_reference_sim_seconds_per_second": round(ref_batch * ref_steps * dt / ref, 1),
        "cores": cores(),
        **host_cpu(),
        "compile_seconds": round(compile_s, 2),
    }
    out["speedup_vs_numpy"] = round(
        out["sim_seconds_per_second_batched"] / out["numpy_reference_sim_seconds_per_second"], 1
    )
    out["realtime_factor_batched"] = out["sim_seconds_per_second_batched"]
    out |= host_peak()
    # one animal in 1/30 s slices through a World (closed-loop stepping) over open-loop
    out |= closed_loop_overhead(body, wave)
    out["closed_loop_period_s"] = round(1 / 30, 4)
    return out
