"""Learning speed, side by side: the paper's annealing budget, and how fast others match it."""

from __future__ import annotations

import math
import time

import numpy as np

from zoetic.learning.run import LearnConfig, build


def learn_until(
    config: LearnConfig, target: float | None = None, max_seconds: float = math.inf, task=None
):
    """Learn ``config`` (its task, or ``task``) until its budget, E <= target or max_seconds of
    wall, the kernel compiled outside the clock; return (setup, figures)."""
    setup = build(config, task)
    opt, obj = setup.optimizer, setup.objective
    obj.evaluate(opt.x0[None])  # compile and warm the kernel outside the clock
    t0 = time.perf_counter()
    reached = None
    while opt.evaluations < config.budget and not opt.done():
        X = opt.ask()
        if len(X) == 0:
            break
        opt.tell(X, obj(X))
        elapsed = time.perf_counter() - t0
        if target is not None and opt.best_f <= target:
            reached = elapsed
            break
        if elapsed > max_seconds:
            break
    seconds = time.perf_counter() - t0
    close = getattr(opt, "close", None)
    if close:
        close()
    return setup, {
        "seconds": round(seconds, 3),
        "final_E": round(float(opt.best_f), 4),
        "evaluations": opt.evaluations,
        "seconds_to_match": None if reached is None else round(reached, 3),
    }


def bench_gradient(base: dict, target: float, max_seconds: float) -> dict:
    """Return the gradient path's compile time (a first run's, and a later run's that finds it
    in the persistent cache: trace, compile and the first value and gradient) and its wall
    time to reach E <= target."""
    from zoetic.bench.jax_sim import compile_cold_and_cached
    from zoetic.learning.gradient import value_and_grad

    def make():  # a fresh objective: its gradient is traced and compiled anew
        built.append(build(LearnConfig(optimizer="gradient", budget=10**6, **base)))
        return lambda: value_and_grad(built[-1].objective, built[-1].optimizer.x0[None])

    built: list = []
    compile_s, cached_s = compile_cold_and_cached(make)  # outside the clock
    opt, obj = built[-1].optimizer, built[-1].objective
    t0 = time.perf_counter()
    reached = None
    while time.perf_counter() - t0 < max_seconds:
        X = opt.ask()
        ev, G = value_and_grad(obj, X)
        opt.tell(X, ev.E, G)
        if opt.best_f <= target:
            reached = time.perf_counter() - t0
            break
    return {
        "gradient_compile_seconds": round(compile_s, 2),
        "gradient_compile_seconds_cached": round(cached_s, 2),
        "gradient_seconds_to_match_anneal": None if reached is None else round(reached, 3),
        "gradient_steps": opt.evaluations,
        "gradient_best_E": round(opt.best_f, 4),
    }


def bench_learn(budget: int = 3500, seed: int = 0, max_seconds: float = 60.0) -> dict:
    """Return annealing's wall time and final E, and the others' time to reach that E."""
    base = dict(animal="shark", task="swim-straight", controller="time", nodes=15, seed=seed)
    _, anneal = learn_until(LearnConfig(optimizer="anneal", budget=budget, **base))
    target = anneal["final_E"]
    out = {
        "task": "shark swim-straight, M = 15, 6 actuators (NM = 90), 4 s horizon",
        "anneal_evaluations": anneal["evaluations"],
        "anneal_seconds": anneal["seconds"],
        "anneal_final_E": target,
        "paper_anneal_seconds": 3600,
    }
    out["speedup_vs_paper"] = round(3600 / max(anneal["seconds"], 1e-9), 1)
    _, cm = learn_until(
        LearnConfig(optimizer="cmaes", budget=100 * budget, popsize=24, **base),
        target,
        max_seconds,
    )
    out["cmaes_seconds_to_match_anneal"] = cm["seconds_to_match"]
    out["cmaes_evaluations_to_match"] = cm["evaluations"]
    try:
        import jax  # noqa: F401

        out.update(bench_gradient(base, target, max_seconds))
    except ImportError as exc:  # JAX missing: say so rather than invent a number
        out["gradient_seconds_to_match_anneal"] = None
        out["gradient_note"] = f"unavailable: {exc}"
    out["seconds_to_match_anneal"] = {
        "cmaes": out["cmaes_seconds_to_match_anneal"],
        "gradient": out.get("gradient_seconds_to_match_anneal"),
    }
    return {k: (v if not isinstance(v, np.floating) else float(v)) for k, v in out.items()}
