"""Dynamic plants: seaweed as light spring-mass strands that sway in the current and part
around passing fishes.

Each strand is a chain of point masses from a fixed anchor on the seabed (node 0), joined by
stretch springs (rest length ``l0``, a dashpot along each segment) and bending springs on
every three consecutive nodes (energy kappa / 2 |a + c - 2 b|^2, zero when the strand is
straight and evenly spaced; a virtual node one segment under the anchor makes the base bend
springily too). The water acts on every node as on the world's balls
(``balls.balls_step``): net buoyancy (the blade is lighter than water, so it stands up) and
quadratic drag against the water's velocity, Cd ``water_drag`` A |u| u with A the blade's
broadside area, taken implicitly so it at most stops the node's motion relative to the water
in one step. The water is the tank's current plus a slow surge, a sinusoid of ``surge`` m/s
amplitude and ``surge_period`` s, so the strands sway.

Fishes push the strands aside: every node and segment middle of a strand that may touch a
fish in a slice of steps (``bodycontact.close_pairs`` on the fishes and strands together) is,
after each step, put back out of the fish's skin by its depth plus the blade's half width
(``bodycontact.skin_distances``: the signed distance and the way out), and its velocity into
the skin is taken away. The fish moves the strand as a kinematic body would: a strand weighs
under a tenth of a fish, so the fishes feel no reaction (one-way coupling), and their minds
still see the seaweed as its cylinder obstacle.

The step is semi-implicit Euler at the world's dt (velocities first, then positions with the
new velocities), vectorised over all strands at once (arrays (S, M + 1, 3), strand s's nodes
along axis 1). Units are SI, y up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from zoetic.bodies import Body
from zoetic.errors import SimulationError
from zoetic.physics.bodycontact import close_pairs, skin_distances, surface_reach
from zoetic.physics.media import Medium
from zoetic.physics.objects import WATER_DENSITY

STABLE = 1.2  # the largest omega dt the stiffest spring mode may reach (2 is the bound)


@dataclass(frozen=True)
class Weed:
    """How a strand is made (SI units): its segments, blade width and thickness (m), density
    (kg/m^3, under water's so that it floats up), drag coefficient across the blade, stretch
    stiffness (N/m a segment), bending stiffness kappa (N/m) and the segments' damping
    ratio."""

    segments: int = 10
    width: float = 0.08
    thickness: float = 0.004
    density: float = 800.0
    drag_coefficient: float = 1.2
    stretch: float = 400.0
    bending: float = 0.3
    damping_ratio: float = 0.5

    def __post_init__(self) -> None:
        if int(self.segments) < 1:
            raise SimulationError(f"a strand needs at least one segment, got {self.segments}")
        for name in ("width", "thickness", "density", "drag_coefficient", "stretch"):
            if not getattr(self, name) > 0:
                raise SimulationError(f"Weed {name} must be positive, got {getattr(self, name)}")
        if self.bending < 0 or self.damping_ratio < 0:
            raise SimulationError("Weed bending and damping ratio must be at least 0")


@dataclass(frozen=True)
class Skins:
    """The fishes' closed surfaces, stacked: fish a has nodes off[a]:off[a + 1] of the world's
    node array and triangles faces[face_off[a]:face_off[a + 1]] (indices into that array), and
    its surface lies within reach[a] m of its nodes (``bodycontact.surface_reach``)."""

    off: np.ndarray
    faces: np.ndarray
    face_off: np.ndarray
    reach: np.ndarray

    @classmethod
    def of(cls, bodies: list[Body], off: np.ndarray) -> Skins:
        """Return the skins of ``bodies`` laid out at the world's node offsets ``off``."""
        faces = [
            np.asarray(b.faces, np.int64).reshape(-1, 3) + off[a] for a, b in enumerate(bodies)
        ]
        counts = np.array([0] + [len(f) for f in faces])
        return cls(
            np.asarray(off, np.int64),
            np.concatenate(faces) if faces else np.zeros((0, 3), np.int64),
            np.cumsum(counts),
            np.array([surface_reach(b) for b in bodies], float),
        )


class Plants:
    """Strands anchored at ``anchors`` (S, 3) on the seabed, ``lengths`` (S,) m long, each
    made as ``weed`` says, in ``medium`` with the water moving at ``current`` (3,) m/s plus the
    surge; stepped at ``dt`` s from time ``t0``. ``pos``, ``vel``: (S, M + 1, 3), node 0 the
    anchor. They start straight up, at rest."""

    def __init__(
        self,
        anchors: np.ndarray,
        lengths: np.ndarray,
        weed: Weed,
        medium: Medium,
        current,
        dt: float,
        surge=(0.0, 0.0, 0.0),
        surge_period: float = 8.0,
        t0: float = 0.0,
    ) -> None:
        self.anchors = np.asarray(anchors, float).reshape(-1, 3)
        lengths = np.asarray(lengths, float).reshape(-1)
        if len(lengths) != len(self.anchors) or not (lengths > 0).all():
            raise SimulationError("every strand needs one positive length")
        if not surge_period > 0:
            raise SimulationError(f"surge_period must be positive, got {surge_period}")
        self.weed, self.dt, self.time = weed, float(dt), float(t0)
        m = int(weed.segments)
        self.l0 = lengths / m  # (S,) m
        volume = weed.width * weed.thickness * self.l0
        self.mass = (weed.density * volume)[:, None]  # (S, 1) kg a node
        self.area = (weed.width * self.l0)[:, None]  # (S, 1) m^2 broadside a node
        g = medium.gravity
        self.lift = (WATER_DENSITY * volume * g - self.mass[:, 0] * g)[:, None]  # N up a node
        self.drag = weed.drag_coefficient * medium.water_drag * self.area  # kg/m
        self.current = np.asarray(current, float).reshape(3)
        self.surge = np.asarray(surge, float).reshape(3)
        self.surge_period = float(surge_period)
        self.seabed = float(self.anchors[:, 1].min()) if len(self.anchors) else 0.0
        self.damp = 2.0 * weed.damping_ratio * np.sqrt(weed.stretch * self.mass)  # (S, 1)
        # the stiffest mode of a chain: 4 k / m stretching, 16 kappa / m bending
        w_max = np.sqrt((4.0 * weed.stretch + 16.0 * weed.bending) / self.mass.min(initial=1.0))
        if len(self.anchors) and w_max * self.dt > STABLE:
            raise SimulationError(
                f"the strands' springs are too stiff for dt = {self.dt:g} s "
                f"(omega dt = {w_max * self.dt:.2f} > {STABLE}); lower Weed.stretch or bending"
            )
        up = np.arange(m + 1)[None, :, None] * self.l0[:, None, None] * np.array([0.0, 1.0, 0.0])
        self.pos = self.anchors[:, None, :] + up
        self.vel = np.zeros_like(self.pos)
        self._constants(m)

    def _constants(self, m: int) -> None:
        """Lay out what every step reuses: the bending energy kappa / 2 |D c|^2 over the chain
        c = (the virtual node under the anchor, nodes 0..M) with D the second differences,
        written as the linear force K x + its virtual node's share (with the net buoyancy)."""
        d = np.zeros((m, m + 2))
        for j in range(m):
            d[j, j : j + 3] = (1.0, -2.0, 1.0)
        below = self.anchors - self.l0[:, None] * np.array([0.0, 1.0, 0.0])  # (S, 3)
        self._dx, self._db_below = d[:, 1:], d[:, :1] * below[:, None, :]  # (M, M+1), (S, M, 3)
        self._bend = -self.weed.bending * d[:, 1:].T @ d[:, 1:]  # (M + 1, M + 1)
        self._fixed = -self.weed.bending * np.einsum("jn,sjc->snc", d[:, 1:], self._db_below)
        self._fixed[:, :, 1] += self.lift
        self._l0 = self.l0[:, None, None]
        self._damp = self.damp[:, :, None]
        self._dt_m = self.dt / self.mass[:, :, None]
        self._drag_dt_m = self.drag[:, :, None] * self._dt_m

    @property
    def nodes(self) -> np.ndarray:
        """Return a copy of the strands' node positions (S, M + 1, 3), m."""
        return self.pos.copy()

    def water(self, t: float) -> np.ndarray:
        """Return the water's velocity (3,) m/s at time ``t`` s: current plus surge."""
        return self.current + self.surge * math.sin(2.0 * math.pi * t / self.surge_period)

    def forces(self, pos: np.ndarray, vel: np.ndarray) -> np.ndarray:
        """Return the springs', dashpots' and net buoyancy's force on every node (S, M + 1, 3)."""
        d = pos[:, 1:] - pos[:, :-1]  # (S, M, 3) segments
        length = np.sqrt((d * d).sum(-1, keepdims=True))
        unit = d / length
        rate = ((vel[:, 1:] - vel[:, :-1]) * unit).sum(-1, keepdims=True)
        pull = (self.weed.stretch * (length - self._l0) + self._damp * rate) * unit
        f = self._bend @ pos + self._fixed
        f[:, :-1] += pull
        f[:, 1:] -= pull
        return f

    def energy(self) -> float:
        """Return the strands' energy (J): kinetic, springs' and bending, and the potential of
        their net buoyancy (taken from the seabed)."""
        stretch = np.linalg.norm(np.diff(self.pos, axis=1), axis=-1) - self.l0[:, None]
        bend = self._dx @ self.pos + self._db_below
        kinetic = 0.5 * (self.mass[:, :, None] * self.vel**2).sum()
        springs = 0.5 * self.weed.stretch * (stretch**2).sum()
        bending = 0.5 * self.weed.bending * (bend**2).sum()
        rise = -(self.lift * (self.pos[:, :, 1] - self.seabed)).sum()
        return float(kinetic + springs + bending + rise)

    def step(self, fishes: tuple | None = None) -> None:
        """Advance one step of dt: springs and buoyancy kick the velocities, the water's drag
        slows them implicitly (at most stopping a node against the water), the positions move
        with the new velocities, then nodes inside a fish are put back out (``fishes``: what
        ``_collide`` reads); the anchors stay and no node sinks through the seabed."""
        v = self.vel + self._dt_m * self.forces(self.pos, self.vel)
        u = v - self.water(self.time + self.dt)
        v -= np.minimum(self._drag_dt_m * np.sqrt((u * u).sum(-1, keepdims=True)), 1.0) * u
        v[:, 0] = 0.0
        self.pos += self.dt * v
        self.vel = v
        if fishes is not None:
            self._collide(*fishes)
        if self.pos[:, :, 1].min() < self.seabed:
            low = self.pos[:, :, 1] < self.seabed
            self.pos[:, :, 1][low] = self.seabed
            self.vel[:, :, 1][low] = np.maximum(self.vel[:, :, 1][low], 0.0)
        self.time += self.dt

    def advance(self, steps: int, skins: Skins | None, start=None, end=None) -> None:
        """Advance ``steps`` steps while the fishes (``skins``) move from their node positions
        ``start`` to ``end`` (N, 3), taken as straight-line motion over the slice; the strands
        near a fish (``close_pairs`` over the slice) are kept out of its skin."""
        touch = None
        if skins is not None and start is not None and len(self.pos) and steps > 0:
            touch = self._touching(skins, np.asarray(start, float), np.asarray(end, float), steps)
        fish_vel = None if touch is None else (end - start) / (steps * self.dt)
        for k in range(steps):
            fishes = None
            if touch is not None:
                fishes = (skins, touch, start + (end - start) * ((k + 1) / steps), fish_vel)
            self.step(fishes)

    def _touching(self, skins: Skins, start, end, steps: int):
        """Return the contact points of the strands that may touch a fish in the slice:
        (strand, node a, node b) of each point (a node: a == b; a segment's middle: b = a + 1)
        and the fish it may touch; None if none may."""
        horizon = steps * self.dt
        s, n1 = self.pos.shape[0], self.pos.shape[1]
        fish_vel = (end - start) / horizon
        pos = np.concatenate([0.5 * (start + end), self.pos.reshape(-1, 3)])[:, :, None]
        vel = np.concatenate([fish_vel, self.vel.reshape(-1, 3)])[:, :, None]
        nf = len(skins.off) - 1
        off = np.concatenate([skins.off, skins.off[-1] + n1 * np.arange(1, s + 1)])
        reach = np.concatenate([skins.reach, np.zeros(s)])
        # a point of a segment lies within l0 / 2 of a node; the fish moves over the slice
        pad = float(0.5 * self.weed.width + 0.5 * self.l0.max())
        pad += 0.5 * float(np.abs(end - start).max(initial=0.0))
        pairs = close_pairs(pos, vel, off, reach, pad, horizon)
        pairs = pairs[(pairs[:, 0] < nf) & (pairs[:, 1] >= nf)]
        if not len(pairs):
            return None
        fish, strand = pairs[:, 0], pairs[:, 1] - nf
        nodes = np.arange(1, n1)
        segs = np.arange(n1 - 1)
        a = np.concatenate([nodes, segs])
        b = np.concatenate([nodes, segs + 1])
        k, n = len(a), len(pairs)
        points = (np.repeat(strand, k), np.tile(a, n), np.tile(b, n))
        return points, np.repeat(fish, k)

    def _collide(self, skins: Skins, touch, fish_pos: np.ndarray, fish_vel: np.ndarray):
        """Put every contact point that lies within the blade's half width of a fish's skin
        back out along the way out of the fish (a segment's middle moves both its ends), and
        take away its velocity into the fish's surface (an inelastic push: the fish, 11.7 kg
        against a strand's 0.7 kg, is not slowed); a node touched at several points takes
        their mean."""
        (s, a, b), fish = touch
        p = 0.5 * (self.pos[s, a] + self.pos[s, b])
        dist, face, bary, normal = skin_distances(
            np.ascontiguousarray(p),
            fish,
            np.ascontiguousarray(fish_pos),
            skins.faces,
            skins.face_off,
        )
        depth = 0.5 * self.weed.width - dist
        hit = (depth > 0.0) & (face >= 0)
        if not hit.any():
            return
        s, a, b, n = s[hit], a[hit], b[hit], normal[hit]
        surface = (bary[hit, :, None] * fish_vel[skins.faces[face[hit]]]).sum(1)
        v = 0.5 * (self.vel[s, a] + self.vel[s, b])
        into = np.minimum(((v - surface) * n).sum(-1), 0.0)
        moves = np.concatenate([depth[hit, None] * n, -into[:, None] * n], axis=1)  # (H, 6)
        two = a != b  # a segment's middle: both ends move
        rows, nodes = np.concatenate([s, s[two]]), np.concatenate([a, b[two]])
        total, count = np.zeros(self.pos.shape[:2] + (6,)), np.zeros(self.pos.shape[:2])
        np.add.at(total, (rows, nodes), np.concatenate([moves, moves[two]]))
        np.add.at(count, (rows, nodes), 1.0)
        mean = total / np.maximum(count, 1.0)[:, :, None]
        self.pos += mean[:, :, :3]
        self.vel += mean[:, :, 3:]
        self.pos[:, 0], self.vel[:, 0] = self.anchors, 0.0
