"""Where a population is simulated: in-process batches (default) or a pool of processes.

An Evaluator maps an Objective and a batch of parameter vectors to an Evaluation. Optimizers
never see it, so a cluster backend (Ray) plugs in by implementing ``__call__`` and ``close``.
When the optimizer needs gradients, ``value_and_grad`` also returns dE/dparams, through the
JAX simulator (in this process: one point at a time).
"""

from __future__ import annotations

import numpy as np

from zoetic.learning.objective import Evaluation, Objective, merge


class Evaluator:
    """What every evaluator offers: scores of a batch, and scores with gradients."""

    name = "base"

    def __call__(self, objective: Objective, params: np.ndarray) -> Evaluation:
        raise NotImplementedError  # pragma: no cover - abstract

    def value_and_grad(self, objective: Objective, params: np.ndarray):
        """Return (Evaluation, gradients (K, dim)) of a batch, through the JAX simulator."""
        from zoetic.learning.gradient import value_and_grad

        return value_and_grad(objective, params)

    def close(self) -> None:
        """Release what the evaluator holds."""


class BatchEvaluator(Evaluator):
    """Simulate the whole batch at once on all cores with the Numba kernel."""

    name = "batch"

    def __call__(self, objective: Objective, params: np.ndarray) -> Evaluation:
        return objective.evaluate(params)

    def close(self) -> None:
        """Nothing to release."""


_WORKER: dict = {}


def _init_worker(objective: Objective) -> None:
    from zoetic.physics.simulate import set_threads

    set_threads(1)
    _WORKER["objective"] = objective


def _evaluate_chunk(params: np.ndarray) -> Evaluation:
    return _WORKER["objective"].evaluate(params)


class ProcessPoolEvaluator(Evaluator):
    """Split each batch over worker processes, one single-threaded simulator each."""

    name = "process"

    def __init__(self, workers: int | None = None):
        from zoetic.physics.simulate import cores

        self.workers = workers or cores()
        self._pool = None
        self._objective_id = None

    def __call__(self, objective: Objective, params: np.ndarray) -> Evaluation:
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor

        if self._pool is None or self._objective_id != id(objective):
            self.close()
            ctx = mp.get_context("spawn")
            self._pool = ProcessPoolExecutor(
                self.workers, mp_context=ctx, initializer=_init_worker, initargs=(objective,)
            )
            self._objective_id = id(objective)
        chunks = [c for c in np.array_split(np.atleast_2d(params), self.workers) if len(c)]
        return merge(list(self._pool.map(_evaluate_chunk, chunks)))

    def close(self) -> None:
        """Shut the worker processes down."""
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
            self._pool = None


def make_evaluator(name: str, workers: int | None = None):
    """Return an evaluator by name: 'batch' (default), 'process' or 'ray' (learning.ray_eval)."""
    from zoetic.errors import ZoeticError

    if name == "batch":
        return BatchEvaluator()
    if name == "process":
        return ProcessPoolEvaluator(workers)
    if name == "ray":  # connects to RAY_ADDRESS (zoetic learn --ray-address), else a local Ray
        from zoetic.learning.ray_eval import RayEvaluator

        return RayEvaluator(actors=workers)
    raise ZoeticError(f"unknown evaluator {name!r} (choose from batch, process, ray)")
