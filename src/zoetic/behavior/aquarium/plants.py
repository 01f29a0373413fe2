"""The tank's seaweed as dynamic plants (``physics.plants``): where the strands grow, and the
observer that steps them with the world.

Each seaweed clump (a ``Cylinder`` named "seaweed" among the tank's obstacles) becomes
``BLADES`` strands anchored on the seabed within ``FRINGE`` m of the clump's radius, 55 to
75 % of the walls' height long, so that they cross the fishes' layer; the water surges slowly
about the tank's current so they sway. With dynamic plants the clump is no solid for the
fishes' bodies (they part the strands) but its cylinder stays the obstacle their minds avoid
and their eyes see: the dense core, while the outer blades reach into the water the fishes
swim through (they steer clear of obstacles by ``routines.CLEARANCE`` = 0.5 m).
"""

from __future__ import annotations

import numpy as np

from zoetic.bodies import Body
from zoetic.control.loop import Observer
from zoetic.physics.media import Medium
from zoetic.physics.objects import Box, Cylinder
from zoetic.physics.plants import Plants, Skins, Weed
from zoetic.physics.world import World

PLANTS = ("dynamic", "static")  # seaweed as swaying strands, or as fixed cylinders
BLADES = 7  # strands a clump
SURGE = (0.12, 0.0, 0.05)  # m/s: the slow surge's amplitude about the current
SURGE_PERIOD = 7.0  # s
FRINGE = 0.5  # m: how far beyond the clump's cylinder blades grow


def is_weed(shape: Box | Cylinder) -> bool:
    """Return True for a seaweed clump among the tank's fixed shapes."""
    return isinstance(shape, Cylinder) and shape.name == "seaweed"


def tank_plants(
    statics: list[Box | Cylinder], seed: int, medium: Medium, current, dt: float
) -> Plants | None:
    """Return the strands of the seaweed clumps among ``statics`` (None if there are none),
    laid out from ``seed`` (their own generator: the rest of the tank's layout is the same
    whether the plants are dynamic or not)."""
    clumps = [s for s in statics if is_weed(s)]
    if not clumps:
        return None
    rng = np.random.default_rng([int(seed), 271])
    anchors, lengths = [], []
    for c in clumps:
        outer = c.radius + FRINGE
        radius = outer * np.sqrt(rng.uniform(0.0, 1.0, BLADES))  # even over the disc
        angle = rng.uniform(-np.pi, np.pi, BLADES)
        base = np.array(c.center) - [0.0, 0.5 * c.length, 0.0]
        ring = np.stack([radius * np.cos(angle), np.zeros(BLADES), radius * np.sin(angle)], 1)
        anchors.append(base + ring)
        lengths.append(c.length * rng.uniform(0.55, 0.75, BLADES))
    return Plants(
        np.concatenate(anchors),
        np.concatenate(lengths),
        Weed(),
        medium,
        current,
        dt,
        surge=SURGE,
        surge_period=SURGE_PERIOD,
    )


class PlantSteps(Observer):
    """Steps the strands with the world: after each slice of steps, the same number of strand
    steps while the fishes move from where they were to where they are; keeps the strands'
    nodes at every record (``frames``)."""

    def __init__(self, plants: Plants, world: World, bodies: list[Body]) -> None:
        self.plants = plants
        self.skins = Skins.of(bodies, world.offsets)
        self.at = world.step_count
        self.fish = world.node_positions(0).astype(float)
        self.frames: list[np.ndarray] = []

    def slice(self, world: World, contacts) -> None:
        """Step the strands over the slice just stepped."""
        now = world.node_positions(0).astype(float)
        self.plants.advance(world.step_count - self.at, self.skins, self.fish, now)
        self.at, self.fish = world.step_count, now

    def record(self, world: World) -> None:
        """Keep the strands' nodes now."""
        self.frames.append(self.plants.nodes)

    def positions(self) -> np.ndarray:
        """Return the strands' nodes at every record (R, S, M + 1, 3), m."""
        return np.stack(self.frames)
