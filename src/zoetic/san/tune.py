"""Phase 2 of SAN synthesis: fine-tune the Fig. 8 parameters, keeping the weights.

The parameters (van de Panne & Fiume 93, Fig. 8) are the delays of the hidden nodes (k1, k2),
each actuator's range and strength (Amin, Amax, ks, kd) and the sensing range of every sensor
that has one (Smin, Smax; touch sensors have none) - 44 for the boulder, as in the paper.
Each trial perturbs one randomly chosen parameter by +delta or -delta: rates and gains are
scaled by (1 + delta) or 1 / (1 + delta), ranges are shifted by delta/2 of their initial span.

- ``sga``: stochastic gradient ascent, Fig. 9: keep a change only if the metric improved.
- ``anneal``: simulated annealing: 65 evaluations per temperature, then T <- 0.75 T; a worse
  change is kept with probability exp(df / T). The best network ever seen is returned.

Both never return a network worse (on the same evaluation) than the one they started with,
and the same seed gives the same result.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from zoetic.errors import ZoeticError
from zoetic.learning.optimizers import Annealing
from zoetic.san.network import TUNING_KEYS, Network, SanPolicy, check_fits

__all__ = [
    "METHODS",
    "MeanEvaluator",
    "Param",
    "TuneResult",
    "Walk",
    "WorldEvaluator",
    "anneal_values",
    "tunable_parameters",
    "tune",
]

METHODS = ("sga", "anneal")
Evaluate = Callable[[Network, object], float]  # (network, tuned creature) -> metric
Progress = Callable[[int, int, float], None]  # (done, total, best metric so far)


class TuneError(ZoeticError):
    """Fine-tuning was asked for something it cannot do."""


@dataclass(frozen=True)
class Param:
    """One tunable parameter: which array (``key``), which entry, and how it is perturbed."""

    key: str  # "k1", "k2" or one of TUNING_KEYS
    index: int
    mode: str  # "scale" or "shift"
    step: float  # scale factor - 1, or shift in the parameter's unit

    @property
    def name(self) -> str:
        """Return a readable name such as ``ks[0]``."""
        return f"{self.key}[{self.index}]"


def _start_values(network: Network, creature) -> dict[str, np.ndarray]:
    tuning = network.tuning if network.tuning is not None else creature.tuning()
    values = {k: np.asarray(tuning[k], dtype=float).copy() for k in TUNING_KEYS}
    values["k1"] = network.k1.copy()
    values["k2"] = network.k2.copy()
    return values


def tunable_parameters(network: Network, creature, delta: float = 0.1) -> list[Param]:
    """Return the Fig. 8 parameters of this network and creature, with their step sizes."""
    values = _start_values(network, creature)
    params: list[Param] = []
    for i in range(network.n_hidden):
        params += [Param("k1", i, "scale", delta), Param("k2", i, "scale", delta)]
    for i in range(network.n_actuators):
        span = abs(values["actuator_hi"][i] - values["actuator_lo"][i]) or 1.0
        params += [
            Param("actuator_lo", i, "shift", 0.5 * delta * span),
            Param("actuator_hi", i, "shift", 0.5 * delta * span),
            Param("ks", i, "scale", delta),
            Param("kd", i, "scale", delta),
        ]
    kinds = [getattr(s, "kind", "angle") for s in getattr(creature, "sensors", ())]
    for i in range(network.n_sensors):
        lo, hi = values["sensor_lo"][i], values["sensor_hi"][i]
        if (kinds and kinds[i] == "touch") or not (np.isfinite(lo) and np.isfinite(hi)):
            continue
        span = abs(hi - lo) or 1.0
        params += [
            Param("sensor_lo", i, "shift", 0.5 * delta * span),
            Param("sensor_hi", i, "shift", 0.5 * delta * span),
        ]
    return params


def _perturbed(values: dict[str, np.ndarray], p: Param, sign: int) -> dict[str, np.ndarray] | None:
    """Return new values with ``p`` moved one step in direction ``sign``; None if invalid."""
    arr = values[p.key].copy()
    if p.mode == "scale":
        factor = 1.0 + p.step
        arr[p.index] *= factor if sign > 0 else 1.0 / factor
    else:
        arr[p.index] += sign * p.step
    out = dict(values)
    out[p.key] = arr
    for lo, hi in (("actuator_lo", "actuator_hi"), ("sensor_lo", "sensor_hi")):
        if p.key in (lo, hi) and not out[lo][p.index] < out[hi][p.index]:
            return None
    return out


def _network(network: Network, values: dict[str, np.ndarray]) -> Network:
    return network.with_params(
        k1=values["k1"], k2=values["k2"], tuning={k: values[k] for k in TUNING_KEYS}
    )


class WorldEvaluator:
    """Evaluate a network in one World, re-applying the Fig. 8 parameters when they change
    (``mirror``: on the seed's follow spline reflected left for right)."""

    def __init__(
        self,
        terrain: str = "flat",
        seed: int = 0,
        seconds: float | None = None,
        mirror: bool = False,
    ):
        self.terrain, self.seed, self.seconds, self.mirror = terrain, seed, seconds, mirror
        self._key: bytes | None = None
        self._world = None

    def __call__(self, network: Network, creature) -> float:
        """Return the world's metric for the network on the (tuned) creature."""
        from zoetic.san.world import World

        tuning = creature.tuning()
        key = b"".join(np.asarray(tuning[k], dtype=float).tobytes() for k in TUNING_KEYS)
        if self._world is None:
            self._world = World(creature, self.terrain, self.seed, mirror=self.mirror)
        elif key != self._key:
            self._world.set_tuning(creature)  # no recompile: same structure, new parameters
        self._key = key
        rollout = self._world.run(SanPolicy(network, creature), seconds=self.seconds)
        metric = float(rollout.metric)
        return metric if np.isfinite(metric) else -math.inf


class MeanEvaluator:
    """Evaluate a network as the mean metric over worlds of several seeds: for a "follow"
    creature, several splines, so that tuning rewards pursuit in general rather than the
    manoeuvres that happen to fit one path. With ``mirror``, each seed's spline counts twice:
    as it is and reflected left for right, so that turning one way can earn nothing the other
    way does not."""

    def __init__(
        self,
        seeds: Sequence[int],
        terrain: str = "flat",
        seconds: float | None = None,
        mirror: bool = False,
    ):
        if not seeds:
            raise TuneError("MeanEvaluator needs at least one seed")
        sides = (False, True) if mirror else (False,)
        self.parts = [WorldEvaluator(terrain, int(s), seconds, m) for s in seeds for m in sides]

    def __call__(self, network: Network, creature) -> float:
        """Return the mean of the worlds' metrics (-inf if any world's metric is not finite)."""
        return float(np.mean([part(network, creature) for part in self.parts]))


@dataclass(frozen=True, eq=False)
class TuneResult:
    """A fine-tuning run: the best network, its metric before and after, and the history."""

    network: Network  # the best network found (weights unchanged)
    start: Network
    before: float
    after: float
    method: str
    trials: int
    seed: int
    current: np.ndarray  # (trials,) metric of the current network after each trial
    best: np.ndarray  # (trials,) best metric so far after each trial
    tried: np.ndarray  # (trials,) metric of each trial's candidate (nan: invalid step)
    accepted: int
    elapsed: float


@dataclass(frozen=True, eq=False)
class Walk:
    """What one annealing walk over named parameter arrays found."""

    values: dict[str, np.ndarray]  # the best values seen (the start's when nothing beat it)
    before: float
    after: float
    current: np.ndarray
    best: np.ndarray
    tried: np.ndarray
    accepted: int
    state: dict  # the optimizer's state_dict() at the end (to resume)


Checkpoint = Callable[[int, "Annealing", dict], None]  # (trials done, optimizer, history)


class _Moves:
    """The walk's space: ``values`` flattened into one vector, and its one-parameter move
    (a move that ``_perturbed`` or ``valid`` refuses leaves ``invalid`` set)."""

    def __init__(self, values: dict[str, np.ndarray], params: list[Param], valid=None):
        self.keys = list(values)
        self.shapes = [values[k].shape for k in self.keys]
        self.splits = np.cumsum([values[k].size for k in self.keys])[:-1]
        self.params, self.valid = params, valid
        self.invalid = False

    def flat(self, values: dict[str, np.ndarray]) -> np.ndarray:
        return np.concatenate([values[k].ravel() for k in self.keys])

    def unflat(self, x: np.ndarray) -> dict[str, np.ndarray]:
        parts = np.split(np.asarray(x, dtype=float), self.splits)
        pairs = zip(self.keys, parts, self.shapes, strict=True)
        return {k: a.reshape(shape).copy() for k, a, shape in pairs}

    def perturb(self, x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        p = self.params[int(rng.integers(len(self.params)))]
        sign = 1 if rng.random() < 0.5 else -1
        cand = _perturbed(self.unflat(x[0]), p, sign)
        if cand is not None and self.valid is not None and not self.valid(cand):
            cand = None
        self.invalid = cand is None
        return x if cand is None else self.flat(cand)[None]


def anneal_values(
    values: dict[str, np.ndarray],
    params: list[Param],
    score: Callable[[dict[str, np.ndarray]], float],
    method: str = "anneal",
    trials: int = 1000,
    seed: int = 0,
    progress: Progress | None = None,
    per_temperature: int = 65,
    cooling: float = 0.75,
    temperature: float | None = None,
    valid: Callable[[dict[str, np.ndarray]], bool] | None = None,
    resume: dict | None = None,
    checkpoint: Checkpoint | None = None,
    every: int = 25,
) -> Walk:
    """Maximise ``score(values)`` by moving one of ``params`` a step at a time (the walk
    of ``tune``, also used by ``evolve``): annealing (learning.optimizers.Annealing) minimising
    -score, T dropping every ``per_temperature`` trials; ``sga`` is the same walk at T = 0,
    keeping strict improvements. A step that ``_perturbed`` or ``valid`` refuses counts as a
    trial but is not evaluated. ``resume`` (a ``checkpoint``'s history) continues a walk.
    """
    moves = _Moves(values, params, valid)

    def safe(v: dict[str, np.ndarray]) -> float:
        f = float(score(v))
        return f if np.isfinite(f) else -math.inf

    x0 = moves.flat(values)
    track = {"current": np.empty(trials), "best": np.empty(trials)}
    track["tried"] = np.full(trials, np.nan)
    if resume is not None:
        f_start, accepted = float(resume["before"]), int(resume["accepted"])
        done, temp = int(resume["done"]), float(resume["temperature"])
    else:
        f_start, accepted, done = safe(values), 0, 0
        temp = float(temperature) if temperature is not None else 0.1 * max(abs(f_start), 1e-3)
    sa = Annealing(
        x0,
        np.full(x0.size, -np.inf),
        np.full(x0.size, np.inf),
        seed,
        t0=temp if method == "anneal" else 0.0,
        alpha=cooling,
        perturb=moves.perturb,
        max_steps=per_temperature,
        min_accepts=10**18,
        accept_ties=method == "anneal",
    )
    if resume is not None:
        sa.load_state_dict(resume["state"])
        for name, arr in track.items():
            arr[: min(done, trials)] = np.asarray(resume[name], dtype=float)[: min(done, trials)]
    else:
        sa.tell(sa.ask(), np.array([-f_start]))
    for t in range(done, trials):
        X = sa.ask()
        g = np.inf  # a refused move is not evaluated; rejected, but it counts in the schedule
        if not moves.invalid:
            track["tried"][t] = f = safe(moves.unflat(X[0]))
            g = -f
        sa.tell(X, np.array([g]))
        accepted += int(sa.last_accept[0])
        track["current"][t], track["best"][t] = -sa.f[0], -sa.best_f
        if progress is not None:
            progress(t + 1, trials, -sa.best_f)
        if checkpoint is not None and ((t + 1) % every == 0 or t + 1 == trials):
            history = {k: v[: t + 1].tolist() for k, v in track.items()}
            history |= {"before": f_start, "accepted": accepted, "done": t + 1}
            checkpoint(t + 1, sa, history | {"temperature": temp, "state": sa.state_dict()})
    f_best = -sa.best_f
    kept = moves.unflat(sa.best_x) if f_best > f_start else {k: v.copy() for k, v in values.items()}
    return Walk(
        values=kept,
        before=f_start,
        after=max(f_best, f_start),
        accepted=accepted,
        state=sa.state_dict(),
        **track,
    )


def tune(
    network: Network,
    creature,
    method: str = "sga",
    trials: int = 1000,
    seed: int = 0,
    terrain: str = "flat",
    seconds: float | None = None,
    delta: float = 0.1,
    progress: Progress | None = None,
    evaluate: Evaluate | None = None,
    per_temperature: int = 65,
    cooling: float = 0.75,
    temperature: float | None = None,
) -> TuneResult:
    """Return the network with its Fig. 8 parameters tuned by ``method`` (weights kept).

    ``evaluate(network, tuned_creature) -> metric`` defaults to a World on ``terrain``.
    ``temperature`` (annealing's first T) defaults to 0.1 x the starting metric.
    """
    if method not in METHODS:
        raise TuneError(f"unknown tuning method {method!r}; use one of {', '.join(METHODS)}")
    if trials < 0:
        raise TuneError("trials must be >= 0")
    check_fits(network, creature)
    evaluate = evaluate or WorldEvaluator(terrain, seed, seconds)
    params = tunable_parameters(network, creature, delta)
    if not params:
        raise TuneError(f"creature {creature.name!r} has no tunable parameters")
    t0 = time.perf_counter()

    def score(values: dict[str, np.ndarray]) -> float:
        net = _network(network, values)
        tuned = creature.with_tuning(**{k: values[k] for k in TUNING_KEYS})
        return float(evaluate(net, tuned))

    walk = anneal_values(
        _start_values(network, creature),
        params,
        score,
        method,
        trials,
        seed,
        progress,
        per_temperature,
        cooling,
        temperature,
    )
    f_start, f_best = walk.before, walk.after
    start_net = _network(network, _start_values(network, creature))
    best_net = _network(network, walk.values) if f_best > f_start else start_net
    current, best, tried, accepted = walk.current, walk.best, walk.tried, walk.accepted
    info = dict(network.info)
    info.update(tuned=method, trials=trials, seed=seed, before=f_start, after=f_best)
    best_net = best_net.with_params(info=info)
    return TuneResult(
        network=best_net,
        start=network,
        before=f_start,
        after=f_best,
        method=method,
        trials=trials,
        seed=seed,
        current=current,
        best=best,
        tried=tried,
        accepted=accepted,
        elapsed=time.perf_counter() - t0,
    )


def write_tune(result: TuneResult, creature, out, terrain: str = "flat") -> dict:
    """Write a tune run directory's data (san.json and start.json, each carrying the creature;
    config.toml, history.csv, summary.json) and return the summary. Its pictures (tuning.png,
    video.mp4) are drawn by ``zoetic.viz.san.draw_tune``."""
    from pathlib import Path

    from zoetic.io import atomic_write_bytes, write_json, write_toml
    from zoetic.san.network import save_network
    from zoetic.san.search import speed_cm_s
    from zoetic.san.show import replay

    out = Path(out)
    net = result.network.with_params(info=dict(result.network.info) | {"terrain": terrain})
    save_network(net, out / "san.json", creature)
    save_network(result.start, out / "start.json", creature)
    config = {"creature": creature.name, "method": result.method, "trials": result.trials}
    write_toml(out / "config.toml", config | {"seed": result.seed, "terrain": terrain})
    rows = zip(result.tried, result.current, result.best, strict=True)
    lines = ["trial,candidate,current,best"]
    lines += [f"{i + 1},{a:.6g},{b:.6g},{c:.6g}" for i, (a, b, c) in enumerate(rows)]
    atomic_write_bytes(out / "history.csv", ("\n".join(lines) + "\n").encode())
    if creature.metric in ("distance", "follow"):  # the metric is the distance covered
        before = speed_cm_s(creature, result.before, 0.0)
        after = speed_cm_s(creature, result.after, 0.0)
    else:  # tuning never changes the metric's kind; a hop's speed needs its distance: replay
        ro = replay(net, creature, terrain=terrain)
        before, after = float("nan"), speed_cm_s(creature, ro.metric, ro.distance, ro.seconds)
    summary = {
        "creature": creature.name,
        "method": result.method,
        "trials": result.trials,
        "metric_before": round(result.before, 4),
        "metric_after": round(result.after, 4),
        "speed_before_cm_s": round(before, 2),
        "speed_after_cm_s": round(after, 2),
        "accepted": result.accepted,
        "seconds": round(result.elapsed, 1),
        "network": str(out / "san.json"),
    }
    write_json(out / "summary.json", summary)
    return summary
