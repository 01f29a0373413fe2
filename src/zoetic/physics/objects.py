"""Passive things in a world: a rigid ball, fixed boxes and cylinders, food particles.

Each is a small frozen description; ``pack_*`` turns a list of them into the flat arrays the
contact kernels read. Positions are in m with y up, like the animals'.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from zoetic.errors import SimulationError

WATER_DENSITY = 1000.0  # kg/m^3: sets a ball's buoyancy when it does not give its own
AXES = {"x": 0, "y": 1, "z": 2}


def _vec(v, what: str) -> tuple[float, float, float]:
    a = np.asarray(v, dtype=float).reshape(-1)
    if a.shape != (3,) or not np.isfinite(a).all():
        raise SimulationError(f"{what} must be three finite numbers, got {v!r}")
    return (float(a[0]), float(a[1]), float(a[2]))


def _positive(x: float, what: str) -> float:
    if not (np.isfinite(x) and x > 0):
        raise SimulationError(f"{what} must be positive, got {x!r}")
    return float(x)


@dataclass(frozen=True)
class Ball:
    """A rigid sphere (no spin): gravity, buoyancy of its submerged part, water drag, contacts.

    buoyancy: buoyant force / weight when fully under water; None takes it from the density
    of water and the ball's volume and mass (a 0.15 m, 0.5 kg ball floats).
    """

    radius: float = 0.15
    mass: float = 0.5
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    buoyancy: float | None = None
    drag_coefficient: float = 0.47
    name: str = "ball"

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _positive(self.radius, "Ball radius"))
        object.__setattr__(self, "mass", _positive(self.mass, "Ball mass"))
        object.__setattr__(self, "position", _vec(self.position, "Ball position"))
        object.__setattr__(self, "velocity", _vec(self.velocity, "Ball velocity"))

    @property
    def buoyancy_ratio(self) -> float:
        """Return buoyant force over weight when fully submerged."""
        if self.buoyancy is not None:
            return float(self.buoyancy)
        volume = 4.0 / 3.0 * np.pi * self.radius**3
        return WATER_DENSITY * volume / self.mass


@dataclass(frozen=True)
class Box:
    """A fixed axis-aligned box (a rock, a wall, a hurdle's board): centre and half sizes."""

    center: tuple[float, float, float]
    half_size: tuple[float, float, float]
    name: str = "box"

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _vec(self.center, "Box center"))
        hs = _vec(self.half_size, "Box half_size")
        for h in hs:
            _positive(h, "Box half_size")
        object.__setattr__(self, "half_size", hs)


@dataclass(frozen=True)
class Cylinder:
    """A fixed cylinder along a world axis (a post, seaweed, a hurdle's bar): centre, radius,
    length along ``axis`` ("y" stands upright)."""

    center: tuple[float, float, float]
    radius: float
    length: float
    axis: str = "y"
    name: str = "cylinder"

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _vec(self.center, "Cylinder center"))
        object.__setattr__(self, "radius", _positive(self.radius, "Cylinder radius"))
        object.__setattr__(self, "length", _positive(self.length, "Cylinder length"))
        if self.axis not in AXES:
            raise SimulationError(f"Cylinder axis must be x, y or z, got {self.axis!r}")


@dataclass(frozen=True)
class Food:
    """A food particle: a point drifting with the world's current, eaten when a head comes
    within ``radius``."""

    position: tuple[float, float, float]
    radius: float = 0.1
    name: str = "food"

    def __post_init__(self) -> None:
        object.__setattr__(self, "position", _vec(self.position, "Food position"))
        object.__setattr__(self, "radius", _positive(self.radius, "Food radius"))


Solid = Ball | Box | Cylinder
Thing = Ball | Box | Cylinder | Food

BOX, CYLINDER = 0, 1


def pack_statics(statics: list[Box | Cylinder]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return (kind (S,) int, centre (S, 3), size (S, 3)) of the fixed shapes.

    size holds a box's half sizes, or a cylinder's (radius, half length, axis index).
    """
    kind = np.zeros(len(statics), dtype=np.int64)
    center = np.zeros((len(statics), 3))
    size = np.zeros((len(statics), 3))
    for k, s in enumerate(statics):
        center[k] = s.center
        if isinstance(s, Box):
            kind[k] = BOX
            size[k] = s.half_size
        else:
            kind[k] = CYLINDER
            size[k] = (s.radius, 0.5 * s.length, AXES[s.axis])
    return kind, center, size


def pack_balls(balls: list[Ball]) -> np.ndarray:
    """Return (K, 4) rows (radius, mass, buoyancy ratio, drag coefficient) of the balls."""
    return np.array(
        [(b.radius, b.mass, b.buoyancy_ratio, b.drag_coefficient) for b in balls], dtype=float
    ).reshape(-1, 4)


class Solids:
    """A world's balls and fixed shapes as the contact kernels read them, for B lanes.

    pos, vel: the balls' state (K, 3, B) in m and m/s (stepped in place); force: (K, 3, B) the
    force the animals' contacts put on each ball over a step; par: ``pack_balls``; kind,
    center, size: ``pack_statics``; ball_obj, static_obj: each one's index among the world's
    objects (what the contact records are indexed by); columns: the objects a node can touch
    (the balls and fixed shapes, food never pushes) in the world's order, and ball_col,
    static_col: each ball's and fixed shape's place among them (the columns of the contact
    kernels' impulse buffers, which leave the food out).
    """

    def __init__(self, objects: list[Thing], batch: int) -> None:
        self.ball_obj = np.array(
            [i for i, o in enumerate(objects) if isinstance(o, Ball)], dtype=np.int64
        )
        static = [i for i, o in enumerate(objects) if isinstance(o, Box | Cylinder)]
        self.static_obj = np.array(static, dtype=np.int64)
        self.balls = [objects[i] for i in self.ball_obj]
        self.statics = [objects[i] for i in self.static_obj]
        self.pos = np.zeros((len(self.balls), 3, batch))
        self.vel = np.zeros_like(self.pos)
        self.force = np.zeros_like(self.pos)
        self.par = pack_balls(self.balls)
        self.kind, self.center, self.size = pack_statics(self.statics)
        self.columns = np.sort(np.concatenate([self.ball_obj, self.static_obj]))
        self.ball_col = np.searchsorted(self.columns, self.ball_obj).astype(np.int64)
        self.static_col = np.searchsorted(self.columns, self.static_obj).astype(np.int64)

    @property
    def any(self) -> bool:
        """Return True if there is a ball or a fixed shape to touch."""
        return len(self.balls) + len(self.statics) > 0
