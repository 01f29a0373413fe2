"""Objective terms, each defined once for NumPy and JAX.

A term is a function ``term(xp, s, params) -> (K,)`` written against an array module ``xp``
(``numpy`` or ``jax.numpy``) and a ``Signals`` view of a batch of recordings
(``zoetic.tasks.signals``: positions (K, R, N, 3), the activations applied at those instants
(K, R, A), their times (R,), the medium's water level, and what is derived from them). The
registry ``TERMS`` is what task files name; a conformance test runs every entry through both
modules. Each term's docstring gives its value per recording, its unit and sign: the objective
minimises the weighted sum, so a "cost" (smaller is better) takes a positive weight and a "gain"
(larger is better) a negative one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from zoetic.control.sensors import wrap_angle
from zoetic.tasks.signals import EPS, Signals, norm_xz

# re-exported: the objective, the stunts and the aquarium read the body frame from here
from zoetic.tasks.signals import PARTS as PARTS
from zoetic.tasks.signals import BodyFrame as BodyFrame
from zoetic.tasks.signals import body_parts as body_parts
from zoetic.tasks.signals import roll_angle as roll_angle

TAIL_STRIKE_TURN = np.pi  # rad of somersault in the air a tail strike must follow (ball-tail)


@dataclass(frozen=True)
class TermParams:
    """The settings a term's formula reads from the task file: target and goal (not the weight)."""

    target: float = 0.0  # or (K,), one per recording
    goal: tuple[float, float, float] = (0.0, 0.0, 0.0)  # or (K, 3), one per recording


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


@term(
    "mean over the motion of the squared shortfall of the heading change from 'target' "
    "(rad^2, 0 once past it): reaching a heading early, not only at the end"
)
def heading_shortfall(xp, s: Signals, p: TermParams):
    """Return (K,) rad^2: mean squared shortfall of the turn so far from 'target' (>= 0; cost)."""
    sign = 1.0 if p.target >= 0 else -1.0
    turned = s.heading - s.heading[:, :1]
    return xp.mean(xp.maximum(sign * (p.target - turned), 0.0) ** 2, axis=1)


@term("metres the centre of mass travelled along the start heading")
def distance_along_heading(xp, s: Signals, p: TermParams):
    """Return (K,) m: centre-of-mass travel along its start heading (forward +; gain)."""
    return s.along


@term("squared sideways displacement of the centre of mass (m^2)")
def lateral_deviation(xp, s: Signals, p: TermParams):
    """Return (K,) m^2: squared sideways end displacement of the centre of mass (>= 0; cost)."""
    h0 = s.heading_xz[:, 0]
    left0 = xp.stack([-h0[:, 1], h0[:, 0]], axis=-1)
    return xp.sum(s.displacement_xz * left0, axis=-1) ** 2


@term("mean squared change of the centre of mass's height (m^2)")
def depth_keeping(xp, s: Signals, p: TermParams):
    """Return (K,) m^2: mean squared change of the centre of mass's height (>= 0; cost)."""
    y = s.com[:, :, 1]
    return xp.mean((y - y[:, :1]) ** 2, axis=1)


@term("squared error of the rise of the centre of mass, end minus start, against 'target' (m^2)")
def height_change(xp, s: Signals, p: TermParams):
    """Return (K,) m^2: squared error of the end-minus-start height vs 'target' (>= 0; cost)."""
    y = s.com[:, :, 1]
    return (y[:, -1] - y[:, 0] - p.target) ** 2


@term("squared error of the heading change against 'target' (rad^2)")
def heading_change(xp, s: Signals, p: TermParams):
    """Return (K,) rad^2: squared error of end-minus-start heading vs 'target' (>= 0; cost)."""
    return (s.heading[:, -1] - s.heading[:, 0] - p.target) ** 2


@term(
    "squared error of the change of the body axis's heading (``Signals.body_heading``, as the "
    "sensors and a task's promises measure it) against 'target' (rad^2): for an animal whose "
    "head wags far from its axis (the snake), which can end 'heading_change' with a swing"
)
def body_heading_change(xp, s: Signals, p: TermParams):
    """Return (K,) rad^2: squared error of end-minus-start body heading vs 'target' (cost)."""
    return (s.body_heading[:, -1] - s.body_heading[:, 0] - p.target) ** 2


@term("squared distance of the head to 'goal', relative to its start (m^2)")
def goal_distance2(xp, s: Signals, p: TermParams):
    """Return (K,) m^2: squared end distance of the head from its start plus 'goal' (cost)."""
    goal = s.head[:, 0] + xp.asarray(p.goal)
    return xp.sum((s.head[:, -1] - goal) ** 2, axis=-1)


@term("squared deviation of the mean forward speed from 'target' (m^2/s^2)")
def speed_deviation(xp, s: Signals, p: TermParams):
    """Return (K,) m^2/s^2: squared error of mean forward speed vs 'target' (>= 0; cost)."""
    return (s.along / s.horizon - p.target) ** 2


@term(
    "squared error of the top-view speed of the centre of mass over the second half of the "
    "motion, in body lengths per second, against 'target' ((BL/s)^2): swimming at a speed of "
    "the animal's own size, the first half left to reach it from rest or slow down from a cruise"
)
def steady_speed_bl(xp, s: Signals, p: TermParams):
    """Return (K,) (BL/s)^2: squared error of the second half's speed vs 'target' (cost)."""
    half = s.com.shape[1] // 2
    span = s.times[-1] - s.times[half] if s.com.shape[1] > 1 else 1.0
    speed = norm_xz(xp, s.com[:, -1] - s.com[:, half]) / span / s.frame.length
    return (speed - p.target) ** 2


@term("squared error of the final pitch against 'target' (rad^2, nose up positive)")
def final_pitch(xp, s: Signals, p: TermParams):
    """Return (K,) rad^2: squared error of the end pitch (nose up +) vs 'target' (>= 0; cost)."""
    return (s.pitch[:, -1] - p.target) ** 2


@term("mean squared roll of the body's left-right axis (rad^2): staying upright")
def roll_keeping(xp, s: Signals, p: TermParams):
    """Return (K,) rad^2: mean squared roll over the motion (>= 0, 0 upright; cost)."""
    return xp.mean(s.roll**2, axis=1)


@term(
    "mean squared shortfall of the head-to-tail distance (head node to the tail part's "
    "centre) below its start, as a fraction of it: keeps a fin from folding forward"
)
def length_keeping(xp, s: Signals, p: TermParams):
    """Return (K,): mean squared fractional shrink of head-to-tail length (>= 0; cost)."""
    tail = s.frame.part_mask("tail")
    tail = tail / max(float(tail.sum()), EPS)
    d = s.positions[:, :, s.frame.head] - xp.einsum("krnd,n->krd", s.positions, xp.asarray(tail))
    length = xp.sqrt(xp.sum(d * d, axis=-1) + EPS)
    return xp.mean(xp.maximum(1.0 - length / length[:, :1], 0.0) ** 2, axis=1)


@term(
    "squared excess of the greatest roll over the motion (``Signals.body_roll``: either way, "
    "upside down counted, as a task's roll promise measures it) above 'target' rad (rad^2, 0 "
    "while the body stays within it): a promise to stay upright as a term"
)
def roll_excess(xp, s: Signals, p: TermParams):
    """Return (K,) rad^2: squared excess of the greatest |roll| over 'target' (>= 0; cost)."""
    return xp.maximum(xp.max(xp.abs(s.body_roll), axis=1) - p.target, 0.0) ** 2


@term(
    "squared excess of the body axis's heading change, end minus start (``Signals."
    "body_heading``, as a task's turn promise measures it), beyond +-'target' rad (rad^2, 0 "
    "within): a promise to keep the heading as a term"
)
def turn_excess(xp, s: Signals, p: TermParams):
    """Return (K,) rad^2: squared excess of |end-minus-start body heading| over 'target'
    (>= 0; cost)."""
    turned = s.body_heading[:, -1] - s.body_heading[:, 0]
    return xp.maximum(xp.abs(turned) - p.target, 0.0) ** 2


@term("greatest height of the centre of mass above its start (m): leaps")
def max_height(xp, s: Signals, p: TermParams):
    """Return (K,) m: greatest rise of the centre of mass above its start height (>= 0; gain)."""
    y = s.com[:, :, 1]
    return xp.max(y, axis=1) - y[:, 0]


@term("fraction of the recorded time the body is wholly out of the water")
def air_time(xp, s: Signals, p: TermParams):
    """Return (K,): fraction (0..1) of records with no node in the water (gain)."""
    out = 1.0 - xp.max(s.in_water, axis=2)  # 1 when no node is wet
    return xp.mean(out, axis=1)


@term("mean speed of the centre of mass (m/s)")
def mean_speed(xp, s: Signals, p: TermParams):
    """Return (K,) m/s: mean speed of the centre of mass between records (>= 0; gain)."""
    v = s.velocity
    return xp.mean(xp.sqrt(xp.sum(v * v, axis=-1) + EPS), axis=1)


@term("mean squared muscle activation: effort")
def effort(xp, s: Signals, p: TermParams):
    """Return (K,): mean squared activation over records and actuators (>= 0; cost)."""
    return xp.mean(s.activations**2, axis=(1, 2))


@term(
    "squared error of the pitch change of the body's axis, end minus start, against 'target' "
    "(rad^2, nose up positive): turning up or down"
)
def pitch_change(xp, s: Signals, p: TermParams):
    """Return (K,) rad^2: squared error of end-minus-start pitch of the body's axis
    (``Signals.body_pitch``, as a task's promise measures it) vs 'target' (>= 0; cost)."""
    return (s.body_pitch[:, -1] - s.body_pitch[:, 0] - p.target) ** 2


@term("greatest height of the centre of mass above the water surface (m): a leap's apex")
def apex_above_surface(xp, s: Signals, p: TermParams):
    """Return (K,) m: highest centre of mass above the water level (< 0 if it stays under; gain)."""
    return xp.max(s.com[:, :, 1], axis=1) - s.level


@term(
    "depth (m) the centre of mass sank below where it started before its apex, counted up to "
    "'target' m when 'target' > 0: the run-up of a leap, diving deep before thrusting upward"
)
def dive_before_apex(xp, s: Signals, p: TermParams):
    """Return (K,) m: start height of the centre of mass less its lowest before the apex
    (>= 0, at most 'target' when that is > 0; gain)."""
    y = s.com[:, :, 1]
    before = xp.arange(y.shape[1])[None, :] <= s.apex_record[:, None]
    dive = xp.maximum(y[:, 0] - xp.min(xp.where(before, y, xp.inf), axis=1), 0.0)
    return xp.where(p.target > 0, xp.minimum(dive, p.target), dive)


@term(
    "greatest fraction of the nodes out of the water at one instant (1: the whole body "
    "clears the water)"
)
def clear_fraction(xp, s: Signals, p: TermParams):
    """Return (K,): greatest fraction (0..1) of nodes out of the water at one record (gain)."""
    return xp.max(xp.mean(1.0 - s.in_water, axis=2), axis=1)


@term(
    "height (m) of the body's highest node above the water surface at the end (0 once the "
    "whole body is back in the water): a leap that has re-entered"
)
def final_height(xp, s: Signals, p: TermParams):
    """Return (K,) m: highest node above the water at the end (>= 0, 0 back in; cost)."""
    return xp.maximum(xp.max(s.positions[:, -1, :, 1], axis=1) - s.level, 0.0)


@term(
    "rotation (rad, unsigned) of the body in its vertical plane while wholly out of the "
    "water: somersaults"
)
def flight_rotation(xp, s: Signals, p: TermParams):
    """Return (K,) rad: unsigned net turn in the vertical plane while airborne (>= 0; gain)."""
    both = s.airborne[:, 1:] * s.airborne[:, :-1]
    return xp.abs(xp.sum(xp.diff(s.body_angle, axis=1) * both, axis=1))


@term(
    "squared error of the pitch of the body's axis (``Signals.body_pitch``, nose up positive) "
    "at the apex of the centre of mass against 'target' (rad^2): horizontal over a hurdle"
)
def apex_pitch(xp, s: Signals, p: TermParams):
    """Return (K,) rad^2: squared error of the body's pitch at the apex vs 'target' (cost)."""
    return (s.at(s.body_pitch, s.apex_record) - p.target) ** 2


@term(
    "squared excess (rad^2) of the pitch of the body's axis (``Signals.body_pitch``, nose up "
    "positive) where the head re-enters the water after the apex (``Signals.reentry_record``; "
    "the last record while it is still out) above 'target' rad, 0 once the body points down at "
    "least that steeply: facing downward on re-entry"
)
def entry_pitch(xp, s: Signals, p: TermParams):
    """Return (K,) rad^2: squared excess of the re-entry pitch over 'target' (>= 0; cost)."""
    return xp.maximum(s.at(s.body_pitch, s.reentry_record) - p.target, 0.0) ** 2


@term(
    "height (m) of the centre of mass above goal[1] where it passes closest to x = goal[0] "
    "(world m): clearing a hurdle bar; a body that never reaches the bar scores at most 0 "
    "less the metres it stayed short (a leap before the bar is no hurdle)"
)
def bar_crossing_height(xp, s: Signals, p: TermParams):
    """Return (K,) m: centre of mass above goal[1] nearest x = goal[0] (< 0 if short; gain)."""
    x = s.com[:, :, 0]
    i = xp.argmin(xp.abs(x - p.goal[0]), axis=1)[:, None]
    h = xp.take_along_axis(s.com[:, :, 1], i, axis=1)[:, 0] - p.goal[1]
    short = xp.maximum(p.goal[0] - xp.max(x, axis=1), 0.0)
    return xp.where(short > 0, xp.minimum(h, 0.0) - short, h)


@term(
    "node-object contacts over the motion (node-steps touching a ball, hurdle or post; "
    "0 without objects)"
)
def contact_count(xp, s: Signals, p: TermParams):
    """Return (K,): node-object contacts summed over the records (>= 0; cost)."""
    return xp.sum(s.contacts, axis=1)


@term("greatest rise of the first ball above its start (m; 0 without a ball): a struck ball")
def ball_rise(xp, s: Signals, p: TermParams):
    """Return (K,) m: greatest rise of the first ball above its start (>= 0; gain)."""
    if s.balls.shape[2] == 0:
        return xp.zeros(s.positions.shape[0])
    y = s.balls[:, :, 0, 1]
    return xp.max(y, axis=1) - y[:, 0]


@term("closest approach (m) of the head to the first ball (0 without a ball)")
def ball_head_distance(xp, s: Signals, p: TermParams):
    """Return (K,) m: closest approach of the head to the first ball's centre (>= 0; cost)."""
    if s.balls.shape[2] == 0:
        return xp.zeros(s.positions.shape[0])
    d = s.head - s.balls[:, :, 0]
    return xp.min(xp.sqrt(xp.sum(d * d, axis=-1) + EPS), axis=1)


@term(
    "splash measure on re-entry (m^3/s): the area times the normal speed of every leading "
    "face at its re-entry (its first downward crossing of the surface after being out of "
    "the water), summed; large for a bellyflop, small for a clean dive"
)
def splash(xp, s: Signals, p: TermParams):
    """Return (K,) m^3/s: summed re-entry flux of leading faces (>= 0; cost or gain)."""
    return xp.sum(s.entry_flux, axis=(1, 2))


@term(
    "greatest distance (m) the first ball moved from its start at or after the nose first "
    "touched it, if the nose struck it first (``Signals.struck_first``): a ball the nose "
    "bounced off its support (0 without such a contact)"
)
def ball_moved_by_nose(xp, s: Signals, p: TermParams):
    """Return (K,) m: greatest ball travel after a first strike by the nose (>= 0; gain)."""
    return s.ball_moved_after("nose") * xp.max(s.struck_first("nose"), axis=1)


@term(
    "greatest distance (m) the first ball moved from its start at or after the tail (flukes) "
    "first touched it, if the tail struck it first (``Signals.struck_first``; 0 without such "
    "a contact, e.g. a ball another part had already knocked off its support)"
)
def ball_moved_by_tail(xp, s: Signals, p: TermParams):
    """Return (K,) m: greatest ball travel after a first strike by the tail (>= 0; gain)."""
    return s.ball_moved_after("tail") * xp.max(s.struck_first("tail"), axis=1)


@term(
    "somersault rotation (rad, about the body's own left-right axis, in flight; "
    "``Signals.flight_pitch``) at which the tail (flukes) struck the first ball, touching it "
    "first (``Signals.struck_first``) while the whole body is out of the water, once it had "
    "turned 'target' rad (0 if it never does): the tail's strike in a somersault"
)
def tail_strike_rotation(xp, s: Signals, p: TermParams):
    """Return (K,) rad: flight somersault turn at the tail's first strike if >= 'target' (gain)."""
    turned = xp.abs(s.flight_pitch)
    struck = (s.struck_first("tail") > 0) & (s.airborne > 0) & (turned >= p.target)
    return xp.max(xp.where(struck, turned, 0.0), axis=1)


@term(
    "rotation (rad, unsigned) about the body's own left-right axis while wholly out of the "
    "water (``Signals.flight_pitch``): somersaults, without the spins ``flight_rotation`` "
    "also counts"
)
def flight_pitch_rotation(xp, s: Signals, p: TermParams):
    """Return (K,) rad: greatest unsigned somersault turn while airborne (>= 0; gain)."""
    return xp.max(xp.abs(s.flight_pitch), axis=1)


@term(
    "rotation (rad, unsigned) about the body's own long axis while wholly out of the water "
    "(``Signals.flight_roll``): an aerial spin, a barrel roll in the air"
)
def flight_roll_rotation(xp, s: Signals, p: TermParams):
    """Return (K,) rad: greatest unsigned spin about the long axis while airborne (>= 0; gain)."""
    return xp.max(xp.abs(s.flight_roll), axis=1)


@term(
    "mean angular velocity (rad/s) about the body's own left-right axis in flight: the "
    "rotation ``flight_pitch_rotation`` over the time wholly out of the water (0 if never "
    "out for two records): a somersault's spin"
)
def flight_pitch_rate(xp, s: Signals, p: TermParams):
    """Return (K,) rad/s: somersault turn over the seconds wholly airborne (>= 0; gain)."""
    if s.airborne.shape[1] < 2:
        return xp.zeros(s.airborne.shape[0])
    both = s.airborne[:, 1:] * s.airborne[:, :-1]
    seconds = xp.sum(both, axis=1) * (s.times[1] - s.times[0])
    return xp.max(xp.abs(s.flight_pitch), axis=1) / xp.maximum(seconds, EPS)


@term(
    "closest approach (m) of the tail (flukes) to the first ball's centre once the body has "
    "turned half a somersault in the air (``TAIL_STRIKE_TURN``); before that, each record "
    "counts its distance plus the arc the tail still has to swing (the turn still to do times "
    "the tail's distance from the centre of mass; all of it while any node is in the water), "
    "so that a strike late in the somersault scores best (0 without a ball)"
)
def ball_tail_distance(xp, s: Signals, p: TermParams):
    """Return (K,) m: least tail-to-ball distance plus the arc left to swing (>= 0; cost)."""
    if s.balls.shape[2] == 0:
        return xp.zeros(s.positions.shape[0])
    tail = np.flatnonzero(s.frame.part_mask("tail"))
    r = s.positions[:, :, tail] - s.com[:, :, None]
    arm = xp.mean(xp.sqrt(xp.sum(r * r, axis=-1) + EPS), axis=2)  # (K, R) m
    turned = xp.where(s.airborne > 0, xp.abs(s.flight_pitch), 0.0)
    to_go = xp.maximum(TAIL_STRIKE_TURN - turned, 0.0)
    return xp.min(s.part_ball_distance("tail") + arm * to_go, axis=1)


@term(
    "top-view distance (m) of the centre of mass from 'goal' (world m) at the end: how far a "
    "goal still is (the Gym swim reward is its decrease over a step)"
)
def goal_distance_xz(xp, s: Signals, p: TermParams):
    """Return (K,) m: top-view end distance of the centre of mass from world 'goal' (cost)."""
    return norm_xz(xp, xp.asarray(p.goal) - s.com[:, -1])


@term(
    "top-view position (m) of the centre of mass at the end along the world heading 'target' "
    "(rad, left turns positive): how far along that line it has got (the Gym crawl reward is "
    "its increase over a step)"
)
def position_along(xp, s: Signals, p: TermParams):
    """Return (K,) m: top-view end centre of mass along world heading 'target' (gain)."""
    com = s.com[:, -1]
    return com[:, 0] * xp.cos(p.target) + com[:, 2] * xp.sin(p.target)


@term(
    "absolute error (rad, at most pi) of the heading of the body's forward axis at the end "
    "(``Signals.body_heading``) against the world heading 'target': how far a turn still has "
    "to go (the Gym turn reward is its decrease over a step)"
)
def heading_error(xp, s: Signals, p: TermParams):
    """Return (K,) rad: |wrapped| end body heading error vs world 'target' (0..pi; cost)."""
    return xp.abs(wrap_angle(p.target - s.body_heading[:, -1]))


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
