"""What an animal senses of itself and its world: sensors as named functions of the state.

Each sensor returns an array with the batch axis first. ``observe(world, animal, sensors)``
collects the named ones into an observation dict; policies declare the sensors they read, so
an open-loop policy costs no sensing at all. Angles follow the objective's conventions: y is
up, heading = atan2(f_z, f_x) of the forward axis f (left turns positive), pitch > 0 nose up,
roll > 0 when the back tilts toward the animal's right (+z when heading along +x). The forward
and up axes are the rest pose's carried by the best linear fit of the current pose (exactly
the rotation for a rigid motion; ``orientation`` gives the best rotation, at an SVD a lane).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from zoetic.bodies import Body
from zoetic.errors import ControllerError
from zoetic.physics.media import Medium
from zoetic.physics.world import Contacts, World


def orientation(body: Body, positions: np.ndarray) -> np.ndarray:
    """Return the rotations (B, 3, 3) that best carry the rest pose onto ``positions``
    (B, N, 3) (mass-weighted Kabsch)."""
    w = body.mass / body.total_mass
    r0 = body.rest_pos - w @ body.rest_pos
    x = positions - np.einsum("n,bnk->bk", w, positions)[:, None, :]
    h = np.einsum("n,ni,bnj->bij", w, r0, x)
    u, _, vt = np.linalg.svd(h)
    r = np.einsum("bji,bkj->bik", vt, u)  # V U^T, a rotation unless it reflects
    det = np.einsum("bi,bi->b", r[:, :, 0], np.cross(r[:, :, 1], r[:, :, 2]))
    bad = det < 0
    if bad.any():  # flip the least significant axis: V diag(1, 1, -1) U^T
        r[bad] -= 2 * np.einsum("bi,bk->bik", vt[bad, 2], u[bad, :, 2])
    return r


def linear_fit(body: Body, positions, xp=np):
    """Return the linear maps L (B, 3, 3) that best carry the centred rest pose onto the
    centred ``positions`` in the mass-weighted least-squares sense (the rotation itself for
    a rigid motion; cheaper than ``orientation``, which needs an SVD per lane), computed with
    the array module ``xp`` (NumPy or JAX)."""
    w = body.mass / body.total_mass
    r0 = body.rest_pos - w @ body.rest_pos
    m_inv = np.linalg.pinv(np.einsum("n,ni,nj->ij", w, r0, r0))
    x = positions - xp.einsum("n,bnk->bk", w, positions)[:, None, :]
    return xp.einsum("n,bni,nj,jk->bik", w, x, r0, m_inv, optimize=True)


def forward_axis(body: Body, positions, xp=np):
    """Return the body's forward axes (B, 3) at ``positions`` (B, N, 3): the rest pose's
    forward axis carried by the best linear fit (``linear_fit``), as unit vectors."""
    return _unit(linear_fit(body, positions, xp) @ body.forward, xp)


def heading_of(forward, xp=np):
    """Return the headings (...,) in rad of forward axes (..., 3): atan2(f_z, f_x), left turns
    (toward +z) positive."""
    return xp.arctan2(forward[..., 2], forward[..., 0])


def wrap_angle(a):
    """Return angles (rad) wrapped into [-pi, pi) (NumPy or JAX arrays, or floats)."""
    return (a + np.pi) % (2 * np.pi) - np.pi


def _unit(v, xp=np):
    return v / (xp.linalg.norm(v, axis=-1, keepdims=True) + 1e-12)


@dataclass
class Senses:
    """One animal's view of a world at one moment; sensors read it (values cached)."""

    body: Body
    positions: np.ndarray  # (B, N, 3)
    velocities: np.ndarray  # (B, N, 3)
    medium: Medium
    time: float
    touching: np.ndarray  # (B, O) bool
    target: np.ndarray | None = None  # (B, 3)
    extra: dict = field(default_factory=dict)

    @cached_property
    def com(self) -> np.ndarray:
        """(B, 3) m: the centre of mass of each lane's positions."""
        return np.einsum("n,bnk->bk", self.body.mass / self.body.total_mass, self.positions)

    @cached_property
    def com_velocity(self) -> np.ndarray:
        """(B, 3) m/s: the mass-weighted mean velocity (the centre of mass's velocity)."""
        return np.einsum("n,bnk->bk", self.body.mass / self.body.total_mass, self.velocities)

    @cached_property
    def rotation(self) -> np.ndarray:
        """(B, 3, 3): the best rotation carrying the rest pose onto the pose (``orientation``)."""
        return orientation(self.body, self.positions)

    @cached_property
    def frame(self) -> np.ndarray:
        """(B, 3, 3): the best linear map carrying the rest pose onto the pose (``linear_fit``)."""
        return linear_fit(self.body, self.positions)

    @cached_property
    def forward(self) -> np.ndarray:
        """(B, 3) the body's forward axis: the rest heading carried by the best linear fit."""
        return _unit(self.frame @ self.body.forward)  # forward_axis, with the fit kept

    @cached_property
    def up(self) -> np.ndarray:
        """(B, 3) the body's up axis, made perpendicular to ``forward``."""
        f0 = self.body.forward
        u = self.frame @ _unit(np.array([0.0, 1.0, 0.0]) - f0[1] * f0)
        return _unit(u - (u * self.forward).sum(-1, keepdims=True) * self.forward)

    def need_target(self) -> np.ndarray:
        """Return the target (B, 3), m; raise ControllerError when none was given."""
        if self.target is None:
            raise ControllerError("a target sensor was asked for, but no target was given")
        return self.target


def _heading(s: Senses) -> np.ndarray:
    return heading_of(s.forward)


def _pitch(s: Senses) -> np.ndarray:
    return np.arcsin(np.clip(s.forward[:, 1], -1.0, 1.0))


def _roll(s: Senses) -> np.ndarray:
    side = _unit(np.cross(s.forward, np.array([0.0, 1.0, 0.0])))
    level_up = np.cross(side, s.forward)
    return np.arctan2((s.up * side).sum(-1), (s.up * level_up).sum(-1))


def _depth(s: Senses) -> np.ndarray:
    level = s.medium.water_level
    if abs(level) >= 1e8:
        return np.zeros(len(s.com))
    return level - s.com[:, 1]


def _to_target(s: Senses) -> np.ndarray:
    return s.need_target() - s.com


def _target_bearing(s: Senses) -> np.ndarray:
    d = _to_target(s)
    return wrap_angle(np.arctan2(d[:, 2], d[:, 0]) - _heading(s))


def _target_elevation(s: Senses) -> np.ndarray:
    d = _to_target(s)
    return np.arctan2(d[:, 1], np.linalg.norm(d[:, [0, 2]], axis=-1))


SENSORS: dict[str, Callable[[Senses], np.ndarray]] = {
    "com": lambda s: s.com,  # (B, 3) m
    "velocity": lambda s: s.com_velocity,  # (B, 3) m/s of the centre of mass
    "speed": lambda s: np.linalg.norm(s.com_velocity, axis=-1),  # (B,) m/s
    "forward_speed": lambda s: (s.com_velocity * s.forward).sum(-1),  # (B,) m/s along heading
    "heading": _heading,  # (B,) rad
    "pitch": _pitch,  # (B,) rad
    "roll": _roll,  # (B,) rad
    "depth": _depth,  # (B,) m below the water surface; 0 without a surface
    "contacts": lambda s: s.touching,  # (B, O) bool: touched each object last period
    "target_distance": lambda s: np.linalg.norm(_to_target(s), axis=-1),  # (B,) m
    "target_bearing": _target_bearing,  # (B,) rad, left positive, in (-pi, pi]
    "target_elevation": _target_elevation,  # (B,) rad above the horizontal
}
TARGET_SENSORS = ("target_distance", "target_bearing", "target_elevation")


def resolve_target(world: World, target, batch: int) -> np.ndarray | None:
    """Return the target as (B, 3): a point (3,) or (B, 3), or an object of the world given by
    its index or name (a ball or food follows it as it moves)."""
    if target is None:
        return None
    if isinstance(target, str | int) and not isinstance(target, bool):
        names = [o.name for o in world.objects]
        idx = names.index(target) if isinstance(target, str) and target in names else target
        if not isinstance(idx, int) or not 0 <= idx < len(world.objects):
            raise ControllerError(f"no object {target!r} in this world (objects: {names})")
        obj = world.objects[idx]
        if obj in world.balls:
            return world.ball_positions[:, world.balls.index(obj)]
        if obj in world.foods:
            return world.food_positions[:, world.foods.index(obj)]
        return np.broadcast_to(np.asarray(obj.center, float), (batch, 3))
    return np.broadcast_to(np.asarray(target, float).reshape(-1, 3), (batch, 3))


def observe(
    world: World,
    animal: int = 0,
    sensors: Sequence[str] | None = None,
    contacts: Contacts | None = None,
    target=None,
) -> dict[str, np.ndarray]:
    """Return the named sensors' readings (default all that apply) for one animal of a world,
    batch axis first, plus ``time`` (s)."""
    names = tuple(SENSORS) if sensors is None else tuple(sensors)
    if sensors is None and target is None:
        names = tuple(n for n in names if n not in TARGET_SENSORS)
    unknown = [n for n in names if n not in SENSORS]
    if unknown:
        raise ControllerError(f"unknown sensor(s) {unknown} (choose from {', '.join(SENSORS)})")
    obs: dict[str, np.ndarray] = {"time": np.full(world.batch, world.time)}
    if not names:
        return obs
    touching = (
        contacts.touching[:, animal]
        if contacts is not None and contacts.impulse[0].shape[2]
        else np.zeros((world.batch, len(world.objects)), dtype=bool)
    )
    s = Senses(
        world.bodies[animal],
        world.positions(animal),
        world.velocities(animal),
        world.medium,
        world.time,
        touching,
        resolve_target(world, target, world.batch),
    )
    for n in names:
        obs[n] = SENSORS[n](s)
    return obs
