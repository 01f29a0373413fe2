"""A learning run: optimizer x objective x evaluator, checkpointed, resumable, reproducible.

The checkpoint (``checkpoint.npz``) holds the log of every evaluation and the optimizer's
whole state (``state_dict``), with a SHA-256 checksum over both; it is written atomically and
the previous one is kept as ``checkpoint.prev.npz``. The animal learned is stored beside
``config.toml`` (``animal.npz``, the Body's arrays). Resuming rebuilds the problem from those
two and restores the optimizer's state (nothing is replayed), then carries on to
the same budget: an interrupted run and an uninterrupted one with the same seed end with the
same history. The budget is an upper bound: a batch that would pass it is cut short; it is the
one setting a resumed run may change (no method's steps depend on it).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from zoetic.bodies import Body, load_animal
from zoetic.control import (
    Controller,
    frequency_domain,
    load_controller,
    save_controller,
    time_domain,
    wave_controller,
)
from zoetic.errors import RunDirError, ZoeticError
from zoetic.io import atomic_write_bytes, write_toml
from zoetic.learning.blas import one_blas_thread
from zoetic.learning.checkpoint import (
    CHECKPOINT,
    LOG_KEYS,
    PREVIOUS,
    Log,
    checkpoint_bytes,
    edited_keys,
    keep_previous,
    read_checkpoint,
    saved_config,
)
from zoetic.learning.checks import check_fits, check_learn_size, check_run, run_dir_parts
from zoetic.learning.config import LearnConfig
from zoetic.learning.evaluate import make_evaluator
from zoetic.learning.objective import Objective
from zoetic.learning.optimizers import Optimizer, make_optimizer
from zoetic.learning.stored_body import ANIMAL_FILE, body_digest, save_body
from zoetic.tasks import Task, load_task, parse_task

__all__ = ["LearnConfig", "Run", "Setup", "build"]

# The defaults and why they are what they are: docs/reproduction.md, "Why default learning was
# weak" and "Learning defaults, measured".
PERIODIC_NODES = 5  # the periodic controller: a constant and two harmonics per actuator
CMAES_POPSIZE = 32  # one population is one batch of the simulator
PERIODIC_AMPLITUDE = 1.0  # bound on the periodic controller's harmonic amplitudes
# terms that prefer neither side: a task made only of these is mirror-symmetric, and its gait
# is learned mirror-symmetric ("auto" coupling -> "wave")
SYMMETRIC_TERMS = frozenset(
    "distance_along_heading lateral_deviation depth_keeping roll_keeping final_pitch "
    "pitch_change speed_deviation mean_speed effort max_height roll_excess turn_excess".split()
)
# terms that prefer neither side when their target is 0 (keep the heading: no turn either way)
SYMMETRIC_AT_ZERO = frozenset({"heading_change", "body_heading_change"})


@dataclass
class Setup:
    """The pieces a run is built from."""

    config: LearnConfig
    task: Task
    objective: Objective
    optimizer: Optimizer
    template: Controller

    @property
    def body(self) -> Body:
        """The animal being learned."""
        return self.objective.body


def _template(config: LearnConfig, body: Body, task: Task) -> tuple[Controller, int]:
    """Return the controller family's template and its nodes per actuator."""
    periodic = config.controller == "periodic"
    m = config.nodes or (PERIODIC_NODES if periodic else task.nodes)
    if config.controller == "time":
        return time_domain(body, m, task.horizon, interp=config.interp), m
    if config.controller == "frequency":
        return frequency_domain(body, m, task.horizon), m
    if periodic:
        base = config.frequency or body.wave_frequency
        if not base > 0:
            raise ZoeticError(f"the periodic controller needs a positive frequency, got {base}")
        return frequency_domain(body, m, task.horizon, base=base), m
    raise ZoeticError(f"unknown controller {config.controller!r} (periodic, time or frequency)")


def build(
    config: LearnConfig,
    task: Task | None = None,
    body: Body | None = None,
    start: Controller | None = None,
) -> Setup:
    """Return the task, objective and a fresh optimizer for a configuration and an animal.

    ``body`` is the animal learned (default: ``config.animal`` loaded from the zoo or its
    file); ``task`` defaults to ``config.task`` loaded; ``start`` is the gait a run with
    ``start = "stored"`` starts from (its run directory's start.json)."""
    body = body if body is not None else load_animal(config.animal)
    task = task or load_task(config.task)
    check_fits(task, body, config.medium)
    template, m = _template(config, body, task)
    periodic = config.controller == "periodic"
    if m != task.nodes:
        task = parse_task({**task.to_dict(), "nodes": m}, task.source)
    fins = resolve_fins(config, task)
    coupling = resolve_coupling(config, task, body, fins)
    bound = PERIODIC_AMPLITUDE if periodic else None
    objective = Objective(
        task, body, template, config.medium, coupling=coupling, fins=fins, harmonic_bound=bound
    )
    lo, hi = objective.bounds()
    x0 = start_point(config, objective, start)
    options = {}
    if config.optimizer == "cmaes":
        options["popsize"] = config.popsize or CMAES_POPSIZE
    if config.optimizer == "anneal" and config.chains > 1:
        options["chains"] = config.chains
    options |= config.extra.get("optimizer", {})
    opt = make_optimizer(config.optimizer, x0, lo, hi, config.seed, config.budget, **options)
    if config.stop_generations is not None and config.stop_improvement is not None:
        opt.plateau = (config.stop_generations, config.stop_improvement)
    return Setup(config, task, objective, opt, template)


def start_point(
    config: LearnConfig, objective: Objective, start: Controller | None = None
) -> np.ndarray:
    """Return where the search starts (``LearnConfig.start``): a known gait on the
    controller's parameters, the animal's own travelling wave ("wave") or the run's stored
    ``start`` ("stored"), or a random point of the box from the seed (a frequency-domain
    controller: small amplitudes about a mid-level constant)."""
    if config.start == "wave":
        return objective.params_of(wave_controller(objective.body))
    if config.start == "stored":
        if start is None:
            raise ZoeticError(f'start = "stored" needs the gait to start from ({START_FILE})')
        return objective.params_of(start)
    lo, hi = objective.bounds()
    x0 = np.random.default_rng(config.seed).uniform(lo, hi)
    if config.controller != "time":
        x0 = np.clip(x0 * 0.5 + np.where(lo == 0.0, 0.25, 0.0), lo, hi)  # constants: lo 0
    return x0


def resolve_coupling(config: LearnConfig, task: Task, body, fins: str = "held") -> str:
    """Return the coupling "auto" stands for: "wave" (right = left, later by the wave's lag)
    when the task prefers neither side, the body has mirror pairs (learned fins count: the
    dolphin's only pair, whose fins set apart rolled it over while it pitched) and the
    controller is periodic; "none" otherwise."""
    if config.coupling != "auto":
        return config.coupling
    mirror = np.asarray(body.actuator_mirror)
    sides = zip(body.actuator_side, body.actuator_kind, strict=True)
    pairs = any(
        side == "right" and 0 <= mirror[k] != k and (kind != "fin" or fins == "free")
        for k, (side, kind) in enumerate(sides)
    )
    symmetric = all(
        t.kind in SYMMETRIC_TERMS or (t.kind in SYMMETRIC_AT_ZERO and t.target == 0.0)
        for t in task.terms
    )
    return "wave" if symmetric and pairs and config.controller != "time" else "none"


def resolve_fins(config: LearnConfig, task: Task) -> str:
    """Return the fins mode "auto" stands for: learned ("free") when the task turns the heading
    (the fish banks into a turn with its pectoral fins) or requires fins (a dolphin cannot bend
    sideways and turns or pitches on them), held level otherwise (an open-loop fin signal would
    pitch a straight swimmer away from its course)."""
    if config.fins != "auto":
        return config.fins
    turns = any(t.kind in SYMMETRIC_AT_ZERO for t in task.terms)
    needs = any("fins" in r.split("|") for r in task.requires)
    return "free" if turns or needs else "held"


START_FILE = "start.json"  # the gait a run with start = "stored" starts from


def _identity(setup: Setup) -> dict:
    """Return what a checkpoint must have been written with: the settings and the animal."""
    return setup.config.to_dict() | {"animal_sha256": body_digest(setup.body)}


class Run:
    """A run directory being learned into."""

    def __init__(self, out: Path, setup: Setup, log: Log | None = None):
        self.out = Path(out)
        self.setup = setup
        self.log = log or Log()
        self._before: tuple | None = None  # (log length, batches) while a step runs
        # (log length, batches, optimizer state) of the last state saved or started from: an
        # interrupted step is undone by restoring it and replaying the logged batches since
        self._anchor: tuple | None = None
        self._saved: int | None = None  # evaluations in the last checkpoint written
        self._cut = False  # the batch being evaluated is the budget's last, partial one
        self.t_start = time.perf_counter() - (self.log.wall[-1] if self.log.wall else 0.0)

    @classmethod
    def create(
        cls,
        out: Path,
        config: LearnConfig,
        body: Body | None = None,
        task: Task | None = None,
        start: Controller | None = None,
    ) -> Run:
        """Start a new run of ``config`` on ``body`` in ``out`` (refuses a directory that already
        holds one, and whatever ``checks.check_run`` refuses).

        ``body`` is the animal learned (default: ``config.animal`` loaded); it is stored in the
        run directory (``animal.npz``) and a resumed run learns it, never a reloaded one.
        ``start``: the gait a run with ``start = "stored"`` starts from, stored as start.json."""
        out = Path(out)
        if (out / CHECKPOINT).exists():
            raise RunDirError(
                f"{out} already holds a run; resume it with --resume {out} or choose another --out"
            )
        body = body if body is not None else load_animal(config.animal)
        task = task or load_task(config.task)
        check_run(config, body, task)
        setup = build(config, task, body, start)
        out.mkdir(parents=True, exist_ok=True)
        save_body(body, out / ANIMAL_FILE)
        if config.start == "stored":
            save_controller(start, out / START_FILE)
        write_toml(out / "config.toml", {"run": config.to_dict(), "task": setup.task.to_dict()})
        return cls(out, setup)

    @classmethod
    def resume(cls, out: Path, budget: int | None = None) -> Run:
        """Rebuild a run from its config.toml and stored animal, and restore its checkpoint;
        a ``budget`` other than the stored one replaces it (config.toml is rewritten)."""
        out = Path(out)
        config, task, body = run_dir_parts(out)
        new_budget = budget is not None and budget != config.budget
        if new_budget:
            config = replace(config, budget=int(budget))
            check_learn_size(config.to_dict(), task, f"{out}: --budget {budget}", body)
        start = None
        if config.start == "stored":
            start = load_controller(out / START_FILE, body)
        setup = build(config, task, body, start)
        run = cls._restore(out, setup)
        if new_budget:
            write_toml(out / "config.toml", {"run": config.to_dict(), "task": task.to_dict()})
        return run

    @classmethod
    def _restore(cls, out: Path, setup: Setup) -> Run:
        """Return the run of ``setup`` in ``out`` with its checkpoint (if any) restored,
        refusing a checkpoint written with other settings (the budget aside) or animal."""
        config = setup.config
        path = out / CHECKPOINT
        if not path.exists() and (out / PREVIOUS).exists():
            path = out / PREVIOUS  # killed between keeping the previous and writing the next
        if not path.exists():
            return cls(out, setup)
        log, state = read_checkpoint(path)
        saved = saved_config(path)
        now = _identity(setup)
        if saved is not None and "animal_sha256" not in saved:  # written before animals were
            now.pop("animal_sha256")
        changed = [k for k in edited_keys(saved, now) if k != "budget"] if saved else []
        if changed:
            raise RunDirError(
                f"{out}: config.toml or {ANIMAL_FILE} was edited since the checkpoint was written "
                f"({', '.join(changed)} changed); undo the edit, or start afresh with another --out"
            )
        try:
            setup.optimizer.load_state_dict(state)
        except (KeyError, ValueError, TypeError, ZoeticError) as exc:
            raise RunDirError(
                f"{out / CHECKPOINT}: the saved {config.optimizer} state does not fit this "
                f"configuration ({exc}); was config.toml edited?"
            ) from None
        return cls(out, setup, log)

    @property
    def evaluations(self) -> int:
        """The number of candidates evaluated so far (the log's length)."""
        return len(self.log.E)

    def best_controller(self) -> Controller:
        """Return the best controller found so far."""
        return self.setup.objective.controller(self.setup.optimizer.best_x)

    def checkpoint(self) -> None:
        """Write checkpoint.npz, history.csv and controller.json (each atomically)."""
        if self._before is not None:  # interrupted inside a step: save the state before it
            n, batches = self._before
            for key in LOG_KEYS[:-1]:
                del getattr(self.log, key)[n:]
            del self.log.batches[batches:]
            self._replay()
            self._before = None
        state = self.setup.optimizer.state_dict()
        self._anchor = (self.evaluations, len(self.log.batches), state)
        data = checkpoint_bytes(self.log, state, _identity(self.setup))
        keep_previous(self.out / CHECKPOINT, self.out / PREVIOUS)
        atomic_write_bytes(self.out / CHECKPOINT, data)
        self._saved = self.evaluations
        atomic_write_bytes(self.out / "history.csv", self.log.history_csv())
        if np.isfinite(self.setup.optimizer.best_f):
            save_controller(self.best_controller(), self.out / "controller.json")

    def step(self, evaluator) -> int:
        """Ask, evaluate and tell one batch; return how many evaluations it made."""
        X = self.ask()
        if X is None:
            return 0
        opt = self.setup.optimizer
        if opt.needs_gradient:
            ev, grad = evaluator.value_and_grad(self.setup.objective, X)
        else:
            ev, grad = evaluator(self.setup.objective, X), None
        return self.tell(X, ev, grad)

    def ask(self) -> np.ndarray | None:
        """Return the next batch to evaluate (cut to the budget's room), or None when there is
        nothing left; until ``tell``, an interruption checkpoints the state before it."""
        opt = self.setup.optimizer
        if self._anchor is None or opt.needs_gradient:  # a gradient is not logged to replay
            self._anchor = (self.evaluations, len(self.log.batches), opt.state_dict())
        self._before = (len(self.log.E), len(self.log.batches))
        X = opt.ask()
        room = self.setup.config.budget - self.evaluations
        if len(X) == 0 or room <= 0:
            self._before = None
            return None
        self._cut = len(X) > room
        return X[:room]

    def _replay(self) -> None:
        """Put the optimizer in the state after the logged batches: the anchor's state
        restored, then each batch logged since asked for again and told its logged E (the
        budget's last, partial batch recorded, as ``tell`` does). A method's steps depend only
        on its state and the scores it is told, as a resumed run's do, so this is the state
        the run had, bit for bit, without a copy of it taken before every step."""
        opt = self.setup.optimizer
        n, batches, state = self._anchor
        opt.load_state_dict(state)
        for size in self.log.batches[batches:]:
            X, E = np.asarray(self.log.X[n : n + size]), np.asarray(self.log.E[n : n + size])
            if size < len(opt.ask()):
                opt.record(X, E)
            else:
                opt.tell(X, E)
            n += size

    def tell(self, X: np.ndarray, ev, grad=None) -> int:
        """Give the optimizer the Evaluation of the batch ``ask`` returned; log it; return its
        size. The last, partial batch is counted and kept if best, not a step of the method."""
        opt = self.setup.optimizer
        if self._cut:
            opt.record(X, ev.E)
        else:
            opt.tell(X, ev.E, grad)
        self.log.add(X, ev, time.perf_counter() - self.t_start)
        self._before = None
        return len(X)

    @property
    def finished(self) -> bool:
        """True when the run has spent its budget or its optimizer has stopped."""
        return self.evaluations >= self.setup.config.budget or self.setup.optimizer.done()

    def learn(self, progress: Callable[[Run], None] | None = None, every_s: float = 2.0):
        """Run to the budget, checkpointing every ``every_s`` seconds and on interruption;
        BLAS held to one thread throughout (``one_blas_thread``)."""
        config = self.setup.config
        evaluator = make_evaluator(config.evaluator)
        last = time.perf_counter()
        try:
            with one_blas_thread():
                while not self.finished:
                    if self.step(evaluator) == 0:
                        break
                    if progress:
                        progress(self)
                    if time.perf_counter() - last > every_s:
                        self.checkpoint()
                        last = time.perf_counter()
        finally:
            evaluator.close()
            self.settle()
        return self

    def settle(self) -> None:
        """End learning for now: checkpoint what is not saved yet (the state before a step
        interrupted midway) and release the optimizer."""
        if self.unsaved:
            self.checkpoint()
        self.setup.optimizer.close()

    @property
    def unsaved(self) -> bool:
        """True when the run holds evaluations (or a step midway) its checkpoint has not."""
        return self._before is not None or self._saved != self.evaluations
