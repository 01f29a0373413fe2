"""Planar rigid-link creatures for sensor-actuator networks (van de Panne & Fiume 93).

A creature is data: rigid links joined by hinge, slide or fixed joints into a tree whose root
link moves freely in its plane (slide x, slide z, hinge about y), binary sensors and PD
actuators. It is read from a TOML file (``src/zoetic/san/zoo/*.toml`` for the ten creatures of
Table 1; the format is documented in ``docs/creatures.md``) and validated; every error is a
:class:`CreatureError` whose message names the file, the entry and the problem.

All values held by the dataclasses are SI: metres, kilograms, radians, N*m/rad (angular ks),
N*m*s/rad (angular kd), N/m and N*s/m (linear). A file may give angles in degrees under a key
ending in ``_deg`` (``lo_deg``, ``angle_deg``, ``ks_deg`` = N*m per degree as in the paper, ...);
:func:`creature_to_toml` always writes SI keys, so ``load_creature(save_creature(c)) == c``.

Public interface::

    Link, Joint, Sensor, Actuator, Creature        frozen dataclasses
    Creature.n_sensors, .n_actuators, .n_links
    Creature.with_tuning(actuator_lo=None, actuator_hi=None, ks=None, kd=None,
                         sensor_lo=None, sensor_hi=None) -> Creature
    Creature.tuning() -> dict[str, np.ndarray]     the same six arrays (A,) / (S,)

Reading and writing creature files is in :mod:`zoetic.san.creature_file`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from zoetic.errors import ZoeticError
from zoetic.io import abbrev

__all__ = [
    "Actuator",
    "Creature",
    "CreatureError",
    "Joint",
    "Link",
    "Sensor",
    "TUNING_KEYS",
    "ZOO_DIR",
]

ZOO_DIR = Path(__file__).parent / "zoo"
TUNING_KEYS = ("actuator_lo", "actuator_hi", "ks", "kd", "sensor_lo", "sensor_hi")
SHAPES = ("capsule", "box", "sphere")
JOINT_KINDS = ("hinge", "slide", "fixed")
SENSOR_KINDS = ("touch", "angle", "eye", "length")
ACTUATOR_KINDS = ("angular", "linear")
METRICS = ("distance", "hop", "follow")
MEDIA = ("ground", "water")
PLANES = ("vertical", "horizontal")
_DEG = math.pi / 180.0


class CreatureError(ZoeticError):
    """A creature file is malformed or physically invalid (the message names file and entry)."""


@dataclass(frozen=True)
class Link:
    """A rigid link; its shape spans its own frame from (start, 0) to (start + length, 0).

    ``radius`` is the capsule/sphere radius or the box half-thickness; ``depth`` the extent out
    of the plane (m, used for water areas; 0 means 2 * radius); ``inertia`` the moment about
    the out-of-plane axis through the shape centre (kg m^2; None: from the shape and mass).
    """

    name: str
    shape: str
    length: float
    radius: float
    mass: float
    inertia: float | None = None
    depth: float = 0.0
    start: float = 0.0

    @property
    def centre(self) -> float:
        """Local x of the shape centre (m)."""
        return self.start + self.length / 2

    @property
    def out_of_plane(self) -> float:
        """Extent of the link out of the plane (m)."""
        return self.depth if self.depth > 0 else 2.0 * self.radius


@dataclass(frozen=True)
class Joint:
    """A joint placing ``child`` in ``parent``'s frame.

    The child's frame sits at ``anchor`` (x, z in the parent frame), rotated by ``angle`` (rad)
    relative to the parent, and for a slide joint moved ``offset`` (m) further along its own x
    axis. Coordinate q (0 at that rest pose): hinge angle (rad), slide displacement (m); a slide
    joint's length is ``offset + q``. ``range`` is an optional hard limit on q; ``stiffness``
    and ``damping`` a passive spring (towards q = 0) and damper.
    """

    name: str
    kind: str
    parent: str
    child: str
    anchor: tuple[float, float] = (0.0, 0.0)
    angle: float = 0.0
    offset: float = 0.0
    range: tuple[float, float] | None = None
    stiffness: float = 0.0
    damping: float = 0.0


@dataclass(frozen=True)
class Sensor:
    """A binary sensor, on while its reading lies in [lo, hi].

    touch: ``target`` link; reading = clearance (m) above the ground of the link's probe point
      at ``at`` (local x, m; None: the whole link's lowest point). Default band [-1, 0.002].
    angle: ``target`` hinge joint; reading = joint angle (rad, wrapped to [-pi, pi]).
    eye: ``target`` link; reading = direction (rad, wrapped) from the eye at local (``at``, 0)
      to the follow point, relative to the link's x axis: [lo, hi] is the cone of view.
    length: ``target`` slide joint or linear actuator; reading = its length (m).
    """

    name: str
    kind: str
    target: str
    lo: float
    hi: float
    at: float | None = None


@dataclass(frozen=True)
class Actuator:
    """A PD actuator on ``joint``: T = ks (target - q) - kd dq/dt, target in [lo, hi].

    angular: hinge joint, lo/hi in rad, ks in N*m/rad, kd in N*m*s/rad.
    linear: slide joint, lo/hi lengths in m (``offset + q``), ks in N/m, kd in N*s/m.
    """

    name: str
    kind: str
    joint: str
    lo: float
    hi: float
    ks: float
    kd: float


@dataclass(frozen=True)
class Creature:
    """A planar creature: links, joints, sensors, actuators and how it is evaluated.

    ``plane``: "vertical" (x forward, z up, gravity, ground contact) or "horizontal" (top
    view: x forward, z to the left, no gravity; crawler and fish). ``medium``: "ground" or
    "water". ``metric``: "distance", "hop" or "follow"; ``seconds`` the evaluation time.
    ``fall_links`` fall when they touch the ground; ``fall_tilt`` (rad) when the root link
    turns that far from its start angle. Friction: ``friction`` (ground contact, vertical
    plane); ``crawl_friction`` (forward, backward, lateral) coefficients of the horizontal
    anisotropic friction; ``water_k`` (N*s/m^3) the water drag per area. ``paper_speed`` is
    Table 1's speed (cm/s); ``useful_speed`` (cm/s) the absolute bar from which a gait that
    does not fall counts as useful.
    """

    name: str
    links: tuple[Link, ...]
    joints: tuple[Joint, ...]
    sensors: tuple[Sensor, ...]
    actuators: tuple[Actuator, ...]
    metric: str = "distance"
    seconds: float = 6.0
    medium: str = "ground"
    expected_cycle: float = 0.5
    paper_speed: float | None = None
    useful_speed: float | None = None
    dt: float = 0.001
    control_dt: float = 0.005
    plane: str = "vertical"
    hidden: int | None = None
    root_angle: float = 0.0
    friction: float = 0.8
    hop_k: float = 0.0
    fall_links: tuple[str, ...] = ()
    fall_tilt: float | None = None
    crawl_friction: tuple[float, float, float] = (0.0, 0.0, 0.0)
    water_k: float = 0.0
    follow_speed: float = 0.1
    follow_lead: float = 0.5
    rough_height: float = 0.02
    description: str = ""
    path: Path | None = field(default=None, compare=False)

    @property
    def n_links(self) -> int:
        """Number of links."""
        return len(self.links)

    @property
    def n_sensors(self) -> int:
        """Number of binary sensors S."""
        return len(self.sensors)

    @property
    def n_actuators(self) -> int:
        """Number of actuators A."""
        return len(self.actuators)

    @property
    def size(self) -> float:
        """The body's length scale (m): the sum of its link lengths, or twice its largest
        radius when every link is a point or a sphere. Speeds in body lengths per second and
        the search's scale-free defaults (``zoetic.san.scales``) are measured in it."""
        total = sum(ln.length for ln in self.links)
        return total if total > 0 else 2.0 * max(ln.radius for ln in self.links)

    def link_index(self, name: str) -> int:
        """Return the index of the link called ``name``."""
        return [ln.name for ln in self.links].index(name)

    def tuning(self) -> dict[str, np.ndarray]:
        """Return the six Fig. 8 arrays: actuator lo/hi, ks, kd (A,) and sensor lo/hi (S,)."""
        a, s = self.actuators, self.sensors
        return {
            "actuator_lo": np.array([x.lo for x in a], dtype=float),
            "actuator_hi": np.array([x.hi for x in a], dtype=float),
            "ks": np.array([x.ks for x in a], dtype=float),
            "kd": np.array([x.kd for x in a], dtype=float),
            "sensor_lo": np.array([x.lo for x in s], dtype=float),
            "sensor_hi": np.array([x.hi for x in s], dtype=float),
        }

    def with_tuning(
        self,
        actuator_lo=None,
        actuator_hi=None,
        ks=None,
        kd=None,
        sensor_lo=None,
        sensor_hi=None,
    ) -> Creature:
        """Return a copy with some Fig. 8 parameters replaced (arrays (A,) / (S,)), validated."""
        where = f"{self.path or self.name}: with_tuning"
        given = dict(actuator_lo=actuator_lo, actuator_hi=actuator_hi, ks=ks, kd=kd)
        given.update(sensor_lo=sensor_lo, sensor_hi=sensor_hi)
        cur = self.tuning()
        for key, val in given.items():
            if val is None:
                continue
            arr = np.asarray(val, dtype=float)
            if arr.shape != cur[key].shape:
                raise CreatureError(
                    f"{where}: {key} must have shape {cur[key].shape}, got {arr.shape}"
                )
            cur[key] = arr
        acts = tuple(
            replace(
                a,
                lo=float(cur["actuator_lo"][i]),
                hi=float(cur["actuator_hi"][i]),
                ks=float(cur["ks"][i]),
                kd=float(cur["kd"][i]),
            )
            for i, a in enumerate(self.actuators)
        )
        sens = tuple(
            replace(s, lo=float(cur["sensor_lo"][i]), hi=float(cur["sensor_hi"][i]))
            for i, s in enumerate(self.sensors)
        )
        for a in acts:
            _check_actuator_values(a, f"{where}: actuator {a.name!r}")
        for s in sens:
            _check_range(s.lo, s.hi, f"{where}: sensor {s.name!r}")
        return replace(self, actuators=acts, sensors=sens)


def _finite(val: Any, where: str) -> float:
    if isinstance(val, bool) or not isinstance(val, int | float):
        raise CreatureError(f"{where} must be a number, got {abbrev(val)}")
    out = float(val)
    if not math.isfinite(out):
        raise CreatureError(f"{where} must be finite, got {val!r}")
    return out


def _check_range(lo: float, hi: float, where: str) -> None:
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise CreatureError(f"{where}: lo and hi must be finite, got lo={lo!r}, hi={hi!r}")
    if lo >= hi:
        raise CreatureError(f"{where}: lo ({lo:g}) must be below hi ({hi:g})")


def _check_actuator_values(a: Actuator, where: str) -> None:
    _check_range(a.lo, a.hi, where)
    if not (math.isfinite(a.ks) and a.ks > 0):
        raise CreatureError(f"{where}: ks must be positive, got {a.ks!r}")
    if not (math.isfinite(a.kd) and a.kd >= 0):
        raise CreatureError(f"{where}: kd must be non-negative, got {a.kd!r}")
