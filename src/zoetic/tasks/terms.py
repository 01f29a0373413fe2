"""Objective terms, each defined once for NumPy and JAX.

A term is a function ``term(xp, s, params) -> (K,)`` written against an array module ``xp``
(``numpy`` or ``jax.numpy``) and a ``Signals`` view of a batch of recordings: positions
(K, R, N, 3), the activations applied at those instants (K, R, A), their times (R,), and the
medium's water level. ``Signals`` derives what terms read (centre of mass, its velocity, the
body frame's heading, pitch and roll, which nodes are in water) with the same ``xp``, so the
NumPy objective and the JAX gradient evaluate the very same formulas. The registry ``TERMS``
is what task files name; a conformance test runs every entry through both modules.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from zoetic.bodies import Body

EPS = 1e-12  # guard on lengths (as the objective always used)
# body parts, front to back, that a contact record names (``BodyFrame.parts``)
PARTS = ("nose", "head", "belly", "back", "tail")
NOSE_SPAN, HEAD_SPAN, TAIL_SPAN = 0.12, 0.3, 0.25  # fractions of the body length
TAIL_STRIKE_TURN = np.pi  # rad of somersault in the air a tail strike must follow (ball-tail)


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

    @classmethod
    def of(cls, body: Body) -> BodyFrame:
        """Return the frame arrays of a body."""
        z = body.rest_pos[:, 2] - np.average(body.rest_pos[:, 2], weights=body.mass)
        left = np.array([n for n in range(body.n_nodes)
                         if body.node_mirror[n] >= 0 and z[n] > 1e-9], dtype=int)  # fmt: skip
        right = body.node_mirror[left].astype(int) if left.size else np.zeros(0, int)
        return cls(body.mass / body.total_mass, int(body.head), left, right,
                   np.asarray(body.panels, int), np.asarray(body.panel_weights, float),
                   body_parts(body))  # fmt: skip

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


def _norm_xz(xp, v):
    x, z = _xz(v)
    return xp.sqrt(x * x + z * z)


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
        return xp.arctan2(-lat[..., 1], _norm_xz(xp, lat) + EPS)
    # the horizontal left of the heading is (-f_z, f_x) in (x, z): left turns are toward +z
    side = lat[..., 2] * forward[..., 0] - lat[..., 0] * forward[..., 2]
    return xp.arctan2(-lat[..., 1], side)


class Signals:
    """What a batch of recordings shows, derived lazily with one array module ``xp``."""

    def __init__(self, xp, frame: BodyFrame, positions, activations, times, level: float,
                 horizon: float, contacts=None, balls=None, ball_touch=None):  # fmt: skip
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
        n = _norm_xz(xp, d) + EPS
        return xp.stack([d[..., 0] / n, d[..., 2] / n], axis=-1)

    @cached_property
    def heading(self):
        """Unwrapped heading (K, R), rad, left turns (toward +z) positive."""
        h = self.heading_xz
        return self.xp.unwrap(self.xp.arctan2(h[..., 1], h[..., 0]), axis=1)

    @cached_property
    def pitch(self):
        """Pitch (K, R), rad, nose up positive: the head's elevation seen from the centre."""
        d = self.head - self.com
        return self.xp.arctan2(d[..., 1], _norm_xz(self.xp, d) + EPS)

    @cached_property
    def roll(self):
        """Roll (K, R), rad: the tilt of the left-right axis (mirror pairs); 0 without pairs."""
        return roll_angle(self.xp, self.positions, self.frame.left, self.frame.right)

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
        xp = self.xp
        k, r = self.positions.shape[:2]
        if self.frame.left.size == 0 or r < 2:
            return xp.zeros((k, r))
        pos = self.positions
        lat = xp.mean(pos[:, :, self.frame.left] - pos[:, :, self.frame.right], axis=2)
        lat = lat / (xp.sqrt(xp.sum(lat * lat, axis=-1, keepdims=True)) + EPS)
        d = self.head - self.com
        a, b = d[:, :-1], d[:, 1:]
        turn = xp.arctan2(xp.sum(xp.cross(a, b) * lat[:, :-1], axis=-1), xp.sum(a * b, axis=-1))
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


@dataclass(frozen=True)
class TermParams:
    """A term's settings from the task file: weight, target and goal."""

    target: float = 0.0
    goal: tuple[float, float, float] = (0.0, 0.0, 0.0)


TermFn = Callable[[Any, Signals, TermParams], Any]


@dataclass(frozen=True)
class TermDef:
    """One registered term: its name, what it measures (with units) and its formula."""

    name: str
    doc: str
    fn: TermFn


TERMS: dict[str, TermDef] = {}


def term(doc: str) -> Callable[[TermFn], TermFn]:
    """Register the decorated function as the term of its name."""

    def register(fn: TermFn) -> TermFn:
        TERMS[fn.__name__] = TermDef(fn.__name__, doc, fn)
        return fn

    return register


@term("mean over the motion of the squared shortfall of the heading change from 'target' "
      "(rad^2, 0 once past it): reaching a heading early, not only at the end")
def heading_shortfall(xp, s: Signals, p: TermParams):
    sign = 1.0 if p.target >= 0 else -1.0
    turned = s.heading - s.heading[:, :1]
    return xp.mean(xp.maximum(sign * (p.target - turned), 0.0) ** 2, axis=1)


@term("metres the centre of mass travelled along the start heading")
def distance_along_heading(xp, s: Signals, p: TermParams):
    return s.along


@term("squared sideways displacement of the centre of mass (m^2)")
def lateral_deviation(xp, s: Signals, p: TermParams):
    h0 = s.heading_xz[:, 0]
    left0 = xp.stack([-h0[:, 1], h0[:, 0]], axis=-1)
    return xp.sum(s.displacement_xz * left0, axis=-1) ** 2


@term("mean squared change of the centre of mass's height (m^2)")
def depth_keeping(xp, s: Signals, p: TermParams):
    y = s.com[:, :, 1]
    return xp.mean((y - y[:, :1]) ** 2, axis=1)


@term("squared error of the heading change against 'target' (rad^2)")
def heading_change(xp, s: Signals, p: TermParams):
    return (s.heading[:, -1] - s.heading[:, 0] - p.target) ** 2


@term("squared distance of the head to 'goal', relative to its start (m^2)")
def goal_distance2(xp, s: Signals, p: TermParams):
    goal = s.head[:, 0] + xp.asarray(p.goal)
    return xp.sum((s.head[:, -1] - goal) ** 2, axis=-1)


@term("squared deviation of the mean forward speed from 'target' (m^2/s^2)")
def speed_deviation(xp, s: Signals, p: TermParams):
    return (s.along / s.horizon - p.target) ** 2


@term("squared error of the final pitch against 'target' (rad^2, nose up positive)")
def final_pitch(xp, s: Signals, p: TermParams):
    return (s.pitch[:, -1] - p.target) ** 2


@term("mean squared roll of the body's left-right axis (rad^2): staying upright")
def roll_keeping(xp, s: Signals, p: TermParams):
    return xp.mean(s.roll**2, axis=1)


@term("mean squared shortfall of the head-to-tail distance (head node to the tail part's "
      "centre) below its start, as a fraction of it: keeps a fin from folding forward")
def length_keeping(xp, s: Signals, p: TermParams):
    tail = s.frame.part_mask("tail")
    tail = tail / max(float(tail.sum()), EPS)
    d = s.positions[:, :, s.frame.head] - xp.einsum("krnd,n->krd", s.positions,
                                                     xp.asarray(tail))  # fmt: skip
    length = xp.sqrt(xp.sum(d * d, axis=-1) + EPS)
    return xp.mean(xp.maximum(1.0 - length / length[:, :1], 0.0) ** 2, axis=1)


@term("greatest height of the centre of mass above its start (m): leaps")
def max_height(xp, s: Signals, p: TermParams):
    y = s.com[:, :, 1]
    return xp.max(y, axis=1) - y[:, 0]


@term("fraction of the recorded time the body is wholly out of the water")
def air_time(xp, s: Signals, p: TermParams):
    out = 1.0 - xp.max(s.in_water, axis=2)  # 1 when no node is wet
    return xp.mean(out, axis=1)


@term("mean speed of the centre of mass (m/s)")
def mean_speed(xp, s: Signals, p: TermParams):
    v = s.velocity
    return xp.mean(xp.sqrt(xp.sum(v * v, axis=-1) + EPS), axis=1)


@term("mean squared muscle activation: effort")
def effort(xp, s: Signals, p: TermParams):
    return xp.mean(s.activations**2, axis=(1, 2))


@term("squared error of the pitch change, end minus start, against 'target' (rad^2, nose up "
      "positive): turning up or down")
def pitch_change(xp, s: Signals, p: TermParams):
    return (s.pitch[:, -1] - s.pitch[:, 0] - p.target) ** 2


@term("greatest height of the centre of mass above the water surface (m): a leap's apex")
def apex_above_surface(xp, s: Signals, p: TermParams):
    return xp.max(s.com[:, :, 1], axis=1) - s.level


@term("greatest fraction of the nodes out of the water at one instant (1: the whole body "
      "clears the water)")
def clear_fraction(xp, s: Signals, p: TermParams):
    return xp.max(xp.mean(1.0 - s.in_water, axis=2), axis=1)


@term("height (m) of the body's highest node above the water surface at the end (0 once the "
      "whole body is back in the water): a leap that has re-entered")
def final_height(xp, s: Signals, p: TermParams):
    return xp.maximum(xp.max(s.positions[:, -1, :, 1], axis=1) - s.level, 0.0)


@term("rotation (rad, unsigned) of the body in its vertical plane while wholly out of the "
      "water: somersaults")
def flight_rotation(xp, s: Signals, p: TermParams):
    both = s.airborne[:, 1:] * s.airborne[:, :-1]
    return xp.abs(xp.sum(xp.diff(s.body_angle, axis=1) * both, axis=1))


@term("squared error of the pitch at the apex of the centre of mass against 'target' (rad^2): "
      "horizontal over a hurdle")
def apex_pitch(xp, s: Signals, p: TermParams):
    i = xp.argmax(s.com[:, :, 1], axis=1)[:, None]
    return (xp.take_along_axis(s.pitch, i, axis=1)[:, 0] - p.target) ** 2


@term("height (m) of the centre of mass above goal[1] where it passes closest to x = goal[0] "
      "(world m): clearing a hurdle bar; a body that never reaches the bar scores at most 0 "
      "less the metres it stayed short (a leap before the bar is no hurdle)")
def bar_crossing_height(xp, s: Signals, p: TermParams):
    x = s.com[:, :, 0]
    i = xp.argmin(xp.abs(x - p.goal[0]), axis=1)[:, None]
    h = xp.take_along_axis(s.com[:, :, 1], i, axis=1)[:, 0] - p.goal[1]
    short = xp.maximum(p.goal[0] - xp.max(x, axis=1), 0.0)
    return xp.where(short > 0, xp.minimum(h, 0.0) - short, h)


@term("node-object contacts over the motion (node-steps touching a ball, hurdle or post; "
      "0 without objects)")
def contact_count(xp, s: Signals, p: TermParams):
    return xp.sum(s.contacts, axis=1)


@term("greatest rise of the first ball above its start (m; 0 without a ball): a struck ball")
def ball_rise(xp, s: Signals, p: TermParams):
    if s.balls.shape[2] == 0:
        return xp.zeros(s.positions.shape[0])
    y = s.balls[:, :, 0, 1]
    return xp.max(y, axis=1) - y[:, 0]


@term("closest approach (m) of the head to the first ball (0 without a ball)")
def ball_head_distance(xp, s: Signals, p: TermParams):
    if s.balls.shape[2] == 0:
        return xp.zeros(s.positions.shape[0])
    d = s.head - s.balls[:, :, 0]
    return xp.min(xp.sqrt(xp.sum(d * d, axis=-1) + EPS), axis=1)


@term("splash measure on re-entry (m^3/s): the area times the normal speed of every leading "
      "face at its re-entry (its first downward crossing of the surface after being out of "
      "the water), summed; large for a bellyflop, small for a clean dive")
def splash(xp, s: Signals, p: TermParams):
    return xp.sum(s.entry_flux, axis=(1, 2))


@term("greatest distance (m) the first ball moved from its start at or after the nose first "
      "touched it, if the nose struck it first (``Signals.struck_first``): a ball the nose "
      "bounced off its support (0 without such a contact)")
def ball_moved_by_nose(xp, s: Signals, p: TermParams):
    return s.ball_moved_after("nose") * xp.max(s.struck_first("nose"), axis=1)


@term("greatest distance (m) the first ball moved from its start at or after the tail (flukes) "
      "first touched it, if the tail struck it first (``Signals.struck_first``; 0 without such "
      "a contact, e.g. a ball another part had already knocked off its support)")
def ball_moved_by_tail(xp, s: Signals, p: TermParams):
    return s.ball_moved_after("tail") * xp.max(s.struck_first("tail"), axis=1)


@term("somersault rotation (rad, about the body's own left-right axis, in flight; "
      "``Signals.flight_pitch``) at which the tail (flukes) struck the first ball, touching it "
      "first (``Signals.struck_first``) while the whole body is out of the water, once it had "
      "turned 'target' rad (0 if it never does): the tail's strike in a somersault")
def tail_strike_rotation(xp, s: Signals, p: TermParams):
    turned = xp.abs(s.flight_pitch)
    struck = (s.struck_first("tail") > 0) & (s.airborne > 0) & (turned >= p.target)
    return xp.max(xp.where(struck, turned, 0.0), axis=1)


@term("rotation (rad, unsigned) about the body's own left-right axis while wholly out of the "
      "water (``Signals.flight_pitch``): somersaults, without the spins ``flight_rotation`` "
      "also counts")
def flight_pitch_rotation(xp, s: Signals, p: TermParams):
    return xp.max(xp.abs(s.flight_pitch), axis=1)


@term("mean angular velocity (rad/s) about the body's own left-right axis in flight: the "
      "rotation ``flight_pitch_rotation`` over the time wholly out of the water (0 if never "
      "out for two records): a somersault's spin")
def flight_pitch_rate(xp, s: Signals, p: TermParams):
    if s.airborne.shape[1] < 2:
        return xp.zeros(s.airborne.shape[0])
    both = s.airborne[:, 1:] * s.airborne[:, :-1]
    seconds = xp.sum(both, axis=1) * (s.times[1] - s.times[0])
    return xp.max(xp.abs(s.flight_pitch), axis=1) / xp.maximum(seconds, EPS)


@term("closest approach (m) of the tail (flukes) to the first ball's centre once the body has "
      "turned half a somersault in the air (``TAIL_STRIKE_TURN``); before that, each record "
      "counts its distance plus the arc the tail still has to swing (the turn still to do times "
      "the tail's distance from the centre of mass; all of it while any node is in the water), "
      "so that a strike late in the somersault scores best (0 without a ball)")
def ball_tail_distance(xp, s: Signals, p: TermParams):
    if s.balls.shape[2] == 0:
        return xp.zeros(s.positions.shape[0])
    tail = np.flatnonzero(s.frame.part_mask("tail"))
    r = s.positions[:, :, tail] - s.com[:, :, None]
    arm = xp.mean(xp.sqrt(xp.sum(r * r, axis=-1) + EPS), axis=2)  # (K, R) m
    turned = xp.where(s.airborne > 0, xp.abs(s.flight_pitch), 0.0)
    to_go = xp.maximum(TAIL_STRIKE_TURN - turned, 0.0)
    return xp.min(s.part_ball_distance("tail") + arm * to_go, axis=1)


def evaluate_terms(xp, s: Signals, terms) -> list:
    """Return each task term's raw value (K,) in order, for ``Term``-like items."""
    return [TERMS[t.kind].fn(xp, s, TermParams(t.target, t.goal)) for t in terms]


def term_names(terms) -> list[str]:
    """Return result keys for a task's terms: the kind, numbered when a kind repeats."""
    seen: dict[str, int] = {}
    out = []
    for t in terms:
        seen[t.kind] = seen.get(t.kind, 0) + 1
        out.append(t.kind if seen[t.kind] == 1 else f"{t.kind}#{seen[t.kind]}")
    return out
