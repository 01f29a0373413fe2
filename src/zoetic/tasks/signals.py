"""What a batch of recordings shows, derived once for NumPy and JAX: ``Signals`` and the
constant arrays it needs from a body (``BodyFrame``).

``Signals`` is written against an array module ``xp`` (``numpy`` or ``jax.numpy``): from
positions (K, R, N, 3), the activations applied at those instants (K, R, A), their times (R,)
and the medium's water level it derives what objective terms read (centre of mass, its
velocity, the body frame's heading, pitch and roll, which nodes are in water), so the NumPy
objective and the JAX gradient evaluate the very same formulas.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from zoetic.bodies import Body
from zoetic.control.sensors import forward_axis, heading_of

EPS = 1e-12  # guard on lengths (as the objective always used)
# body parts, front to back, that a contact record names (``BodyFrame.parts``)
PARTS = ("nose", "head", "belly", "back", "tail")
NOSE_SPAN, HEAD_SPAN, TAIL_SPAN = 0.12, 0.3, 0.25  # fractions of the body length


@dataclass(frozen=True)
class BodyFrame:
    """The constant arrays terms need from a body: mass weights, head, mirror pairs, the
    water panels (for the splash) and which part of the body each node belongs to."""

    weights: np.ndarray  # (N,) mass fractions
    head: int
    left: np.ndarray  # (P,) nodes on the left (z > 0) that have a mirror node
    right: np.ndarray  # (P,) their mirror nodes
    panels: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 4), int))
    panel_weights: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 4)))
    parts: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, int))  # (N,)
    body: Body | None = None  # for the body's forward axis (``Signals.body_heading``)
    length: float = 1.0  # m, the body's length (``Body.length``): speeds in body lengths/s

    @classmethod
    def of(cls, body: Body) -> BodyFrame:
        """Return the frame arrays of a body."""
        z = body.rest_pos[:, 2] - np.average(body.rest_pos[:, 2], weights=body.mass)
        left = np.array(
            [n for n in range(body.n_nodes) if body.node_mirror[n] >= 0 and z[n] > 1e-9], dtype=int
        )
        right = body.node_mirror[left].astype(int) if left.size else np.zeros(0, int)
        return cls(
            body.mass / body.total_mass,
            int(body.head),
            left,
            right,
            np.asarray(body.panels, int),
            np.asarray(body.panel_weights, float),
            body_parts(body),
            body,
            body.length,
        )

    def part_mask(self, part: str) -> np.ndarray:
        """Return (N,) 1.0 on the nodes of a part (one of ``PARTS``), else 0.0."""
        return (self.parts == PARTS.index(part)).astype(float)


def body_parts(body: Body) -> np.ndarray:
    """Return (N,) the index in ``PARTS`` of each node's body part, from the rest pose: along
    the axis from the centre of mass to the head, the front 12% of the length is the nose, the
    rest of the front 30% the head, the rear 25% the tail (flukes); between them the nodes
    below the centre of mass are the belly, those above the back."""
    rest = np.asarray(body.rest_pos, float)
    com = body.mass @ rest / body.total_mass
    axis = rest[body.head] - com
    axis /= np.linalg.norm(axis) + EPS
    s = (rest - com) @ axis
    front, length = s.max(), s.max() - s.min() + EPS
    parts = np.where(rest[:, 1] < com[1], PARTS.index("belly"), PARTS.index("back"))
    parts = np.where(s <= s.min() + TAIL_SPAN * length, PARTS.index("tail"), parts)
    parts = np.where(s >= front - HEAD_SPAN * length, PARTS.index("head"), parts)
    parts = np.where(s >= front - NOSE_SPAN * length, PARTS.index("nose"), parts)
    parts[body.head] = PARTS.index("nose")
    return parts.astype(int)


def _xz(v):
    return v[..., 0], v[..., 2]


def norm_xz(xp, v):
    """Return the top-view (x, z) lengths (...,) of vectors (..., 3)."""
    x, z = _xz(v)
    return xp.sqrt(x * x + z * z)


def _unit(xp, v):
    """Return vectors (..., 3) scaled to unit length (zero vectors stay near zero)."""
    return v / (xp.sqrt(xp.sum(v * v, axis=-1, keepdims=True)) + EPS)


def roll_angle(xp, positions, left, right, forward=None):
    """Return the roll (...), rad, of positions (..., N, 3): the tilt of the left-right axis
    (the mean of left minus right over the mirror pairs, ``BodyFrame.left`` and ``.right``)
    from the horizontal, positive when the left side is down (rolled to the left, seen from
    behind); 0 without pairs. Within +-pi/2, so a fish upside down reads 0, unless
    ``forward`` (..., 3), the fish's heading, is given: then the left-right axis is measured
    against the heading's horizontal left, and the roll runs over +-pi (pi upside down)."""
    if len(left) == 0:
        return xp.zeros(positions.shape[:-2])
    lat = xp.mean(positions[..., left, :] - positions[..., right, :], axis=-2)
    if forward is None:
        return xp.arctan2(-lat[..., 1], norm_xz(xp, lat) + EPS)
    # the horizontal left of the heading is (-f_z, f_x) in (x, z): left turns are toward +z
    side = lat[..., 2] * forward[..., 0] - lat[..., 0] * forward[..., 2]
    return xp.arctan2(-lat[..., 1], side)


class Signals:
    """What a batch of recordings shows, derived lazily with one array module ``xp``."""

    def __init__(
        self,
        xp,
        frame: BodyFrame,
        positions,
        activations,
        times,
        level: float,
        horizon: float,
        contacts=None,
        balls=None,
        ball_touch=None,
    ):
        self.xp = xp
        self.frame = frame
        self.positions = positions  # (K, R, N, 3)
        self.activations = activations  # (K, R, A)
        self.times = times  # (R,)
        self.level = level
        self.horizon = float(horizon)
        # from a World rollout: (node, object) contacts since the previous record (K, R), and
        # ball centres (K, R, nb, 3); none without objects
        k, r = positions.shape[:2]
        self.contacts = xp.zeros((k, r)) if contacts is None else contacts
        self.balls = xp.zeros((k, r, 0, 3)) if balls is None else balls
        # (K, R, N): each node's contact with the first ball (impulse, N s) since the previous
        # record; zeros without one
        n = positions.shape[2]
        self.ball_touch = xp.zeros((k, r, n)) if ball_touch is None else ball_touch

    @cached_property
    def com(self):
        """Centre of mass (K, R, 3)."""
        return self.xp.einsum("krnd,n->krd", self.positions, self.xp.asarray(self.frame.weights))

    @cached_property
    def head(self):
        """Head node position (K, R, 3)."""
        return self.positions[:, :, self.frame.head]

    @cached_property
    def heading_xz(self):
        """Unit top-view heading (K, R, 2): the head's direction from the centre of mass."""
        xp = self.xp
        d = self.head - self.com
        n = norm_xz(xp, d) + EPS
        return xp.stack([d[..., 0] / n, d[..., 2] / n], axis=-1)

    @cached_property
    def heading(self):
        """Unwrapped heading (K, R), rad, left turns (toward +z) positive."""
        h = self.heading_xz
        return self.xp.unwrap(self.xp.arctan2(h[..., 1], h[..., 0]), axis=1)

    @cached_property
    def body_forward(self):
        """Unit forward axis (K, R, 3) of the body as the sensors measure it
        (``control.sensors.forward_axis``: the rest pose's forward axis carried by the best
        linear fit; needs ``BodyFrame.of``), not swung by the head as the head's direction is."""
        k, r, n = self.positions.shape[:3]
        f = forward_axis(self.frame.body, self.positions.reshape(k * r, n, 3), self.xp)
        return f.reshape(k, r, 3)

    @cached_property
    def body_heading(self):
        """Unwrapped heading (K, R), rad, of the body's forward axis (``body_forward``), not
        swung by the head's wag as ``heading`` is."""
        xp = self.xp
        return xp.unwrap(heading_of(self.body_forward, xp), axis=1)

    @cached_property
    def body_pitch(self):
        """Pitch (K, R), rad, nose up positive, of the body's forward axis (``body_forward``),
        as the sensors and a task's promises measure it."""
        xp = self.xp
        return xp.arcsin(xp.clip(self.body_forward[..., 1], -1.0, 1.0))

    @cached_property
    def pitch(self):
        """Pitch (K, R), rad, nose up positive: the head's elevation seen from the centre."""
        d = self.head - self.com
        return self.xp.arctan2(d[..., 1], norm_xz(self.xp, d) + EPS)

    @cached_property
    def apex_record(self):
        """Record (K,) of the centre of mass's apex (its highest point)."""
        return self.xp.argmax(self.com[:, :, 1], axis=1)

    @cached_property
    def reentry_record(self):
        """Record (K,) at which the head is first back under the water after the centre of
        mass's apex (a leap's re-entry, the head leading a dive); the last record while the
        head is still out by then."""
        xp = self.xp
        r = self.positions.shape[1]
        wet = (self.head[:, :, 1] < self.level) & (
            xp.arange(r)[None, :] >= self.apex_record[:, None]
        )
        return xp.where(xp.any(wet, axis=1), xp.argmax(wet, axis=1), r - 1)

    @cached_property
    def reentered(self):
        """1.0 (K,) where the head was out of the water at the apex and is back under it by the
        end (``reentry_record`` is a re-entry), else 0.0."""
        xp = self.xp
        head_y = self.head[:, :, 1]
        out = self.at(head_y, self.apex_record) >= self.level
        back = self.at(head_y, self.reentry_record) < self.level
        return xp.where(out & back, 1.0, 0.0)

    def at(self, values, records):
        """Return (K,) values (K, R) at one record (K,) per recording."""
        return self.xp.take_along_axis(values, records[:, None], axis=1)[:, 0]

    @cached_property
    def roll(self):
        """Roll (K, R), rad: the tilt of the left-right axis (mirror pairs); 0 without pairs."""
        return roll_angle(self.xp, self.positions, self.frame.left, self.frame.right)

    @cached_property
    def body_roll(self):
        """Roll (K, R), rad, over +-pi (pi upside down): the tilt of the left-right axis
        against the horizontal left of the body's forward axis (``body_forward``), as a task's
        roll promise measures it; ``roll`` reads a fish upside down as upright."""
        return roll_angle(
            self.xp, self.positions, self.frame.left, self.frame.right, self.body_forward
        )

    @cached_property
    def body_angle(self):
        """Unwrapped angle (K, R), rad, of the head about the centre of mass in the vertical
        plane of the start heading: 0 level, pi/2 nose up, 2 pi after a full back somersault."""
        xp = self.xp
        d = self.head - self.com
        h0 = self.heading_xz[:, :1]  # (K, 1, 2)
        ahead = d[..., 0] * h0[..., 0] + d[..., 2] * h0[..., 1]
        return xp.unwrap(xp.arctan2(d[..., 1], ahead), axis=1)

    @cached_property
    def airborne(self):
        """1.0 where no node is in the water, else 0.0, (K, R)."""
        return 1.0 - self.xp.max(self.in_water, axis=2)

    @cached_property
    def velocity(self):
        """Centre-of-mass velocity (K, R-1, 3), m/s, between records."""
        dt = self.times[1] - self.times[0] if len(self.times) > 1 else 1.0
        return (self.com[:, 1:] - self.com[:, :-1]) / dt

    @cached_property
    def in_water(self):
        """1.0 where a node is under the water level, else 0.0, (K, R, N)."""
        return self.xp.where(self.positions[..., 1] < self.level, 1.0, 0.0)

    @cached_property
    def face_centres(self):
        """Centres of the water panels (K, R, P, 3)."""
        pos = self.positions[:, :, self.frame.panels]  # (K, R, P, 4, 3)
        return self.xp.einsum("krpqd,pq->krpd", pos, self.xp.asarray(self.frame.panel_weights))

    @cached_property
    def face_normals(self):
        """Panel normals (K, R, P, 3) whose length is twice the panel's area."""
        pos = self.positions[:, :, self.frame.panels]
        return self.xp.cross(pos[..., 2, :] - pos[..., 0, :], pos[..., 3, :] - pos[..., 1, :])

    @cached_property
    def crossing_flux(self):
        """The surface crossings of the panels (K, R-1, P), m^3/s: where a panel's centre
        crosses the water surface between two records, its area times its speed along its
        outward normal there when it leads the motion (a face slapping the water flat moves a
        lot of water, one slicing in edge-on little, a trailing face none), positive going
        in, negative coming out; 0 where it does not cross."""
        xp = self.xp
        c = self.face_centres
        y = c[..., 1]
        above = y >= self.level
        down = above[:, :-1] & ~above[:, 1:]
        up = ~above[:, :-1] & above[:, 1:]
        dt = self.times[1] - self.times[0] if len(self.times) > 1 else 1.0
        v = (c[:, 1:] - c[:, :-1]) / dt
        n = 0.5 * (self.face_normals[:, :-1] + self.face_normals[:, 1:])
        flux = 0.5 * xp.maximum(xp.sum(n * v, axis=-1), 0.0)
        return xp.where(down, flux, xp.where(up, -flux, 0.0))

    @cached_property
    def entry_flux(self):
        """The splash of each panel's re-entry (K, R-1, P), m^3/s: its ``crossing_flux`` at
        its first downward crossing after it has been out of the water (above it at the start,
        or crossed up since), 0 elsewhere. One plunge per face: a face that leaves the water
        and comes back down hits it once; the same face beating across the surface
        afterwards, or slapping it before it has been out, is no re-entry (counting those let
        a body wallowing at the surface for a second outscore a bellyflop)."""
        xp = self.xp
        above = self.face_centres[..., 1] >= self.level  # (K, R, P)
        up = xp.where(~above[:, :-1] & above[:, 1:], 1, 0)
        down = ~above[:, 1:] & above[:, :-1]
        been_out = (xp.cumsum(up, axis=1) > 0) | above[:, :1]  # out by the end of each step
        plunge = xp.where(down & been_out, 1, 0)
        first = (plunge > 0) & (xp.cumsum(plunge, axis=1) == 1)
        return xp.where(first, xp.maximum(self.crossing_flux, 0.0), 0.0)

    def part_touch(self, part: str):
        """Contact of a body part with the first ball (K, R), N s, since the previous record."""
        return self.xp.sum(self.ball_touch * self.xp.asarray(self.frame.part_mask(part)), axis=2)

    def ball_moved_after(self, part: str):
        """Greatest distance (K,), m, of the first ball from its start at or after that part's
        first contact with it (0 without a ball or without such a contact)."""
        xp = self.xp
        if self.balls.shape[2] == 0:
            return xp.zeros(self.positions.shape[0])
        touched = xp.cumsum(self.part_touch(part), axis=1) > 0
        d = self.balls[:, :, 0] - self.balls[:, :1, 0]
        dist = xp.sqrt(xp.sum(d * d, axis=-1) + EPS)
        return xp.max(xp.where(touched, dist, 0.0), axis=1)

    def struck_first(self, part: str):
        """1.0 (K, R) at the record of the first ball's first contact with the body where that
        part is among those touching it (it struck the ball first, not after another part had
        knocked it away), else 0.0."""
        xp = self.xp
        hit = xp.where(xp.sum(self.ball_touch, axis=2) > 0, 1.0, 0.0)
        first = hit * (xp.cumsum(hit, axis=1) == 1.0)
        return first * xp.where(self.part_touch(part) > 0, 1.0, 0.0)

    @cached_property
    def flight_pitch(self):
        """Signed rotation (K, R), rad, of the body about its own left-right axis (a
        somersault's axis) while wholly out of the water, up to each record: the sum of the
        head's turns about the centre of mass around that axis between records. Unlike
        ``body_angle``, which is read in the start's vertical plane, a spin about the
        vertical or a body turned sideways adds nothing. Zeros without mirror pairs."""
        if self.frame.left.size == 0 or self.positions.shape[1] < 2:
            return self.xp.zeros(self.positions.shape[:2])
        return self._airborne_turn(self.head - self.com, _unit(self.xp, self._lateral))

    @cached_property
    def flight_roll(self):
        """Signed rotation (K, R), rad, of the body about its own long axis (centre of mass to
        head: a spin's axis) while wholly out of the water, up to each record: the sum of the
        left-right axis' turns about the long axis between records, positive when the left
        side goes down. Zeros without mirror pairs."""
        xp = self.xp
        if self.frame.left.size == 0 or self.positions.shape[1] < 2:
            return xp.zeros(self.positions.shape[:2])
        axis = _unit(xp, self.head - self.com)
        lat = self._lateral
        lat = lat - xp.sum(lat * axis, axis=-1, keepdims=True) * axis  # across the long axis
        return self._airborne_turn(lat, axis)

    @cached_property
    def _lateral(self):
        """The body's left-right vector (K, R, 3): mean of left minus right over mirror pairs."""
        pos = self.positions
        return self.xp.mean(pos[:, :, self.frame.left] - pos[:, :, self.frame.right], axis=2)

    def _airborne_turn(self, v, axis):
        """Return (K, R) rad: the signed turns of vectors ``v`` (K, R, 3) about the unit
        ``axis`` (K, R, 3) from record to record, summed over the steps wholly airborne (0 at
        the first record)."""
        xp = self.xp
        a, b = v[:, :-1], v[:, 1:]
        turn = xp.arctan2(xp.sum(xp.cross(a, b) * axis[:, :-1], axis=-1), xp.sum(a * b, axis=-1))
        both = self.airborne[:, 1:] * self.airborne[:, :-1]
        turned = xp.cumsum(turn * both, axis=1)
        return xp.concatenate([xp.zeros_like(turned[:, :1]), turned], axis=1)

    def part_ball_distance(self, part: str):
        """Closest approach (K, R), m, of a body part's nodes to the first ball's centre
        (zeros without a ball)."""
        xp = self.xp
        if self.balls.shape[2] == 0:
            return xp.zeros(self.positions.shape[:2])
        nodes = np.flatnonzero(self.frame.part_mask(part))
        d = self.positions[:, :, nodes] - self.balls[:, :, :1]
        return xp.min(xp.sqrt(xp.sum(d * d, axis=-1) + EPS), axis=2)

    @cached_property
    def displacement_xz(self):
        """Top-view displacement of the centre of mass, start to end, (K, 2)."""
        d = self.com[:, -1] - self.com[:, 0]
        return self.xp.stack([d[:, 0], d[:, 2]], axis=-1)

    @cached_property
    def along(self):
        """Metres travelled along the start heading, (K,)."""
        return self.xp.sum(self.displacement_xz * self.heading_xz[:, 0], axis=-1)
