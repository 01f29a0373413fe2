"""The checks a learning run passes before anything is built or written, in one place for the
Python API (``zoetic.learn``), ``Run.create`` / ``Run.resume`` and the command line: the same
refusals with the same ZoeticError messages wherever a run starts."""

from __future__ import annotations

from dataclasses import fields
from pathlib import Path

from zoetic import io as rd
from zoetic.bodies import Body, load_animal
from zoetic.errors import BodyError, RunDirError
from zoetic.learning.config import LearnConfig
from zoetic.learning.optimizers import OPTIMIZERS
from zoetic.learning.stored_body import ANIMAL_FILE, load_body
from zoetic.physics.simulate import check_dt
from zoetic.tasks import Task, check_fits, load_task, parse_task

MAX_BUDGET = 10_000_000  # evaluations of one learning run
CHOICES = {  # the controller kinds are left to learning.run.build, which names its own
    "interp": ("linear", "bspline"),
    "evaluator": ("batch", "process", "ray"),
    "coupling": ("auto", "none", "wave", "antiphase"),
    "fins": ("auto", "held", "free"),
    "medium": ("ground", "water", "sea", "vacuum"),
    "optimizer": tuple(OPTIMIZERS),
    "start": ("random", "wave", "stored"),
}
BOUNDS = {
    "budget": (1, MAX_BUDGET),
    "nodes": (2, 100_000),
    "popsize": (2, 100_000),
    "chains": (1, 10_000),
    "seed": (0, 2**63 - 1),
    "stop_generations": (1, 100_000),
    "stop_improvement": (0.0, 1.0),
}
# settings that mean something only together
PAIRED = (("stop_generations", "stop_improvement"),)


def check_learn_config(d: dict, where: str) -> dict:
    """Check a learning run's settings (config.toml's [run], or the caller's) strictly.

    The keys are LearnConfig's fields (so new fields are known at once); each value's type
    follows the field's annotation, choices and bounds are checked; returns ``d``.
    """
    E = RunDirError
    if not isinstance(d, dict):
        raise E(f"{where}: must be a table, got {rd.abbrev(d)}")
    kinds = {f.name: str(f.type) for f in fields(LearnConfig)}
    rd.check_keys(d, kinds, where, E)
    for key, value in d.items():
        at, kind = f"{where}: {key}", kinds[key]
        if value is None and "None" in kind:
            continue
        if kind.startswith("int"):
            lo, hi = BOUNDS.get(key, (None, None))
            rd.integer(value, at, E, lo, hi)
        elif kind.startswith("float"):
            rd.number(value, at, E, *BOUNDS.get(key, (None, None)))
        elif kind.startswith("str"):
            rd.string(value, at, E, CHOICES.get(key))
        elif kind.startswith("bool") and not isinstance(value, bool):
            raise E(f"{at} must be true or false, got {rd.abbrev(value)}")
        elif kind.startswith("dict") and not isinstance(value, dict):
            raise E(f"{at} must be a table, got {rd.abbrev(value)}")
    for a, b in PAIRED:
        if (d.get(a) is None) != (d.get(b) is None):
            given, missing = (a, b) if d.get(a) is not None else (b, a)
            raise E(f"{where}: {given} needs {missing} too (the plateau stop uses both)")
    return d


def check_learnable(animal: Body | str | Path) -> Body:
    """Return the animal's body (loaded when named), refusing one with nothing to learn (no
    actuators) or whose own time step is beyond what its springs and masses allow."""
    body = animal if isinstance(animal, Body) else load_animal(animal)
    label = body.source if isinstance(animal, Body) else str(animal)
    check_dt(body, body.dt, None, body.source)  # the body's own step, before anything is written
    if body.n_actuators == 0:
        raise BodyError(
            f"{label}: the {body.name} has no actuators, so there is nothing to learn; give "
            "it [[actuators]] and muscles (springs with an 'actuator')"
        )
    return body


def check_learn_size(
    run: dict, task: Task | None = None, where: str = "options", body: Body | None = None
) -> None:
    """Refuse a learning run that would take more than the memory limit or too many steps.

    Counted before anything is built: the log of every evaluation (budget x parameters) and
    one batch of simulations (candidates x steps x actuators); the task's horizon at the
    animal's dt is bounded in steps. ``task`` and ``body`` default to the named ones.
    """
    body = body if body is not None else load_animal(run.get("animal", "shark"))
    task = task or load_task(run.get("task", "swim-straight"))
    horizon = float(getattr(task, "horizon", 0.0) or 0.0)
    steps = rd.check_steps(horizon, body.dt, f"{where}: the task's horizon", RunDirError)
    nodes = int(run.get("nodes") or getattr(task, "nodes", 15) or 15)
    params = body.n_actuators * nodes
    budget = int(run.get("budget", 3500))
    batch = int(run.get("popsize") or 0) or max(64, int(run.get("chains") or 1))
    rd.check_memory(
        budget * (params + 6) * 8 * 2,
        f"{where}: a log of {budget:,} evaluations of {params:,} parameters",
        RunDirError,
        "use a smaller --budget or fewer --nodes",
    )
    rd.check_memory(
        batch * steps * (body.n_actuators * 12 + 8 * nodes),
        f"{where}: simulating {batch} candidates for {horizon:g} s",
        RunDirError,
        "use a smaller --popsize, fewer --nodes or a shorter task",
    )


def check_run(config: LearnConfig, body: Body, task: Task, where: str = "options") -> None:
    """Refuse a new run whose settings, animal, size or task-for-animal fit do not hold."""
    check_learn_config(config.to_dict(), where)
    check_learnable(body)
    check_learn_size(config.to_dict(), task, where, body)
    check_fits(task, body, config.medium)


def run_dir_parts(out: Path) -> tuple[LearnConfig, Task, Body]:
    """Return a run directory's settings, task and animal, each checked; RunDirError if the
    directory, its config.toml or its stored animal is missing, unreadable or malformed.

    The animal is the one stored beside config.toml (``animal.npz``); a run written before
    animals were stored names a zoo animal or a file, which is loaded."""
    out = Path(out)
    if not out.is_dir():
        raise RunDirError(f"{out}: no such directory, so not a zoetic run directory")
    cfg = out / "config.toml"
    if not cfg.is_file():
        raise RunDirError(f"{out}: no config.toml, so not a zoetic run directory")
    doc = rd.read_toml(cfg, what="run configuration", error=RunDirError)
    if "run" not in doc or "task" not in doc:
        raise RunDirError(f"{cfg}: needs a [run] and a [task] table; was it edited?")
    check_learn_config(doc["run"], f"{cfg}: [run]")
    if not isinstance(doc["task"], dict):
        raise RunDirError(f"{cfg}: [task] must be a table")
    task = parse_task(doc["task"], str(cfg))
    stored = out / ANIMAL_FILE
    body = load_body(stored) if stored.exists() else load_animal(doc["run"].get("animal", "shark"))
    check_learn_size(doc["run"], task, f"{cfg}: [run]", body)
    try:
        config = LearnConfig(**doc["run"])
    except TypeError as exc:
        raise RunDirError(f"{cfg}: malformed ({exc})") from None
    return config, task, body


def check_run_dir(out: Path) -> None:
    """Refuse a run directory whose config.toml or stored animal is missing or malformed."""
    run_dir_parts(out)
