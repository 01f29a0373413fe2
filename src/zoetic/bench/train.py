"""Learning with the defaults people run first, timed: ``zoetic demo``'s learning and
``zoetic repertoire train`` of an animal (``zoetic bench train``)."""

from __future__ import annotations

import tempfile
import time


def bench_train(
    animal: str = "shark",
    demo_budget: int | None = None,
    train_budget: int | None = None,
    seed: int = 0,
) -> dict:
    """Return the wall seconds of the demo's learning (its settings, no video nor run files;
    the kernel compiled outside the clock) and of training ``animal``'s basic repertoire into
    a temporary directory (as ``zoetic repertoire train`` does, run files included), each with
    its budget (default: the commands' own) and final E."""
    from zoetic.behavior.training import train_repertoire
    from zoetic.bench.learn import learn_until
    from zoetic.learning.config import DEMO_BUDGET, demo_config

    config = demo_config(demo_budget or DEMO_BUDGET, seed)
    _, demo = learn_until(config)
    extra = {} if train_budget is None else {"budget": train_budget}
    with tempfile.TemporaryDirectory(prefix="zoetic-bench-train-") as tmp:
        t0 = time.perf_counter()
        rep = train_repertoire(animal, tmp, seed=seed, **extra)
        train_s = time.perf_counter() - t0
    return {
        "demo_evaluations": demo["evaluations"],
        "demo_learning_seconds": demo["seconds"],
        "demo_final_E": demo["final_E"],
        "repertoire_animal": animal,
        "repertoire_budget_per_entry": train_budget or "default",
        "repertoire_entries": len(rep.names),
        "repertoire_train_seconds": round(train_s, 2),
    }
