"""Several learning runs at once: one batched simulation for the generations of all of them.

A generation of one run is a small batch for the kernel (a repertoire entry's 32 candidates from
2 starts are 64 lanes, where the kernel runs about 1.6x faster per lane at 192 or more). Runs
of the same animal whose rollouts last as long (same medium, time step, steps and recording
interval) have their generations simulated together in one call, then each run scores its own
lanes and tells its own optimizer. The kernel's lanes do not interact, so every run sees the
same scores, bit for bit, as when learned alone: same seed, same history.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from zoetic.learning.blas import one_blas_thread
from zoetic.learning.run import Run
from zoetic.learning.stored_body import body_digest
from zoetic.physics import State, simulate


def _together(run: Run) -> bool:
    """True when the run's candidates can join a shared batch: simulated in this process by
    the batched kernel, scored without gradients."""
    return run.setup.config.evaluator == "batch" and not run.setup.optimizer.needs_gradient


def _groups(runs: list[Run]) -> list[list[Run]]:
    """Return the runs grouped by what their rollouts must share: the body and the
    simulation settings (``Objective.rollout_key``); first-seen order kept."""
    groups: dict[tuple, list[Run]] = {}
    digests: dict[int, str] = {}
    for run in runs:
        obj = run.setup.objective
        body = digests.setdefault(id(obj.body), body_digest(obj.body))
        groups.setdefault((body, *obj.rollout_key()), []).append(run)
    return list(groups.values())


def _generation(group: list[Run], stalled: set[int]) -> None:
    """Ask every unfinished run of a group for a batch, simulate them all in one call and tell
    each run its own scores; a run with nothing more to ask joins ``stalled`` (by id)."""
    asked = []
    for run in group:
        if run.finished or id(run) in stalled:
            continue
        X = run.ask()
        if X is None:
            stalled.add(id(run))
        else:
            asked.append((run, X))
    if not asked:
        return
    objs = [run.setup.objective for run, _ in asked]
    lanes = [obj.lanes(X) for obj, (_, X) in zip(objs, asked, strict=True)]
    starts = [obj.start_lanes(len(X)) for obj, (_, X) in zip(objs, asked, strict=True)]
    first = objs[0]
    state = State(
        np.concatenate([s.positions for s in starts]),
        np.concatenate([s.velocities for s in starts]),
    )
    traj = simulate(
        first.body, np.concatenate(lanes), first.medium, first.dt, state, first.record_every
    )
    at = 0
    for obj, table, (run, X) in zip(objs, lanes, asked, strict=True):
        part = slice(at, at + len(table))
        at += len(table)
        run.tell(X, obj.score(X, table, traj.positions[part], traj.failed[part]))


def learn_together(
    runs: list[Run], progress: Callable[[Run], None] | None = None, every_s: float = 2.0
) -> list[Run]:
    """Learn every run to its budget, runs that share rollouts (``_groups``) a generation of
    each per batched simulation; each run checkpoints every ``every_s`` seconds and on
    interruption, as ``Run.learn`` does. A run that cannot share (another evaluator, a
    gradient method) is learned alone first. BLAS is held to one thread throughout
    (``one_blas_thread``)."""
    with one_blas_thread():
        return _learn_together(runs, progress, every_s)


def _learn_together(
    runs: list[Run], progress: Callable[[Run], None] | None, every_s: float
) -> list[Run]:
    """``learn_together``'s work, BLAS's threads aside."""
    shared = [run for run in runs if _together(run)]
    for run in runs:
        if not _together(run):
            run.learn(progress=progress, every_s=every_s)
    groups = _groups(shared)
    stalled: set[int] = set()
    last = time.perf_counter()
    try:
        while any(not run.finished and id(run) not in stalled for run in shared):
            before = [run.evaluations for run in shared]
            for group in groups:
                _generation(group, stalled)
            for run, n in zip(shared, before, strict=True):
                if progress and run.evaluations > n:
                    progress(run)
            if time.perf_counter() - last > every_s:
                for run in shared:
                    if run.unsaved:
                        run.checkpoint()
                last = time.perf_counter()
    finally:
        for run in shared:
            run.settle()
    return runs
