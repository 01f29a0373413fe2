"""Phase 1 of SAN synthesis: generate random networks and evaluate them, in parallel.

Every network is drawn up front from one generator seeded with ``seed``, and every evaluation
is a reset, deterministic simulation, so a search returns the same metrics whatever the
number of worker processes. Each worker builds its World (one MuJoCo compile) once, in the
pool's initializer, and receives networks in chunks.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass

import numpy as np

from zoetic.san.network import Network, SanPolicy, random_network

__all__ = ["Outcome", "SearchResult", "evaluate_networks", "search", "speed_cm_s"]

Progress = Callable[[int, int, float], None]  # (done, total, best metric so far)


@dataclass(frozen=True)
class Outcome:
    """What one evaluation measured: the metric, whether it fell, signed distance (m)."""

    metric: float
    fell: bool
    distance: float


def speed_cm_s(creature, metric: float, distance: float, seconds: float | None = None) -> float:
    """Return the gait's speed in cm/s: metric / time for distance and follow, else |x| / time."""
    t = float(seconds if seconds is not None else creature.seconds)
    if creature.metric in ("distance", "follow"):
        return 100.0 * float(metric) / t
    return 100.0 * abs(float(distance)) / t


@dataclass(frozen=True, eq=False)
class SearchResult:
    """Every trial of a phase-1 search, in generation order, and the ranking of them."""

    creature: object
    networks: list[Network]
    metrics: np.ndarray  # (trials,)
    fell: np.ndarray  # (trials,) bool
    distances: np.ndarray  # (trials,) signed m
    seconds: float
    terrain: str
    seed: int
    elapsed: float  # wall-clock seconds for the evaluations
    workers: int

    @property
    def order(self) -> np.ndarray:
        """Return the trial indices from the best metric to the worst (ties by index)."""
        m = np.where(np.isfinite(self.metrics), self.metrics, -np.inf)
        return np.argsort(-m, kind="stable")

    def top(self, k: int) -> list[int]:
        """Return the indices of the ``k`` best trials."""
        return [int(i) for i in self.order[:k]]

    @property
    def speeds(self) -> np.ndarray:
        """Return every trial's speed (cm/s), see ``speed_cm_s``."""
        return np.array(
            [
                speed_cm_s(self.creature, m, d, self.seconds)
                for m, d in zip(self.metrics, self.distances, strict=True)
            ]
        )


# --- worker side --------------------------------------------------------------------------

_WORKER: dict = {}


def _init_worker(creature, terrain: str, seed: int, seconds: float) -> None:
    from zoetic.san.world import World

    _WORKER["world"] = World(creature, terrain=terrain, seed=seed)
    _WORKER["creature"] = creature
    _WORKER["seconds"] = seconds


def _evaluate_one(network: Network) -> Outcome:
    world, creature = _WORKER["world"], _WORKER["creature"]
    rollout = world.run(SanPolicy(network, creature), seconds=_WORKER["seconds"])
    metric = float(rollout.metric)
    if not np.isfinite(metric):  # a blown-up simulation can never rank
        metric = -np.inf
    return Outcome(metric, bool(rollout.fell), float(rollout.distance))


def _evaluate_chunk(start: int, networks: Sequence[Network]) -> tuple[int, list[Outcome]]:
    return start, [_evaluate_one(net) for net in networks]


# --- driver -------------------------------------------------------------------------------


def _pool_context():
    methods = mp.get_all_start_methods()
    return mp.get_context("fork" if "fork" in methods else methods[0])


def evaluate_networks(
    creature,
    networks: Sequence[Network],
    terrain: str = "flat",
    seed: int = 0,
    seconds: float | None = None,
    workers: int | None = None,
    progress: Progress | None = None,
    chunk: int | None = None,
) -> list[Outcome]:
    """Return one Outcome per network (same order), evaluated on ``workers`` processes."""
    seconds = float(creature.seconds if seconds is None else seconds)
    total = len(networks)
    workers = max(1, min(int(workers or os.cpu_count() or 1), max(total, 1)))
    outcomes: list[Outcome | None] = [None] * total
    best = -np.inf

    def note(start: int, outs: list[Outcome], done: int) -> None:
        nonlocal best
        outcomes[start : start + len(outs)] = outs
        best = max([best] + [o.metric for o in outs])
        if progress is not None:
            progress(done, total, float(best))

    if workers == 1:
        _init_worker(creature, terrain, seed, seconds)
        try:
            for i, net in enumerate(networks):
                note(i, [_evaluate_one(net)], i + 1)
        finally:
            _WORKER.clear()
        return outcomes  # type: ignore[return-value]

    size = chunk or max(1, min(8, total // (workers * 4) or 1))
    done = 0
    with ProcessPoolExecutor(
        max_workers=workers,
        mp_context=_pool_context(),
        initializer=_init_worker,
        initargs=(creature, terrain, seed, seconds),
    ) as pool:
        futures = [
            pool.submit(_evaluate_chunk, s, list(networks[s : s + size]))
            for s in range(0, total, size)
        ]
        try:
            for fut in as_completed(futures):
                start, outs = fut.result()
                done += len(outs)
                note(start, outs, done)
        except BaseException:
            for fut in futures:
                fut.cancel()
            raise
    return outcomes  # type: ignore[return-value]


def search(
    creature,
    trials: int = 200,
    top: int = 10,
    seed: int = 0,
    terrain: str = "flat",
    workers: int | None = None,
    progress: Progress | None = None,
    seconds: float | None = None,
    n_hidden: int | None = None,
) -> SearchResult:
    """Return all ``trials`` random SANs for ``creature`` with their metrics (phase 1).

    ``top`` is kept for the caller's convenience (``result.top(top)``); every trial is kept.
    The same seed gives the same networks and metrics whatever ``workers`` is.
    """
    if trials < 1:
        raise ValueError("trials must be at least 1")
    rng = np.random.default_rng(seed)
    networks = [random_network(creature, rng, n_hidden=n_hidden) for _ in range(trials)]
    seconds = float(creature.seconds if seconds is None else seconds)
    t0 = time.perf_counter()
    outs = evaluate_networks(creature, networks, terrain, seed, seconds, workers, progress)
    elapsed = time.perf_counter() - t0
    return SearchResult(
        creature=creature,
        networks=networks,
        metrics=np.array([o.metric for o in outs]),
        fell=np.array([o.fell for o in outs], dtype=bool),
        distances=np.array([o.distance for o in outs]),
        seconds=seconds,
        terrain=terrain,
        seed=seed,
        elapsed=elapsed,
        workers=max(1, min(int(workers or os.cpu_count() or 1), trials)),
    )
