"""The Ray evaluator: a population split into sub-batches over long-lived actors on a cluster.

Each actor is a Python process with the compiled Numba kernel kept warm between generations; it
simulates its sub-batch single-threaded (one actor per CPU). The objective (body arrays, task,
controller template) is put in the object store once per objective and fetched once per actor.
A candidate's evaluation depends only on its parameters (the kernel's result does not depend on
a candidate's place in a batch), so a sub-batch lost with a dying worker is simply evaluated
again: the actor is restarted by Ray and the sub-batch re-submitted, by candidate index; the
generation's result is the same, bit for bit, as the in-process evaluator's.

``ray.init`` connects to ``address`` (or ``RAY_ADDRESS``, or starts a local Ray when neither is
set). Install with ``pip install 'zoetic[ray]'``.
"""

from __future__ import annotations

import os
from collections.abc import Callable

import numpy as np

from zoetic.errors import ZoeticError
from zoetic.learning.objective import Evaluation, Objective, merge


def import_ray():
    """Return the ray module, or raise a ZoeticError that says how to install it."""
    try:
        import ray
    except ImportError:
        raise ZoeticError(
            "the ray evaluator needs Ray: pip install 'zoetic[ray]' (or pip install ray)"
        ) from None
    return ray


_AUTH_FAILURE = ("InvalidAuthToken", "AuthenticationError", "Unauthenticated")


def _connect_failure(address: str | None, exc: BaseException) -> str:
    """Say why ``ray.init`` could not join the cluster at ``address``: the token, or the network.

    Ray 2.5x clusters turn token authentication on by default; a driver started without
    ``RAY_AUTH_MODE=token`` is refused, which Ray reports as a ConnectionError whose cause's text
    (not its type) names the refusal."""
    text = " ".join(str(e) for e in (exc, exc.__cause__, exc.__context__) if e is not None)
    if any(word in text for word in _AUTH_FAILURE):
        mode = os.environ.get("RAY_AUTH_MODE", "unset")
        return (
            f"the Ray cluster at {address} refused this driver's authentication token "
            f"(InvalidAuthToken; RAY_AUTH_MODE is {mode}): the cluster has token "
            "authentication on, so run zoetic with RAY_AUTH_MODE=token and the cluster's token "
            "in ~/.ray/auth_token, RAY_AUTH_TOKEN_PATH or RAY_AUTH_TOKEN (docs/cluster.md)"
        )
    first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    return f"cannot reach the Ray cluster at {address} ({first})"


class _Worker:
    """A Ray actor: caches one job (an objective, ...) by key and runs sub-batches through it."""

    def __init__(self) -> None:
        from zoetic.physics.simulate import set_threads

        set_threads(1)
        self._jobs: dict = {}

    def pid(self) -> int:
        return os.getpid()

    def evaluate(self, key: int, boxed_ref: list, start: int, items):
        """Return (start, job.evaluate(items)) for the items ``start .. start + len(items)``."""
        if key not in self._jobs:
            import ray

            self._jobs = {key: ray.get(boxed_ref[0])}  # one job at a time
        return start, self._jobs[key].evaluate(items)


class RayPool:
    """Long-lived Ray actors that run a job's ``evaluate`` over sub-batches, in index order.

    A job is any picklable object with ``evaluate(items)`` (an Objective, a SAN search's
    trials); it is put in the object store once and cached by each actor.
    """

    def __init__(
        self,
        address: str | None = None,
        actors: int | None = None,
        chunks_per_actor: int = 2,
        retries: int = 3,
        on_submit: Callable[[RayPool], None] | None = None,
    ):
        self.address = address or os.environ.get("RAY_ADDRESS") or None
        self.n_actors = actors
        self.chunks_per_actor = max(1, chunks_per_actor)
        self.retries = retries
        self.on_submit = on_submit  # called once tasks are in flight (tests kill a worker there)
        self.resubmitted = 0  # sub-batches evaluated again after a worker was lost
        self._actors: list = []
        self._key: int | None = None
        self._ref = None
        self._job = None
        self._started_ray = False

    def _start(self) -> None:
        ray = import_ray()
        if not ray.is_initialized():
            try:
                ray.init(
                    address=self.address,
                    log_to_driver=False,
                    include_dashboard=False,
                    configure_logging=False,
                )
            except (ConnectionError, RuntimeError) as exc:
                raise ZoeticError(_connect_failure(self.address, exc)) from None
            self._started_ray = True
        n = self.n_actors or max(1, int(ray.cluster_resources().get("CPU", 1)))
        remote = ray.remote(num_cpus=1, max_restarts=-1, max_task_retries=self.retries)(_Worker)
        self._actors = [remote.remote() for _ in range(n)]

    def pids(self) -> list[int]:
        """Return the process ids of the actors (a test kills one)."""
        return import_ray().get([a.pid.remote() for a in self._actors])

    def map(self, job, items, on_part: Callable[[int, object], None] | None = None) -> list:
        """Return ``job.evaluate`` of consecutive sub-batches of ``items``, in their order.

        ``on_part(start, result)`` is called as each sub-batch comes back (any order).
        """
        ray = import_ray()
        if not self._actors:
            self._start()
        if self._job is not job:
            self._job, self._ref = job, ray.put(job)
            self._key = (self._key or 0) + 1
        n = min(len(items), len(self._actors) * self.chunks_per_actor)
        bounds = np.linspace(0, len(items), n + 1).astype(int)
        chunks = {int(a): (int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:], strict=True)}
        pending, attempts, done = {}, dict.fromkeys(chunks, 0), {}

        def submit(start: int, k: int) -> None:
            a, b = chunks[start]
            actor = self._actors[k % len(self._actors)]
            pending[actor.evaluate.remote(self._key, [self._ref], a, items[a:b])] = start

        for k, start in enumerate(chunks):
            submit(start, k)
        if self.on_submit is not None:
            self.on_submit(self)
        lost = (
            ray.exceptions.RayActorError,
            ray.exceptions.WorkerCrashedError,
            ray.exceptions.ObjectLostError,
        )
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            start = pending.pop(ready[0])
            try:
                _, part = ray.get(ready[0])
            except lost as exc:
                attempts[start] += 1
                if attempts[start] > self.retries:
                    raise ZoeticError(
                        f"items {chunks[start][0]}..{chunks[start][1] - 1}: "
                        f"lost {attempts[start]} times on Ray workers ({exc})"
                    ) from None
                self.resubmitted += 1
                submit(start, start + attempts[start])
                continue
            done[start] = part
            if on_part is not None:
                on_part(start, part)
        return [done[s] for s in sorted(done)]

    def close(self) -> None:
        """Stop the actors (and the local Ray this evaluator started)."""
        if not self._actors:
            return
        ray = import_ray()
        for a in self._actors:
            ray.kill(a)
        self._actors, self._job, self._ref = [], None, None
        if self._started_ray:
            ray.shutdown()
            self._started_ray = False


class RayEvaluator(RayPool):
    """Evaluate batches on Ray actors; same seed, same result as ``BatchEvaluator``."""

    name = "ray"

    def __call__(self, objective: Objective, params: np.ndarray) -> Evaluation:
        params = np.atleast_2d(np.asarray(params, np.float64))
        return merge(self.map(objective, params))
