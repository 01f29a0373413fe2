"""zoetic: physics-based artificial animals that learn to move by themselves.

The Python API in a few names (each imported on first use, so ``import zoetic`` stays light:
no JAX, no matplotlib, no Numba until a simulation runs)::

    shark = zoetic.load_animal("shark")
    traj = zoetic.simulate(shark, "wave", seconds=4)
    result = zoetic.learn(shark, "swim-straight", optimizer="cmaes", budget=2000, seed=0)
    world = zoetic.World([shark, zoetic.Ball(position=(1, 0, 0))], medium="water")
    run = zoetic.aquarium(fishes=6, predators=1, seconds=20, seed=0)  # run.summary, run.life
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import import_module
from pathlib import Path
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

_EXPORTS: dict[str, str] = {
    "load_animal": "zoetic.bodies",
    "list_animals": "zoetic.bodies",
    "Body": "zoetic.bodies",
    "load_task": "zoetic.tasks",
    "list_tasks": "zoetic.tasks",
    "World": "zoetic.physics.world",
    "WorldState": "zoetic.physics.world",
    "Animal": "zoetic.physics.world",
    "Contacts": "zoetic.physics.world",
    "Ball": "zoetic.physics.objects",
    "Box": "zoetic.physics.objects",
    "Cylinder": "zoetic.physics.objects",
    "Food": "zoetic.physics.objects",
    "Trajectory": "zoetic.physics.simulate",
    "Policy": "zoetic.control.policy",
    "OpenLoopPolicy": "zoetic.control.policy",
    "rollout": "zoetic.control.rollout",
    "observe": "zoetic.control.sensors",
    "load_controller": "zoetic.control",
    "wave_controller": "zoetic.control",
    "ZoeticError": "zoetic.errors",
    "aquarium": "zoetic.behavior.aquarium.tank",
}

__all__ = [
    "Animal",
    "Ball",
    "Body",
    "Box",
    "Contacts",
    "Cylinder",
    "Food",
    "LearnResult",
    "OpenLoopPolicy",
    "Policy",
    "Trajectory",
    "World",
    "WorldState",
    "ZoeticError",
    "aquarium",
    "learn",
    "list_animals",
    "list_tasks",
    "load_animal",
    "load_controller",
    "load_task",
    "observe",
    "rollout",
    "simulate",
    "wave_controller",
]

if TYPE_CHECKING:  # for type checkers and IDEs; at run time the names load lazily
    import numpy as np

    from zoetic.behavior.aquarium.tank import aquarium
    from zoetic.bodies import Body, list_animals, load_animal
    from zoetic.control import Controller, load_controller, wave_controller
    from zoetic.control.policy import OpenLoopPolicy, Policy
    from zoetic.control.rollout import rollout
    from zoetic.control.sensors import observe
    from zoetic.errors import ZoeticError
    from zoetic.physics.objects import Ball, Box, Cylinder, Food
    from zoetic.physics.simulate import Trajectory
    from zoetic.physics.world import Animal, Contacts, World, WorldState
    from zoetic.tasks import list_tasks, load_task


def __getattr__(name: str) -> Any:
    """Import a public name on first use."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'zoetic' has no attribute {name!r}")
    value = getattr(import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_EXPORTS])


# ---- the API's own calls (imports inside, so that ``import zoetic`` stays light) ----------


def _body(animal: Body | str | Path) -> Body:
    from zoetic.bodies import Body, load_animal

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
    from zoetic.control import controller_from_spec
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
    """Learn a controller for an animal and a task and return a LearnResult.

    ``animal`` is a Body (learned exactly as given, changes included) or a zoo name or animal
    file to load. ``out`` keeps the run directory, with the animal stored in it (resumable with
    ``zoetic learn --resume``); else the run lives in a temporary directory. The same checks as
    ``zoetic learn`` refuse a run (ZoeticError) before anything is written.

    options: further LearnConfig fields (nodes, popsize, chains, evaluator, coupling, medium).
    """
    import tempfile

    import numpy as np

    from zoetic.bodies import Body
    from zoetic.learning.run import LearnConfig, Run

    body = _body(animal)
    label = body.name if isinstance(animal, Body) else str(animal)
    config = LearnConfig(
        animal=label,
        task=str(task),
        optimizer=optimizer,
        budget=budget,
        seed=seed,
        controller=controller,
        **options,
    )

    def run_in(directory: Path) -> LearnResult:
        run = Run.create(directory, config, body).learn()
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
