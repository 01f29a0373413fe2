"""Sensor-actuator networks (van de Panne & Fiume 93): planar creatures, their MuJoCo world.

Creatures (``creature``; files in ``creature_file``): :class:`Creature` with :class:`Link`,
:class:`Joint`, :class:`Sensor`, :class:`Actuator`; :func:`load_creature` (zoo name or path),
:func:`list_creatures`, :func:`creature_to_toml`, :func:`save_creature`; errors are
:class:`CreatureError`. The format is documented in ``docs/creatures.md``.

Simulation (``world``): ``World(creature, terrain="flat" | "rough", seed=0, follow=None)``
compiles the MuJoCo model once; ``World.run(policy, seconds=None, record_every=0)`` returns a
:class:`Rollout`; :func:`evaluate` is the one-call metric. A :class:`Policy` has ``reset()`` and
``step(sensors (S,) bool, dt) -> (A,) commands in [-2, 2]``.

Pictures are drawn by ``zoetic.viz.san`` from what this package computes (it draws nothing).

Synthesis, imported on demand: ``search`` (phase 1, random SANs), ``tune`` (phase 2, Fig. 8
parameters), ``gaits`` (kept gaits sorted into distinct modes), ``evolve`` (body and network
together, section 6.3).
"""

from zoetic.san.creature import (
    TUNING_KEYS,
    Actuator,
    Creature,
    CreatureError,
    Joint,
    Link,
    Sensor,
)
from zoetic.san.creature_file import (
    creature_to_toml,
    list_creatures,
    load_creature,
    save_creature,
)
from zoetic.san.world import Policy, Rollout, World, evaluate

__all__ = [
    "TUNING_KEYS",
    "Actuator",
    "Creature",
    "CreatureError",
    "Joint",
    "Link",
    "Policy",
    "Rollout",
    "Sensor",
    "World",
    "creature_to_toml",
    "evaluate",
    "list_creatures",
    "load_creature",
    "save_creature",
]
