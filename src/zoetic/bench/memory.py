"""The repertoire a benchmark uses when it is given none: the animal's default basic training,
trained once into ``runs/bench`` and kept under a name keyed by the body and its training
tasks (``training.plan_digest``), so that a changed body or task retrains it."""

from __future__ import annotations

from pathlib import Path

QUICK_BUDGET = 150  # evaluations per entry of a --quick bench's repertoire: seconds, not skill


def bench_memory(animal: str, name: str, seed: int = 0, budget: int | None = None) -> Path:
    """Return the directory of ``animal``'s default repertoire (``name``: its body's name),
    training it first (with ``seed``; ``budget`` evaluations per entry, default the
    training's) when it is not there yet."""
    from zoetic.behavior.training import plan_digest, train_repertoire

    tag = "" if budget is None else f"-budget{budget}"
    memory = Path("runs/bench") / f"{name}-memory-{plan_digest(animal)}{tag}"
    if not (memory / "repertoire.json").exists():
        extra = {} if budget is None else {"budget": budget}
        train_repertoire(animal, memory, seed=seed, **extra)
    return memory
