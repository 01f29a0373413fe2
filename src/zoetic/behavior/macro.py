"""Macro controllers: sequences of repertoire entries optimised as a whole (section 3.2).

A plan is a fixed number L of segments, each an entry of the repertoire and how long it plays
(s); played in order as a SequenceController (5% linear cross-fades), its last entry holding
if the plan is shorter than the horizon. The objective of a reach-a-goal task is
    E = distance (m) of the centre of mass from the goal at the end of the horizon
        + obstacle_weight (m/s) * seconds spent inside any obstacle disc
        + time_weight (m/s) * time to reach the goal (the horizon when never reached)
        + depth_weight * the centre of mass's greatest depth change past depth_band (m)
        + attitude_weight (m/rad) * the worst roll past roll_ok,
so a plan that reaches the goal by sinking or rising away from the start depth, or by swimming
on its side or upside down, costs more. A fish's plans are judged as they are played: with the
righting reflex of ``behavior.upright`` (each 1 s window the planned entry or one of its
fin-righting variants, whichever keeps the fish upright and at depth), every plan of a batch a
lane of one World; each segment then lasts a whole number of windows (its duration rounded).
Two searches share an ask/tell interface and evaluate whole batches in one simulation:
simulated annealing (the paper's schedule, adapted to entries and durations) and a genetic
algorithm (tournaments, crossover of segment blocks, mutation of entries and durations),
which the paper suggests may suit this combinatorial problem better.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.targets import TrackingError
from zoetic.behavior.tracking import OVERLAP, TrackConfig, body_length, obstacle_seconds
from zoetic.behavior.upright import RightedPlans, attitude, has_fins, right_plans
from zoetic.bodies import Body
from zoetic.control.abstract import SequenceController, Waves
from zoetic.learning.blas import one_blas_thread
from zoetic.learning.optimizers import Annealing
from zoetic.physics import Trajectory, simulate


@dataclass(frozen=True)
class ReachTask:
    """Reach ``goal`` (x, z) within ``horizon`` s, keeping out of obstacle discs (x, z, r)."""

    goal: tuple[float, float]
    obstacles: tuple[tuple[float, float, float], ...] = ()
    horizon: float = 40.0
    radius: float | None = None  # reaching radius (m); default half a body length
    obstacle_weight: float = 1.0
    time_weight: float = 0.01
    depth_band: float = 0.5  # m above or below the start depth that costs nothing
    depth_weight: float = 10.0  # m of cost per m of depth change past the band
    roll_ok: float = 30.0  # deg of roll (either way) that costs nothing
    attitude_weight: float = 5.0  # m of cost per rad of the worst roll past roll_ok


def path_scores(com_xz: np.ndarray, record_dt: float, task: ReachTask, radius: float) -> dict:
    """Return closest/final distance (m), time in obstacles (s), reach time (s, NaN) and cost.

    com_xz: (B, R, 2) centre-of-mass paths in the horizontal plane, recorded record_dt apart.
    """
    d = np.linalg.norm(com_xz - np.asarray(task.goal, float), axis=-1)
    inside = obstacle_seconds(com_xz, np.asarray(task.obstacles, float), record_dt)
    hit = d < radius
    reach = np.where(hit.any(axis=1), hit.argmax(axis=1) * record_dt, np.nan)
    t_cost = np.where(np.isfinite(reach), reach, task.horizon)
    cost = d[:, -1] + task.obstacle_weight * inside + task.time_weight * t_cost
    return {
        "cost": cost,
        "closest": d.min(axis=1),
        "final": d[:, -1],
        "inside": inside,
        "reach": reach,
    }


class MacroProblem:
    """A reach task over a repertoire: plans of L (entry, duration) segments, scored in batches.

    righting: the reflex's knobs (``TrackConfig``: window, fin tilt, depth and attitude terms)
    with which plans are played and judged; None (or a finless animal): played as planned."""

    righting: TrackConfig | None = None

    def __init__(
        self,
        body: Body,
        repertoire: Repertoire,
        task: ReachTask,
        segments: int = 6,
        durations: tuple[float, float] | None = None,
        record_every: int = 10,
        allowed: tuple[str, ...] | None = None,
        righting: TrackConfig | None = None,
    ):
        self.body, self.task = body, task
        self.names = list(repertoire.names if allowed is None else allowed)
        missing = [n for n in self.names if n not in repertoire.controllers]
        if missing or not self.names:
            raise TrackingError(f"the repertoire has no entries {missing or self.names}")
        self.ctrls = [repertoire.controllers[n] for n in self.names]
        if segments < 1 or not task.horizon > 0:
            raise TrackingError("a plan needs at least one segment and a positive horizon")
        self.segments = int(segments)
        lo, hi = durations or (0.5, max(1.0, task.horizon / 2))
        if not 0 < lo < hi:
            raise TrackingError(f"durations must satisfy 0 < min < max, got {lo}, {hi}")
        self.lower, self.upper = float(lo), float(hi)
        self.radius = task.radius if task.radius is not None else 0.5 * body_length(body)
        self.record_every = int(record_every)
        self.steps = int(round(task.horizon / body.dt / self.record_every)) * self.record_every
        if righting is not None and has_fins(body, self.ctrls, righting.fin_tilt):
            self.righting = righting

    @property
    def entries(self) -> int:
        """Return the number of repertoire entries a segment can pick."""
        return len(self.names)

    def played(self, durations: np.ndarray) -> np.ndarray:
        """Return the segments' durations (s) as played: with the righting reflex each one's
        span (its duration less the cross-fade) is rounded to whole windows, at least one."""
        d = np.asarray(durations, float)
        if self.righting is None:
            return d
        step = self.righting.interval / (1.0 - OVERLAP)
        return np.maximum(1.0, np.round(d / step)) * step

    def sequence(self, entries: np.ndarray, durations: np.ndarray) -> SequenceController:
        """Return the plan as one controller: the entries in order, cross-faded."""
        played = self.played(durations)
        items = tuple((self.ctrls[int(e)], float(d)) for e, d in zip(entries, played, strict=True))
        c = self.ctrls[0]
        return SequenceController(c.animal, c.actuators, items, OVERLAP)

    @cached_property
    def _waves(self) -> dict[int, Waves]:
        """The entries' mode waves at the steps of the horizon (and those times), by
        controller id, filled as
        plans first play them (``SequenceController.raw``): computed once a problem."""
        return {}

    def tables(self, entries: np.ndarray, durations: np.ndarray) -> np.ndarray:
        """Return the activation tables (B, steps, A) of plans (B, L) over the horizon."""
        dt = self.body.dt
        return np.stack(
            [
                self.sequence(a, b).table(self.steps, dt, waves=self._waves)
                for a, b in zip(entries, durations, strict=True)
            ]
        )

    def random(self, rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Return n random plans: entries (n, L) and durations (n, L)."""
        e = rng.integers(0, self.entries, (n, self.segments))
        return e, rng.uniform(self.lower, self.upper, (n, self.segments))

    def rollout(self, entries, durations, record_every: int | None = None) -> Trajectory:
        """Return the trajectories of plans (B, L) played from rest over the horizon (with the
        righting reflex: recorded every ``righting.record_every`` steps)."""
        e, d = np.atleast_2d(entries), np.atleast_2d(durations)
        if self.righting is not None:
            return self.righted(e, d).trajectory()
        return simulate(
            self.body, self.tables(e, d), record_every=record_every or self.record_every
        )

    def righted(self, entries: np.ndarray, durations: np.ndarray) -> RightedPlans:
        """Return plans (B, L) played side by side with the righting reflex over the horizon."""
        plans = [
            ([self.names[int(i)] for i in a], self.sequence(a, b))
            for a, b in zip(entries, durations, strict=True)
        ]
        return right_plans(self.body, plans, self.task.horizon, self.righting)

    def evaluate(self, entries: np.ndarray, durations: np.ndarray) -> dict:
        """Return the scores (path_scores) of plans (B, L), all simulated as one batch."""
        traj = self.rollout(entries, durations)
        scores = self.scores(traj)
        scores["cost"] = np.where(traj.failed, np.inf, scores["cost"])
        return scores

    def scores(self, traj: Trajectory) -> dict:
        """Return path_scores of a trajectory of this problem's animal."""
        com3 = traj.com(self.body)
        out = path_scores(
            com3[..., [0, 2]], float(traj.times[1] - traj.times[0]), self.task, self.radius
        )
        dy = np.max(np.abs(com3[..., 1] - com3[:, :1, 1]), axis=1)
        roll, pitch = attitude(self.body, traj.positions)
        ok = np.isfinite(roll).all(axis=1)
        out["depth"] = dy
        out["roll"] = np.where(ok, np.max(np.abs(np.nan_to_num(roll)), axis=1), np.nan)
        out["pitch"] = np.where(ok, np.max(np.abs(np.nan_to_num(pitch)), axis=1), np.nan)
        t = self.task
        roll_over = np.radians(np.maximum(out["roll"] - t.roll_ok, 0.0))
        out["cost"] = (
            out["cost"]
            + t.depth_weight * np.maximum(dy - t.depth_band, 0.0)
            + t.attitude_weight * roll_over
        )
        return out


def _move(e, d, rng, k, lo, hi, step, swap):
    """Return perturbed plans: every duration by up to step of its range, entries by chance."""
    d = np.clip(d + rng.uniform(-1, 1, d.shape) * step * (hi - lo), lo, hi)
    e = e.copy()
    if k > 1:
        change = rng.random(e.shape) < step
        e[change] = (e[change] + rng.integers(1, k, change.sum())) % k  # a different entry
    n, length = e.shape
    if length > 1:
        for i in np.flatnonzero(rng.random(n) < swap):  # reorder: swap two neighbours
            j = rng.integers(0, length - 1)
            e[i, [j, j + 1]], d[i, [j, j + 1]] = e[i, [j + 1, j]], d[i, [j + 1, j]]
    return e, d


class _Search:
    """Shared bookkeeping of the plan searches: best plan, evaluation count."""

    name = "base"

    def __init__(self, problem: MacroProblem, seed: int):
        self.k, self.length = problem.entries, problem.segments
        self.lo, self.hi = problem.lower, problem.upper
        self.rng = np.random.default_rng(seed)
        self.random = lambda n: problem.random(self.rng, n)
        self.evaluations = 0
        self.best_f = np.inf
        self.best = (np.zeros(self.length, int), np.full(self.length, self.lo))

    def _record(self, e, d, f) -> np.ndarray:
        f = np.where(np.isfinite(f), f, np.inf)
        self.evaluations += len(f)
        i = int(np.argmin(f))
        if f[i] < self.best_f:
            self.best_f, self.best = float(f[i]), (e[i].copy(), d[i].copy())
        return f

    def status(self) -> dict:
        """Return a few numbers worth showing in a progress bar."""
        return {}


class PlanAnnealing(_Search):
    """Simulated annealing over plans with the paper's schedule, ``chains`` at a time.

    T0 = 0.5, T <- 0.9 T after at most 10 n steps or n accepted moves (n = 2L variables).
    Each step moves every duration uniformly by up to 10% of its range, replaces each entry
    by another with probability 10%, and swaps two neighbouring segments with probability
    10%. Temperatures are in units of the chains' mean starting cost. The annealing itself is
    ``learning.optimizers.Annealing`` over plans coded as [entries, durations].
    """

    name = "anneal"

    def __init__(self, problem, seed, chains=16, t0=0.5, alpha=0.9, step=0.1, swap=0.1):
        super().__init__(problem, seed)
        e, d = self.random(int(chains))
        n = self.length
        lower = np.concatenate([np.zeros(n), np.full(n, self.lo)])
        upper = np.concatenate([np.full(n, self.k - 1.0), np.full(n, self.hi)])

        def perturb(x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
            e, d = _move(x[:, :n].astype(int), x[:, n:], rng, self.k, self.lo, self.hi, step, swap)
            return np.hstack([e, d])

        self.sa = Annealing(
            np.hstack([e, d]),
            lower,
            upper,
            seed,
            t0=t0,
            alpha=alpha,
            chains=int(chains),
            perturb=perturb,
            relative=True,
            rng=self.rng,
        )

    @property
    def e(self) -> np.ndarray:
        """Return the chains' current entries (chains, L)."""
        return self.sa.x[:, : self.length].astype(int)

    @property
    def T(self) -> float:
        """The current temperature, in units of the chains' mean starting cost."""
        return self.sa.T

    def ask(self) -> tuple[np.ndarray, np.ndarray]:
        """Return the next batch of plans to evaluate: (entries, durations)."""
        x = self.sa.ask()
        return x[:, : self.length].astype(int), x[:, self.length :].copy()

    def tell(self, e, d, f) -> None:
        """Accept or reject each chain's move by the Metropolis rule at the current T."""
        f = self._record(e, d, f)
        self.sa.tell(np.hstack([e, d]).astype(float), f)

    def status(self):
        """Return {"T": the temperature, "accept": running acceptance rate, 0..1}."""
        return self.sa.status()


class PlanGenetic(_Search):
    """A generational genetic algorithm over plans, keeping the ``elite`` best unchanged.

    Parents are picked by tournaments of ``tournament``; a child takes one parent's segments
    with a block of the other's (probability ``crossover``), then each entry is replaced and
    each duration moved (Gaussian, 10% of the range) with probability 1/L, and two
    neighbouring segments swap with probability 10%.
    """

    name = "ga"

    def __init__(self, problem, seed, popsize=32, elite=2, tournament=3, crossover=0.9):
        super().__init__(problem, seed)
        self.popsize, self.elite = int(popsize), int(elite)
        self.tournament, self.crossover = int(tournament), float(crossover)
        self.pop: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self.generation = 0

    def _pick(self, f: np.ndarray) -> int:
        contenders = self.rng.integers(0, len(f), self.tournament)
        return int(contenders[np.argmin(f[contenders])])

    def ask(self) -> tuple[np.ndarray, np.ndarray]:
        """Return the next batch of plans to evaluate: the first population, then children."""
        if self.pop is None:
            return self.random(self.popsize)
        pe, pd, pf = self.pop
        n = self.popsize - self.elite
        ce, cd = np.empty((n, self.length), int), np.empty((n, self.length))
        for c in range(n):
            a, b = self._pick(pf), self._pick(pf)
            ce[c], cd[c] = pe[a], pd[a]
            if self.rng.random() < self.crossover and self.length > 1:
                i, j = np.sort(self.rng.choice(self.length + 1, 2, replace=False))
                ce[c, i:j], cd[c, i:j] = pe[b, i:j], pd[b, i:j]
        p = 1.0 / self.length
        if self.k > 1:
            change = self.rng.random(ce.shape) < p
            ce[change] = (ce[change] + self.rng.integers(1, self.k, change.sum())) % self.k
        nudge = self.rng.random(cd.shape) < p
        sigma = 0.1 * (self.hi - self.lo)
        cd = np.clip(cd + nudge * self.rng.normal(0, sigma, cd.shape), self.lo, self.hi)
        return _move(ce, cd, self.rng, self.k, self.lo, self.hi, 0.0, 0.1)

    def tell(self, e, d, f) -> None:
        """Form the next population from the elite and the evaluated children."""
        f = self._record(e, d, f)
        if self.pop is not None:
            pe, pd, pf = self.pop
            keep = np.argsort(pf, kind="stable")[: self.elite]
            e, d, f = (np.concatenate([x[keep], y]) for x, y in ((pe, e), (pd, d), (pf, f)))
        self.pop = (e.copy(), d.copy(), f.copy())
        self.generation += 1

    def status(self):
        """Return {"gen": the number of populations evaluated so far}."""
        return {"gen": float(self.generation)}


SEARCHES = {"anneal": PlanAnnealing, "ga": PlanGenetic}


@dataclass
class MacroResult:
    """The best plan a search found, its scores, and the best cost after each batch."""

    method: str
    names: list[str]  # entry name of each segment
    entries: np.ndarray  # (L,)
    durations: np.ndarray  # (L,) s
    sequence: SequenceController
    scores: dict  # path_scores of the best plan (floats)
    evaluations: int
    wall: float
    horizon: float
    history: list[tuple[int, float]] = field(default_factory=list)
    stopped: bool = False  # ended before its budget: ``stop`` said the best plan was good enough

    def summary(self) -> dict:
        """Return the numbers worth printing and saving."""
        s = self.scores
        return {
            "method": self.method,
            "cost": round(float(s["cost"]), 4),
            "closest_m": round(float(s["closest"]), 3),
            "final_m": round(float(s["final"]), 3),
            "inside_obstacle_s": round(float(s["inside"]), 2),
            "worst_depth_change_m": round(float(s["depth"]), 3),
            "worst_roll_deg": round(float(s["roll"]), 1),
            "worst_pitch_deg": round(float(s["pitch"]), 1),
            "reached_s": None if not np.isfinite(s["reach"]) else round(float(s["reach"]), 2),
            "evaluations": self.evaluations,
            "wall_s": round(self.wall, 2),
            "plan": [
                {
                    "entry": n,
                    "start_s": round(float(t), 3),
                    "duration_s": round(float(d), 3),
                    "played": bool(t < self.horizon),
                }
                for n, t, d in zip(self.names, self.sequence.starts(), self.durations, strict=True)
            ],
        }


@dataclass(frozen=True)
class _Plans:
    """Plans as one array (B, 2L), entries then durations: the job a Ray actor keeps."""

    problem: MacroProblem

    def evaluate(self, plans: np.ndarray) -> dict:
        k = plans.shape[1] // 2
        return self.problem.evaluate(plans[:, :k].astype(np.int64), plans[:, k:])


def search(
    problem: MacroProblem,
    method: str = "ga",
    budget: int = 2000,
    seed: int = 0,
    progress: Callable[[_Search], None] | None = None,
    evaluator: str = "batch",
    stop: Callable[[_Search], bool] | None = None,
    **options,
) -> MacroResult:
    """Return the best plan ``method`` (anneal or ga) finds within ``budget`` evaluations, or
    as soon as ``stop`` (asked after each batch) says the search's best plan will do.

    ``evaluator``: batch (this process) or ray (learning.ray_eval: RAY_ADDRESS, else a local Ray).
    """
    if method not in SEARCHES:
        raise TrackingError(f"unknown search method {method!r}: choose anneal or ga")
    if evaluator not in ("batch", "ray"):
        raise TrackingError(f"unknown evaluator {evaluator!r}: choose batch or ray")
    opt = SEARCHES[method](problem, seed, **options)
    pool = None
    if evaluator == "ray":
        from zoetic.learning.ray_eval import RayPool

        pool, job = RayPool(), _Plans(problem)

    def cost(e: np.ndarray, d: np.ndarray) -> np.ndarray:
        if pool is None:
            return problem.evaluate(e, d)["cost"]
        parts = pool.map(job, np.concatenate([e, d], axis=1).astype(np.float64))
        return np.concatenate([p["cost"] for p in parts])

    history = []
    start = time.perf_counter()
    stopped = False
    try:
        while opt.evaluations < budget and not stopped:
            with one_blas_thread():  # the plans' small products; see learning.blas
                e, d = opt.ask()
                opt.tell(e, d, cost(e, d))
            history.append((opt.evaluations, opt.best_f))
            if progress is not None:
                progress(opt)
            stopped = stop is not None and opt.evaluations < budget and bool(stop(opt))
    finally:
        if pool is not None:
            pool.close()
    wall = time.perf_counter() - start
    e, d = opt.best
    with one_blas_thread():
        scores = {k: float(v[0]) for k, v in problem.evaluate(e[None], d[None]).items()}
    return MacroResult(
        method=method,
        names=[problem.names[i] for i in e],
        entries=e,
        durations=problem.played(d),
        sequence=problem.sequence(e, d),
        scores=scores,
        evaluations=opt.evaluations,
        wall=wall,
        horizon=problem.task.horizon,
        history=history,
        stopped=stopped,
    )
