"""The SAN phase-1 search's throughput: ``zoetic bench san``."""

from __future__ import annotations

import numpy as np

from zoetic.san.network import random_network
from zoetic.san.search import search, time_one_trial


def bench_search(creature: str = "walker", trials: int = 200, workers: int | None = None) -> dict:
    """Time a phase-1 search of ``trials`` random SANs on all cores; returns the figures."""
    from zoetic.san import load_creature

    c = load_creature(creature)
    net = random_network(c, np.random.default_rng(0))
    compile_s, one = time_one_trial(c, net, "flat", 0, c.seconds)  # one compile, timed apart
    result = search(c, trials=trials, seed=0, workers=workers)
    steps = trials * round(c.seconds / c.dt)
    return {
        f"{c.name}_{trials}_trials_seconds": round(result.elapsed, 3),
        "steps_per_second": round(steps / result.elapsed),
        "simulated_seconds_per_second": round(trials * c.seconds / result.elapsed, 1),
        "workers": result.workers,
        "trials": trials,
        "seconds_per_trial": c.seconds,
        "physics_dt": c.dt,
        "control_dt": c.control_dt,
        "compile_seconds": round(compile_s, 4),
        "one_trial_seconds_in_process": round(one, 4),
        "best_metric": round(float(np.max(result.metrics)), 4),
    }
