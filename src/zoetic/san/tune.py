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
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from zoetic.errors import ZoeticError
from zoetic.learning.optimizers import Annealing
from zoetic.san.network import TUNING_KEYS, Network, SanPolicy, check_fits

__all__ = [
    "METHODS", "Param", "TuneResult", "Walk", "WorldEvaluator", "anneal_values",
    "tunable_parameters", "tune",
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
    """Evaluate a network in one World, re-applying the Fig. 8 parameters when they change."""

    def __init__(self, terrain: str = "flat", seed: int = 0, seconds: float | None = None):
        self.terrain, self.seed, self.seconds = terrain, seed, seconds
        self._key: bytes | None = None
        self._world = None

    def __call__(self, network: Network, creature) -> float:
        """Return the world's metric for the network on the (tuned) creature."""
        from zoetic.san.world import World

        tuning = creature.tuning()
        key = b"".join(np.asarray(tuning[k], dtype=float).tobytes() for k in TUNING_KEYS)
        if self._world is None:
            self._world = World(creature, terrain=self.terrain, seed=self.seed)
        elif key != self._key:
            self._world.set_tuning(creature)  # no recompile: same structure, new parameters
        self._key = key
        rollout = self._world.run(SanPolicy(network, creature), seconds=self.seconds)
        metric = float(rollout.metric)
        return metric if np.isfinite(metric) else -math.inf


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
    keys = list(values)
    sizes = [values[k].size for k in keys]

    def unflat(x: np.ndarray) -> dict[str, np.ndarray]:
        parts = np.split(np.asarray(x, dtype=float), np.cumsum(sizes)[:-1])
        return {k: a.reshape(values[k].shape).copy() for k, a in zip(keys, parts, strict=True)}

    invalid = [False]

    def perturb(x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        p = params[int(rng.integers(len(params)))]
        sign = 1 if rng.random() < 0.5 else -1
        cand = _perturbed(unflat(x[0]), p, sign)
        if cand is not None and valid is not None and not valid(cand):
            cand = None
        invalid[0] = cand is None
        return x if cand is None else np.concatenate([cand[k].ravel() for k in keys])[None]

    def safe(v: dict[str, np.ndarray]) -> float:
        f = float(score(v))
        return f if np.isfinite(f) else -math.inf

    x0 = np.concatenate([values[k].ravel() for k in keys])
    current, best = np.empty(trials), np.empty(trials)
    tried = np.full(trials, np.nan)
    if resume is not None:
        f_start, accepted = float(resume["before"]), int(resume["accepted"])
        done = int(resume["done"])
        temp = float(resume["temperature"])
    else:
        f_start, accepted, done = safe(values), 0, 0
        temp = float(temperature) if temperature is not None else 0.1 * max(abs(f_start), 1e-3)
    sa = Annealing(x0, np.full(x0.size, -np.inf), np.full(x0.size, np.inf), seed,
                   t0=temp if method == "anneal" else 0.0, alpha=cooling, perturb=perturb,
                   max_steps=per_temperature, min_accepts=10**18,
                   accept_ties=method == "anneal")  # fmt: skip
    if resume is not None:
        sa.load_state_dict(resume["state"])
        n = min(done, trials)
        for name, arr in (("current", current), ("best", best), ("tried", tried)):
            arr[:n] = np.asarray(resume[name], dtype=float)[:n]
    else:
        sa.tell(sa.ask(), np.array([-f_start]))
    for t in range(done, trials):
        X = sa.ask()
        if invalid[0]:
            g = np.inf  # not evaluated; rejected, but the trial counts in the schedule
        else:
            f = safe(unflat(X[0]))
            tried[t], g = f, -f
        sa.tell(X, np.array([g]))
        accepted += int(sa.last_accept[0])
        current[t], best[t] = -sa.f[0], -sa.best_f
        if progress is not None:
            progress(t + 1, trials, -sa.best_f)
        if checkpoint is not None and ((t + 1) % every == 0 or t + 1 == trials):
            checkpoint(t + 1, sa, {
                "before": f_start, "accepted": accepted, "done": t + 1, "temperature": temp,
                "current": current[: t + 1].tolist(), "best": best[: t + 1].tolist(),
                "tried": tried[: t + 1].tolist(), "state": sa.state_dict(),
            })  # fmt: skip
    f_best = -sa.best_f
    return Walk(
        values=unflat(sa.best_x) if f_best > f_start else {k: v.copy() for k, v in values.items()},
        before=f_start, after=max(f_best, f_start), current=current, best=best, tried=tried,
        accepted=accepted, state=sa.state_dict(),
    )  # fmt: skip


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
        _start_values(network, creature), params, score, method, trials, seed, progress,
        per_temperature, cooling, temperature,
    )  # fmt: skip
    f_start, f_best = walk.before, walk.after
    start_net = _network(network, _start_values(network, creature))
    best_net = _network(network, walk.values) if f_best > f_start else start_net
    current, best, tried, accepted = walk.current, walk.best, walk.tried, walk.accepted
    info = dict(network.info)
    info.update(tuned=method, trials=trials, seed=seed, before=f_start, after=f_best)
    best_net = best_net.with_params(info=info)
    return TuneResult(
        network=best_net, start=network, before=f_start, after=f_best, method=method,
        trials=trials, seed=seed, current=current, best=best, tried=tried, accepted=accepted,
        elapsed=time.perf_counter() - t0,
    )  # fmt: skip


def plot_tuning(result: TuneResult, path, title: str = ""):
    """Write tuning.png: each candidate's metric, the accepted and the best against trials."""
    from zoetic.viz.san import plot_tuning as plot

    return plot(result, path, title)

def write_tune(result: TuneResult, creature, out, terrain: str = "flat", video: bool = True):
    """Write a tune run directory (san.json, start.json, history.csv, tuning.png, video.mp4)."""
    from pathlib import Path

    from zoetic.io import atomic_write_bytes, write_json, write_toml
    from zoetic.san.network import save_network
    from zoetic.san.search import speed_cm_s

    out = Path(out)
    seconds = float(creature.seconds)
    info = dict(result.network.info)
    info["terrain"] = terrain
    net = result.network.with_params(info=info)
    save_network(net, out / "san.json")
    save_network(result.start, out / "start.json")
    write_toml(out / "config.toml", {
        "creature": creature.name, "method": result.method, "trials": result.trials,
        "seed": result.seed, "terrain": terrain,
    })  # fmt: skip
    lines = ["trial,candidate,current,best"] + [
        f"{i + 1},{a:.6g},{b:.6g},{c:.6g}"
        for i, (a, b, c) in enumerate(zip(result.tried, result.current, result.best, strict=True))
    ]
    atomic_write_bytes(out / "history.csv", ("\n".join(lines) + "\n").encode())
    plot_tuning(result, out / "tuning.png", f"{creature.name} {result.method}")

    def speed(metric: float) -> float:
        # tuning never changes the metric's kind; hop speed needs the distance, so replay
        if creature.metric in ("distance", "follow"):
            return speed_cm_s(creature, metric, 0.0, seconds)
        return float("nan")

    summary = {
        "creature": creature.name,
        "method": result.method,
        "trials": result.trials,
        "metric_before": round(result.before, 4),
        "metric_after": round(result.after, 4),
        "speed_before_cm_s": round(speed(result.before), 2),
        "speed_after_cm_s": round(speed(result.after), 2),
        "accepted": result.accepted,
        "seconds": round(result.elapsed, 1),
        "network": str(out / "san.json"),
        "tuning_plot": str(out / "tuning.png"),
    }
    if video:
        from zoetic.san.show import show_video

        path, rollout = show_video(net, creature, out / "video.mp4", terrain=terrain)
        if creature.metric not in ("distance", "follow"):
            summary["speed_after_cm_s"] = round(
                speed_cm_s(creature, rollout.metric, rollout.distance, rollout.seconds), 2
            )
        summary["video"] = str(path)
    write_json(out / "summary.json", summary)
    return summary
