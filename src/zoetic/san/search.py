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
from pathlib import Path

import numpy as np

from zoetic.san.network import Network, SanPolicy, random_network

__all__ = [
    "Outcome",
    "SearchResult",
    "evaluate_networks",
    "pool_context",
    "search",
    "speed_cm_s",
    "time_one_trial",
]

Progress = Callable[[int, int, float], None]  # (done, total, best metric so far)
TERRAINS = ("flat", "rough")


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


def _init_worker(creature, terrain: str, seed: int, seconds: float, mirror: bool = False) -> None:
    from zoetic.san.world import World

    _WORKER["world"] = World(creature, terrain=terrain, seed=seed, mirror=mirror)
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


@dataclass(frozen=True)
class _Trials:
    """One creature, terrain, seed and horizon: the job a Ray actor keeps (learning.ray_eval)."""

    creature: object
    terrain: str
    seed: int
    seconds: float
    mirror: bool = False

    def evaluate(self, networks: Sequence[Network]) -> list[Outcome]:
        if _WORKER.get("trials") is not self:
            _init_worker(self.creature, self.terrain, self.seed, self.seconds, self.mirror)
            _WORKER["trials"] = self
        return [_evaluate_one(net) for net in networks]


def time_one_trial(
    creature, network: Network, terrain: str = "flat", seed: int = 0, seconds: float | None = None
) -> tuple[float, float]:
    """Return (seconds to set up a worker, seconds for one trial of ``network``), both in this
    process and exactly as a search's worker does them. Setting up builds the World (its first
    use compiles the simulator); no worker state is left behind."""
    seconds = float(creature.seconds if seconds is None else seconds)
    try:
        t0 = time.perf_counter()
        _init_worker(creature, terrain, seed, seconds)
        setup = time.perf_counter() - t0
        t0 = time.perf_counter()
        _evaluate_one(network)
        return setup, time.perf_counter() - t0
    finally:
        _WORKER.clear()


# --- driver -------------------------------------------------------------------------------


def pool_context():
    """Return the multiprocessing context the search's worker pools use (fork where there is
    one: workers inherit the loaded modules)."""
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
    evaluator: str = "process",
    mirror: bool = False,
) -> list[Outcome]:
    """Return one Outcome per network (same order), evaluated on ``workers`` processes, or on
    Ray actors with ``evaluator="ray"`` (``RAY_ADDRESS``, else a local Ray; ``workers`` actors);
    ``mirror``: on the seed's follow spline reflected left for right."""
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

    if evaluator == "ray":
        from zoetic.learning.ray_eval import RayPool

        pool = RayPool(actors=workers if workers and workers > 1 else None)
        done = 0

        def part(start: int, outs: list[Outcome]) -> None:
            nonlocal done
            done += len(outs)
            note(start, outs, done)

        try:
            trials = _Trials(creature, terrain, seed, seconds, mirror)
            pool.map(trials, list(networks), on_part=part)
        finally:
            pool.close()
        return outcomes  # type: ignore[return-value]
    if evaluator != "process":
        from zoetic.errors import ZoeticError

        raise ZoeticError(f"unknown evaluator {evaluator!r} (process or ray)")
    if workers == 1:
        _init_worker(creature, terrain, seed, seconds, mirror)
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
        mp_context=pool_context(),
        initializer=_init_worker,
        initargs=(creature, terrain, seed, seconds, mirror),
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
    evaluator: str = "process",
) -> SearchResult:
    """Return all ``trials`` random SANs for ``creature`` with their metrics (phase 1).

    ``top`` is kept for the caller's convenience (``result.top(top)``); every trial is kept.
    The same seed gives the same networks and metrics whatever ``workers`` is.
    """
    if trials < 1:
        raise ValueError("trials must be at least 1")
    if terrain not in TERRAINS:
        from zoetic.san.creature import CreatureError

        raise CreatureError(f"unknown terrain {terrain!r} (expected 'flat' or 'rough')")
    rng = np.random.default_rng(seed)
    networks = [random_network(creature, rng, n_hidden=n_hidden) for _ in range(trials)]
    seconds = float(creature.seconds if seconds is None else seconds)
    t0 = time.perf_counter()
    outs = evaluate_networks(
        creature, networks, terrain, seed, seconds, workers, progress, evaluator=evaluator
    )
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


# --- usefulness, files and benchmark ---------------------------------------------------------

USEFUL_FRACTION = 0.5  # of the best gait's speed
USEFUL_FLOOR_CM_S = 1.0


USEFUL_BODY_LENGTHS_S = 0.1  # the scale-free usefulness bar, in body lengths per second


def body_length_bar_cm_s(creature, body_lengths_s: float = USEFUL_BODY_LENGTHS_S) -> float:
    """Return the scale-free usefulness bar (cm/s): ``body_lengths_s`` of the creature's own
    size (``Creature.size``) per second, 0.1 by default; the zoo's absolute bars (a quarter
    of Table 1's speeds) lie between 0.04 (star) and 0.3 (luxo) body lengths per second."""
    return 100.0 * body_lengths_s * float(creature.size)


def useful_threshold_cm_s(result: SearchResult) -> float:
    """Return the speed (cm/s) from which a trial counts as useful in this search.

    Half the speed of the best gait the search found (without falling), and at least 1 cm/s:
    a useful network is one whose gait is within a factor of two of the best.
    """
    ok = (~result.fell) & np.isfinite(result.metrics)
    best = float(result.speeds[ok].max()) if ok.any() else 0.0
    return max(USEFUL_FRACTION * best, USEFUL_FLOOR_CM_S)


def useful_mask(result: SearchResult, threshold_cm_s: float | None = None) -> np.ndarray:
    """Return which trials are useful: not fallen and at least ``threshold_cm_s`` fast."""
    thr = useful_threshold_cm_s(result) if threshold_cm_s is None else threshold_cm_s
    return (~result.fell) & (result.speeds >= thr) & np.isfinite(result.metrics)


def write_search(result: SearchResult, out, top: int = 10) -> dict:
    """Write a search run directory's data (config.toml, trials.csv, sans/NN.json, each SAN
    file carrying its creature; summary.json) and return the summary. Its pictures (ranking,
    videos) are drawn by ``zoetic.viz.san.draw_search``."""
    from zoetic.io import atomic_write_bytes, write_json, write_toml
    from zoetic.san.network import save_network

    out = Path(out)
    c = result.creature
    speeds = result.speeds
    kept = result.top(top)
    config = {"creature": c.name, "trials": len(result.networks), "top": top}
    config |= {"seed": result.seed, "terrain": result.terrain, "seconds": result.seconds}
    write_toml(out / "config.toml", config | {"workers": result.workers})
    lines = ["trial,metric,speed_cm_s,fell,distance_m"]
    for i, (m, s, f, d) in enumerate(
        zip(result.metrics, speeds, result.fell, result.distances, strict=True)
    ):
        lines.append(f"{i},{m:.6g},{s:.4g},{int(f)},{d:.6g}")
    atomic_write_bytes(out / "trials.csv", ("\n".join(lines) + "\n").encode())
    sans = []
    for rank, i in enumerate(kept, start=1):
        info = {"rank": rank, "trial": i, "metric": float(result.metrics[i])}
        info |= {"speed_cm_s": round(float(speeds[i]), 3), "fell": bool(result.fell[i])}
        info |= {"terrain": result.terrain, "seed": result.seed, "seconds": result.seconds}
        net = result.networks[i].with_params(info=info)
        sans.append(save_network(net, out / "sans" / f"{rank:02d}.json", c))
    use = useful_mask(result)
    bar = getattr(c, "useful_speed", None)  # the creature's absolute bar (cm/s)
    absolute = None
    if bar is not None:
        ab = useful_mask(result, bar)
        absolute = f"{int(ab.sum())}/{len(ab)} ({100 * ab.mean():.1f}%, >= {bar:g} cm/s, no fall)"
    summary = {
        "creature": c.name,
        "trials": len(result.networks),
        "best_metric": round(float(result.metrics[kept[0]]), 4),
        "best_speed_cm_s": round(float(speeds[kept[0]]), 2),
        "paper_speed_cm_s": getattr(c, "paper_speed", None),
        "useful": f"{int(use.sum())}/{len(use)} ({100 * use.mean():.1f}%, "
        f">= {useful_threshold_cm_s(result):.3g} cm/s, half the best, without falling)",
        "useful_absolute": absolute,
        "fell": int(result.fell.sum()),
        "evaluation_s": round(result.elapsed, 2),
        "sans": str(out / "sans"),
    }
    write_json(out / "summary.json", summary)
    return summary
