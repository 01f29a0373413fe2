"""Several learning runs at once: one batched simulation for the generations of all of them.

A generation of one run is a small batch for the kernel (a repertoire entry's 32 candidates from
2 starts are 64 lanes, where the kernel runs about 1.6x faster per lane at 192 or more). Runs
of the same animal whose rollouts share the medium, time step and recording interval have their
generations simulated together: one call of all their lanes up to the shortest rollout's end,
then the longer ones continue from where it left them (rollouts that end on a recorded instant;
another length shares only with rollouts as long), and each run scores its own lanes and tells
its own optimizer. The kernel's lanes do not interact, and a lane continued from where a call
left it moves as in one call, so every run sees the same scores, bit for bit, as when learned
alone: same seed, same history.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from zoetic.learning.blas import one_blas_thread
from zoetic.learning.run import Run
from zoetic.learning.stored_body import body_digest
from zoetic.physics import State
from zoetic.physics.simulate import kernel_layout, simulate_laid_out


def _together(run: Run) -> bool:
    """True when the run's candidates can join a shared batch: simulated in this process by
    the batched kernel, scored without gradients."""
    return run.setup.config.evaluator == "batch" and not run.setup.optimizer.needs_gradient


def _groups(runs: list[Run]) -> list[list[Run]]:
    """Return the runs grouped by what their rollouts must share: the body and the
    simulation settings (``_share_key``); first-seen order kept."""
    groups: dict[tuple, list[Run]] = {}
    digests: dict[int, str] = {}
    for run in runs:
        obj = run.setup.objective
        body = digests.setdefault(id(obj.body), body_digest(obj.body))
        groups.setdefault((body, *_share_key(obj)), []).append(run)
    return list(groups.values())


def _share_key(obj) -> tuple:
    """What a run's rollouts must share with another's to be simulated in the same kernel
    calls (``Objective.rollout_key``), rollouts of another length included when both end on
    a recorded instant: the shorter share a call with the longer up to their end, and the
    longer continue from there in a call of their own (a lane started from where another
    call left it moves as in one call, bit for bit)."""
    medium, dt, steps, every = obj.rollout_key()
    return (medium, dt, every) if steps % every == 0 else (medium, dt, steps, every)


def _simulate_staged(obj, signals: list[np.ndarray], starts: list[State]):
    """Return (positions (L, R, N, 3), failed (L,)) of each run's rollouts, its candidates'
    actuator ``signals`` (K, A, T) each played from its S starts (L = K S lanes, ``starts``):
    one kernel call up to each distinct rollout length, of the lanes that last at least that
    long, each continuing from where the last call left it."""
    ends = sorted({t.shape[2] for t in signals})
    states = list(starts)
    parts: list[list[np.ndarray]] = [[] for _ in signals]
    failed = [np.zeros(len(s.positions), dtype=bool) for s in starts]
    t0 = 0
    for end in ends:
        live = [i for i, t in enumerate(signals) if t.shape[2] >= end]
        state = State(
            np.concatenate([states[i].positions for i in live]),
            np.concatenate([states[i].velocities for i in live]),
        )
        act_t = _laid_out([signals[i][:, :, t0:end] for i in live], [len(failed[i]) for i in live])
        traj = simulate_laid_out(obj.body, act_t, obj.medium, obj.dt, state, obj.record_every)
        at = 0
        for i in live:
            lanes = slice(at, at + len(failed[i]))
            at += len(failed[i])
            parts[i].append(traj.positions[lanes, 0 if t0 == 0 else 1 :])
            failed[i] |= traj.failed[lanes]
            states[i] = State(traj.final.positions[lanes], traj.final.velocities[lanes])
        t0 = end
    return [
        (p[0] if len(p) == 1 else np.concatenate(p, axis=1), f)
        for p, f in zip(parts, failed, strict=True)
    ]


def _laid_out(signals: list[np.ndarray], lanes: list[int]) -> np.ndarray:
    """Return the kernel's activations (T, A, L), clipped to [0, 1], of runs' actuator
    ``signals`` (K, A, T), each candidate played from ``lanes`` / K starts (candidate k from
    start s in lane k S + s, as ``Objective.simulate`` lays them out), the runs' lanes one
    after another: the float32 of their ``Objective.tables`` repeated over the starts."""
    steps, actuators = signals[0].shape[2], signals[0].shape[1]
    act_t = kernel_layout(steps, actuators, sum(lanes))
    at = 0
    for signal, n in zip(signals, lanes, strict=True):
        per = n // len(signal)
        single = signal.astype(np.float32).transpose(2, 1, 0)  # cast first: half the gather
        for s in range(per):
            act_t[:, :, at + s : at + n : per] = single
        at += n
    return np.clip(act_t, 0.0, 1.0, out=act_t)


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
    signals = [o.actuator_signals(np.atleast_2d(X)) for o, (_, X) in zip(objs, asked, strict=True)]
    starts = [obj.start_lanes(len(X)) for obj, (_, X) in zip(objs, asked, strict=True)]
    rollouts = _simulate_staged(objs[0], signals, starts)
    for i, (run, X) in enumerate(asked):
        positions, failed = rollouts[i]
        acts = objs[i].recorded(signals[i], positions.shape[1])
        run.tell(X, objs[i].score(X, acts, positions, failed))


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
