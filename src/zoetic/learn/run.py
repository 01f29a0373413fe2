"""A learning run: optimizer x objective x evaluator, checkpointed, resumable, reproducible.

The checkpoint is the log of every ask/tell exchange. Because each optimizer is deterministic
given its seed, resuming rebuilds it from ``config.toml`` and replays the log (no simulation),
which leaves it in exactly the state it had, then carries on to the same budget: an
interrupted run and an uninterrupted one with the same seed end with the same result.
"""

from __future__ import annotations

import io
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from zoetic.bodies import load_animal
from zoetic.control import Controller, frequency_domain, save_controller, time_domain
from zoetic.errors import RunDirError, ZoeticError
from zoetic.io import atomic_write_bytes, read_toml, write_toml
from zoetic.learn.evaluate import make_evaluator
from zoetic.learn.objective import Objective
from zoetic.learn.optimizers import Optimizer, make_optimizer
from zoetic.tasks import Task, load_task, parse_task

# Defaults measured on the zoo (docs/reproduction.md, "Why default learning was weak"): a
# gait is periodic, so the default controller is a Fourier series on harmonics of the animal's
# stroke frequency (a constant and two harmonics per actuator), which keeps going past the
# horizon; CMA-ES asks for populations of 32, which the batched kernel simulates at once.
PERIODIC_NODES = 5
CMAES_POPSIZE = 32


@dataclass
class LearnConfig:
    """Everything that defines a learning run (written to config.toml)."""

    animal: str = "shark"
    task: str = "swim-straight"
    optimizer: str = "cmaes"
    budget: int = 3500
    seed: int = 0
    controller: str = "periodic"
    nodes: int | None = None
    interp: str = "linear"
    popsize: int | None = None
    chains: int = 1
    evaluator: str = "batch"
    coupling: str = "none"
    medium: str | None = None
    frequency: float | None = None  # periodic controller's base frequency, Hz (animal's wave)
    extra: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        d = {k: v for k, v in asdict(self).items() if v is not None}
        return d


@dataclass
class Setup:
    """The pieces a run is built from."""

    config: LearnConfig
    task: Task
    objective: Objective
    optimizer: Optimizer
    template: Controller


def build(config: LearnConfig, task: Task | None = None) -> Setup:
    """Return the body, task, objective and a fresh optimizer for a configuration."""
    body = load_animal(config.animal)
    task = task or load_task(config.task)
    if task.animals and body.name not in task.animals:
        raise ZoeticError(
            f"task {task.name!r} is for {', '.join(task.animals)}, not the {body.name}"
        )
    periodic = config.controller == "periodic"
    m = config.nodes or (PERIODIC_NODES if periodic else task.nodes)
    if config.controller == "time":
        template = time_domain(body, m, task.horizon, interp=config.interp)
    elif config.controller == "frequency":
        template = frequency_domain(body, m, task.horizon)
    elif periodic:
        base = config.frequency or body.wave_frequency
        if not base > 0:
            raise ZoeticError(f"the periodic controller needs a positive frequency, got {base}")
        template = frequency_domain(body, m, task.horizon, base=base)
    else:
        raise ZoeticError(
            f"unknown controller {config.controller!r} (periodic, time or frequency)"
        )
    if m != task.nodes:
        task = parse_task({**task.to_dict(), "nodes": m}, task.source)
    objective = Objective(task, body, template, config.medium, coupling=config.coupling)
    lo, hi = objective.bounds()
    rng = np.random.default_rng(config.seed)
    x0 = rng.uniform(lo, hi)
    if config.controller != "time":  # random small amplitudes about a mid-level constant
        x0 = np.clip(x0 * 0.5 + np.where(hi == 1.0, 0.25, 0.0), lo, hi)
    options = {}
    if config.optimizer == "cmaes":
        options["popsize"] = config.popsize or CMAES_POPSIZE
    if config.optimizer == "anneal" and config.chains > 1:
        options["chains"] = config.chains
    opt = make_optimizer(config.optimizer, x0, lo, hi, config.seed, config.budget, **options)
    return Setup(config, task, objective, opt, template)


@dataclass
class Log:
    """Every evaluation in order: parameters, E and its parts, wall time; and batch sizes."""

    X: list = field(default_factory=list)
    E: list = field(default_factory=list)
    E_u: list = field(default_factory=list)
    E_v: list = field(default_factory=list)
    wall: list = field(default_factory=list)
    batches: list = field(default_factory=list)

    def add(self, X, ev, wall: float) -> None:
        self.X.extend(np.asarray(X))
        self.E.extend(ev.E)
        self.E_u.extend(ev.E_u)
        self.E_v.extend(ev.E_v)
        self.wall.extend([wall] * len(ev.E))
        self.batches.append(len(ev.E))

    def save(self, path: Path) -> None:
        buf = io.BytesIO()
        np.savez_compressed(
            buf, X=np.array(self.X), E=np.array(self.E), E_u=np.array(self.E_u),
            E_v=np.array(self.E_v), wall=np.array(self.wall), batches=np.array(self.batches),
        )  # fmt: skip
        atomic_write_bytes(path, buf.getvalue())

    @classmethod
    def load(cls, path: Path) -> Log:
        try:
            with np.load(path) as z:
                return cls(*(list(z[k]) for k in ("X", "E", "E_u", "E_v", "wall")),
                           batches=list(z["batches"]))  # fmt: skip
        except (OSError, KeyError, ValueError) as exc:
            raise RunDirError(f"{path}: unreadable checkpoint ({exc})") from None

    def history_csv(self) -> bytes:
        best = np.minimum.accumulate(np.array(self.E)) if self.E else np.array([])
        lines = ["evaluation,E,E_u,E_v,best_E,wall_time"]
        for i, (e, eu, ev, b, w) in enumerate(
            zip(self.E, self.E_u, self.E_v, best, self.wall, strict=True)
        ):
            lines.append(f"{i + 1},{e:.6g},{eu:.6g},{ev:.6g},{b:.6g},{w:.3f}")
        return ("\n".join(lines) + "\n").encode()


def _replay(opt: Optimizer, log: Log) -> None:
    """Feed a fresh optimizer the logged exchanges, checking it asks for the same points."""
    X = np.array(log.X)
    E = np.array(log.E)
    i = 0
    for n in log.batches:
        asked = opt.ask()
        if asked.shape[0] != n or not np.allclose(asked, X[i : i + n], rtol=0, atol=1e-12):
            raise RunDirError(
                "the checkpoint does not match this configuration (the optimizer asks for "
                "different points); was config.toml edited?"
            )
        opt.tell(asked, E[i : i + n])
        i += n


class Run:
    """A run directory being learned into."""

    def __init__(self, out: Path, setup: Setup, log: Log | None = None):
        self.out = Path(out)
        self.setup = setup
        self.log = log or Log()
        self.t_start = time.perf_counter() - (self.log.wall[-1] if self.log.wall else 0.0)

    @classmethod
    def create(cls, out: Path, config: LearnConfig) -> Run:
        """Start a new run in ``out`` (refuses a directory that already holds one)."""
        out = Path(out)
        if (out / "checkpoint.npz").exists():
            raise RunDirError(
                f"{out} already holds a run; resume it with --resume {out} or choose another --out"
            )
        setup = build(config)
        out.mkdir(parents=True, exist_ok=True)
        write_toml(out / "config.toml", {"run": config.to_dict(), "task": setup.task.to_dict()})
        return cls(out, setup)

    @classmethod
    def resume(cls, out: Path) -> Run:
        """Rebuild a run from its config.toml and replay its checkpoint."""
        out = Path(out)
        if not (out / "config.toml").exists():
            raise RunDirError(f"{out}: no config.toml, so not a zoetic run directory")
        doc = read_toml(out / "config.toml", what="run configuration")
        try:
            config = LearnConfig(**doc["run"])
            task = parse_task(doc["task"], str(out / "config.toml"))
        except (KeyError, TypeError) as exc:
            raise RunDirError(f"{out / 'config.toml'}: malformed ({exc})") from None
        if config.optimizer == "gradient" and cls is Run:
            from zoetic.learn.gradient_run import GradientRun

            return GradientRun.resume_gradient(out)
        setup = build(config, task)
        log = Log.load(out / "checkpoint.npz") if (out / "checkpoint.npz").exists() else Log()
        _replay(setup.optimizer, log)
        return cls(out, setup, log)

    @property
    def evaluations(self) -> int:
        return len(self.log.E)

    def best_controller(self) -> Controller:
        """Return the best controller found so far."""
        return self.setup.objective.controller(self.setup.optimizer.best_x)

    def checkpoint(self) -> None:
        """Write checkpoint.npz, history.csv and controller.json (each atomically)."""
        self.log.save(self.out / "checkpoint.npz")
        atomic_write_bytes(self.out / "history.csv", self.log.history_csv())
        if np.isfinite(self.setup.optimizer.best_f):
            save_controller(self.best_controller(), self.out / "controller.json")

    def step(self, evaluator) -> int:
        """Ask, evaluate and tell one batch; return how many evaluations it made."""
        opt = self.setup.optimizer
        X = opt.ask()
        if len(X) == 0:
            return 0
        ev = evaluator(self.setup.objective, X)
        opt.tell(X, ev.E)
        self.log.add(X, ev, time.perf_counter() - self.t_start)
        return len(X)

    def learn(self, progress: Callable[[Run], None] | None = None, every_s: float = 2.0):
        """Run to the budget, checkpointing every ``every_s`` seconds and on interruption."""
        config = self.setup.config
        evaluator = make_evaluator(config.evaluator)
        last = time.perf_counter()
        try:
            while self.evaluations < config.budget and not self.setup.optimizer.done():
                if self.step(evaluator) == 0:
                    break
                if progress:
                    progress(self)
                if time.perf_counter() - last > every_s:
                    self.checkpoint()
                    last = time.perf_counter()
        finally:
            evaluator.close()
            self.checkpoint()
            close = getattr(self.setup.optimizer, "close", None)
            if close:
                close()
        return self
