"""Ray's cost on one machine, side by side with in-process evaluation: ``zoetic bench ray``."""

from __future__ import annotations

import time

import numpy as np

from zoetic.learning.evaluate import BatchEvaluator
from zoetic.learning.ray_eval import RayEvaluator, import_ray


def bench_ray(
    animal: str = "shark",
    task: str = "swim-straight",
    population: int = 64,
    generations: int = 5,
    actors: int | None = None,
) -> dict:
    """Seconds per generation in process and on a local Ray, measured side by side."""
    from zoetic.learning.run import LearnConfig, build
    from zoetic.physics.simulate import cores

    setup = build(LearnConfig(animal=animal, task=task, seed=0))
    obj = setup.objective
    lo, hi = obj.bounds()
    rng = np.random.default_rng(0)
    gens = [rng.uniform(lo, hi, (population, len(lo))) for _ in range(generations)]
    ray = import_ray()
    started = not ray.is_initialized()
    if started:
        ray.init(
            num_cpus=actors or cores(),
            log_to_driver=False,
            include_dashboard=False,
            configure_logging=False,
        )
    evaluators = {"in_process": BatchEvaluator(), "ray": RayEvaluator(actors=actors)}
    times: dict[str, float] = {}
    try:
        t0 = time.perf_counter()
        evaluators["ray"](obj, gens[0])  # actors start, kernels compile
        startup = time.perf_counter() - t0
        evaluators["in_process"](obj, gens[0])
        same = True
        for name, ev in evaluators.items():
            t0 = time.perf_counter()
            results = [ev(obj, x).E for x in gens]
            times[name] = (time.perf_counter() - t0) / generations
            if name == "in_process":
                ref = results
            else:
                same = all(np.array_equal(a, b) for a, b in zip(ref, results, strict=True))
        n_actors = len(evaluators["ray"]._actors)
    finally:
        evaluators["ray"].close()
        if started:
            ray.shutdown()
    return {
        "benchmark": "ray",
        "animal": animal,
        "candidates_per_generation": population,
        "horizon_s": setup.task.horizon,
        "actors": n_actors,
        "in_process_s_per_generation": round(times["in_process"], 4),
        "ray_s_per_generation": round(times["ray"], 4),
        "ray_overhead_s_per_generation": round(times["ray"] - times["in_process"], 4),
        "ray_over_in_process": round(times["ray"] / times["in_process"], 3),
        "ray_startup_s": round(startup, 2),
        "same_E_bit_for_bit": bool(same),
    }
