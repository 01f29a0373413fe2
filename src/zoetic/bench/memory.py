"""The repertoire a benchmark uses when it is given none: the animal's default basic training,
trained once into ``runs/bench`` and kept under a name keyed by the body and its training
tasks (``training.plan_digest``), so that a changed body or task retrains it."""

from __future__ import annotations

from pathlib import Path


def bench_memory(animal: str, name: str, seed: int = 0) -> Path:
    """Return the directory of ``animal``'s default repertoire (``name``: its body's name),
    training it first (with ``seed``) when it is not there yet."""
    from zoetic.behavior.training import plan_digest, train_repertoire

    memory = Path("runs/bench") / f"{name}-memory-{plan_digest(animal)}"
    if not (memory / "repertoire.json").exists():
        train_repertoire(animal, memory, seed=seed)
    return memory
