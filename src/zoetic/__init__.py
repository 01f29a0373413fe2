"""zoetic: physics-based artificial animals that learn to move by themselves.

The Python API in a few names (each imported on first use, so ``import zoetic`` stays light:
no JAX, no matplotlib, no Numba until a simulation runs)::

    shark = zoetic.load_animal("shark")
    traj = zoetic.simulate(shark, "wave", seconds=4)
    result = zoetic.learn(shark, "swim-straight", optimizer="cmaes", budget=2000, seed=0)
    world = zoetic.World([shark, zoetic.Ball(position=(1, 0, 0))], medium="water")
"""

from __future__ import annotations

import sys
import types
from importlib import import_module
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

_EXPORTS: dict[str, str] = {
    "load_animal": "zoetic.bodies",
    "list_animals": "zoetic.bodies",
    "Body": "zoetic.bodies",
    "load_task": "zoetic.tasks",
    "list_tasks": "zoetic.tasks",
    "simulate": "zoetic.api",
    "LearnResult": "zoetic.api",
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
    from zoetic.api import LearnResult, simulate
    from zoetic.bodies import Body, list_animals, load_animal
    from zoetic.control import load_controller, wave_controller
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


class _Learn:
    """``zoetic.learn(...)`` learns (see ``zoetic.api.learn``); ``zoetic.learn.<module>``
    still reaches the ``zoetic.learn`` package, whose name this callable shares."""

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return import_module("zoetic.api").learn(*args, **kwargs)

    def __getattr__(self, name: str) -> Any:
        return getattr(import_module("zoetic.learn"), name)

    @property
    def __signature__(self):  # so that help() and IDEs show api.learn's typed signature
        import inspect

        return inspect.signature(import_module("zoetic.api").learn)

    @property
    def __doc__(self) -> str | None:  # type: ignore[override]
        return import_module("zoetic.api").learn.__doc__


learn = _Learn()


class _Package(types.ModuleType):
    """The zoetic module: importing the ``zoetic.learn`` package must not replace the
    ``learn`` callable (Python binds a loaded submodule as an attribute of its parent)."""

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "learn" and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
