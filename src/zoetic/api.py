"""The few calls a Python user needs: load, simulate, learn (re-exported by ``import zoetic``)."""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from zoetic.bodies import Body, load_animal
from zoetic.control import Controller, controller_from_spec
from zoetic.physics.simulate import Trajectory


def _body(animal: Body | str | Path) -> Body:
    return animal if isinstance(animal, Body) else load_animal(animal)


def simulate(
    animal: Body | str | Path,
    controller: Controller | str | np.ndarray = "wave",
    seconds: float = 4.0,
    medium: str | None = None,
    dt: float | None = None,
) -> Trajectory:
    """Return the Trajectory of an animal under a controller (object, 'wave', 'rest', a
    controller file, or a policy) for ``seconds``, recorded at about 100 Hz."""
    from zoetic.control.rollout import rollout
    from zoetic.physics.world import World
    from zoetic.runs import record_stride

    body = _body(animal)
    if isinstance(controller, str | Path):
        controller = controller_from_spec(str(controller), body)
    world = World([body], medium=medium, dt=dt)
    stride = record_stride(world.dt)
    return rollout(world, controller, seconds, 1 / 30, record_every=stride).trajectory(0)


@dataclass(frozen=True)
class LearnResult:
    """A finished learning run: the best controller, its energy E, and E of every evaluation
    in order (``history``, (n,)); ``run_dir`` when one was written."""

    controller: Controller
    best_E: float
    history: np.ndarray
    run_dir: Path | None = None


def learn(
    animal: Body | str | Path,
    task: str | Path = "swim-straight",
    optimizer: str = "cmaes",
    budget: int = 2000,
    seed: int = 0,
    controller: str = "time",
    out: str | Path | None = None,
    **options,
) -> LearnResult:
    """Learn a controller for an animal and a task and return a LearnResult; ``out`` keeps
    the run directory (resumable with ``zoetic learn --resume``), else it is temporary.

    options: further LearnConfig fields (nodes, popsize, chains, evaluator, coupling, medium).
    """
    from zoetic.learn.run import LearnConfig, Run

    name = animal.source if isinstance(animal, Body) and Path(animal.source).exists() else animal
    if isinstance(name, Body):
        name = name.name
    config = LearnConfig(
        animal=str(name), task=str(task), optimizer=optimizer, budget=budget, seed=seed,
        controller=controller, **options,
    )  # fmt: skip

    def run_in(directory: Path) -> LearnResult:
        run = Run.create(directory, config).learn()
        return LearnResult(
            controller=run.best_controller(),
            best_E=float(run.setup.optimizer.best_f),
            history=np.array(run.log.E, dtype=float),
            run_dir=Path(out) if out is not None else None,
        )

    if out is not None:
        return run_in(Path(out))
    with tempfile.TemporaryDirectory(prefix="zoetic-learn-") as tmp:
        return run_in(Path(tmp))
