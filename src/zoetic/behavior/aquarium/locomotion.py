"""The motor layer of the aquarium: motor demands (speed, turn, pitch) in, muscle activations out.

``Locomotion`` is the small interface the behaviour routines' demands go through;
``MotorLocomotion`` is the built-in motor skill: the parameterised controllers of
``behavior.wave_motor.WaveMotor`` (swim at a speed, turn by an angle, pitch with the fins), the
body's own steered wave calibrated once per body and frequency, so that a demanded speed is
the speed swum and a demanded turn the angle turned (in ``TURN_SECONDS``, or as fast as the
body can).
"""

from __future__ import annotations

import os
import weakref
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Protocol

import numpy as np

from zoetic.behavior.learned_motor import LEARNED_STRENGTH, LearnedMotor
from zoetic.behavior.motor import righting
from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.wave_motor import WaveMotor
from zoetic.bodies import Body

TURN_SECONDS = 1.0  # s a demanded heading change is to take (the routines re-aim every period)
MAX_PITCH = 0.5  # rad: the largest fin pitch a routine may ask for


@dataclass(frozen=True)
class Demand:
    """What a behaviour routine asks of the motor system: forward speed (m/s), the heading
    change wanted (rad, left positive) and the pitch wanted (rad, nose up positive); and the
    fish's roll (rad, ``tasks.terms.roll_angle``, left side down positive) and roll rate
    (rad/s) that the tank measured, which the motor layer's righting reflex feeds back to the
    fins (``behavior.motor.righting``); and its bend (``bend``: nose to tail over the rest
    length, 1 straight), which the learned motor's fold guard reads."""

    speed: float
    turn: float = 0.0
    pitch: float = 0.0
    roll: float = 0.0
    roll_rate: float = 0.0
    bend: float = 1.0

    @property
    def fin_pitch(self) -> float:
        """The pitch the fins are set to: the one asked, within +-``MAX_PITCH``."""
        return min(max(self.pitch, -MAX_PITCH), MAX_PITCH)


TAIL_NODE = "tail_top"  # the node whose distance to the nose (the head) measures the bend
FOLDED = 0.8  # bend under this: the tail fin has folded forward through the peduncle (0.6-0.7)


def bend_nodes(body: Body) -> tuple[int, int, float] | None:
    """Return (nose node: the body's head, tail node, rest distance m) that ``bend`` measures
    on the body, or None if it has no ``TAIL_NODE``."""
    if TAIL_NODE not in body.node_names:
        return None
    head, tail = body.head, body.node_names.index(TAIL_NODE)
    return head, tail, float(np.linalg.norm(body.rest_pos[head] - body.rest_pos[tail]))


def bend(body: Body, positions: np.ndarray) -> np.ndarray:
    """Return the fish's bend at each of ``positions`` (..., N, 3): the nose-to-tail-fin
    distance over its rest length (1 for a body without a tail node). A fish steering hard
    bends to about 0.87; a folded tail leaves 0.6-0.7 (under ``FOLDED``)."""
    nodes = bend_nodes(body)
    if nodes is None:
        return np.ones(positions.shape[:-2])
    nose, tail, rest = nodes
    return np.linalg.norm(positions[..., nose, :] - positions[..., tail, :], axis=-1) / rest


class Locomotion(Protocol):
    """Turns motor demands into activations."""

    def activations(self, demand: Demand, times: np.ndarray) -> np.ndarray:
        """Return activations (T, A) for the times (T,) s of a control period."""
        ...


class MotorLocomotion:
    """The built-in motor skill: ``WaveMotor.calibrate(body, frequency)``'s swim, turn and
    pitch controllers (``turn_seconds``: the time a demanded turn is to take)."""

    def __init__(
        self,
        body: Body,
        frequency: float | None = None,
        turn_seconds: float = TURN_SECONDS,
        righting: bool = True,
    ) -> None:
        self.body = body
        self.motor = WaveMotor.calibrate(body, frequency)
        self.turn_seconds = float(turn_seconds)
        self.righting = righting  # the righting reflex (fins' lean from the demand's roll)

    @property
    def top_speed(self) -> float:
        """Return the fastest the calibrated wave swims (m/s)."""
        return self.motor.top_speed

    @property
    def turn_radius(self) -> float:
        """Return the radius (m) of the sharpest turn at full amplitude."""
        return float(self.motor.speeds[-1] / max(self.motor.rates[-1, -1], 1e-6))

    def activations(self, demand: Demand, times: np.ndarray) -> np.ndarray:
        """Return activations (T, A): swim(speed) turning by demand.turn, fins at the pitch."""
        return self.activations_many([demand], times)[0]

    def activations_many(self, demands: list[Demand], times: np.ndarray) -> np.ndarray:
        """Return activations (D, T, A) for several demands at once (one wave evaluation)."""
        return self.motor.activations_many(
            times,
            [d.speed for d in demands],
            [d.turn for d in demands],
            [d.fin_pitch for d in demands],
            self.turn_seconds,
            [righting(d.roll, d.roll_rate) if self.righting else 0.0 for d in demands],
        )


TURN_MIN = 0.1  # rad: a smaller demanded turn swims on (the next period corrects it)
# s: the longest a learned sharp turn is played at once; played longer (or repeated) it can
# fold the tail fin forward through the peduncle for good, and the fish then swims backwards
TURN_BURST = 0.3
# s of swimming after a turn before the next may start, to either side: a burst cut short by
# a turn the other way folds the tail, and one restarted at once to the same side replays the
# sharp turn's opening (which turns the other way) again and again
TURN_REST = 0.3
# rad: with a learned steering gait, a demanded turn under this is steered while swimming
# (``LearnedMotor.steer``: go-straight blended with steer-left/right at the weight whose
# calibrated rate turns it in ``STEER_SECONDS``); the sharp turn only for larger ones
STEER_MAX = 2.0
STEER_SECONDS = TURN_SECONDS  # s a steered turn is to take (the rate asked: turn over this)
# The fold guard: a fish asked to swim slower than GUARD_SPEED and bent under BEND_GUARD
# (``Demand.bend``, measured by the tank at the period's start) swims straight this period,
# any turn under way ended: a slow fish bent that far folds its tail within a period. A
# steady steer bends the shark to 0.85-0.88, so the guard then alternates steer and swim.
BEND_GUARD = 0.87
GUARD_SPEED = 0.3  # m/s


class LearnedLocomotion:
    """A learned motor skill: ``behavior.learned_motor.LearnedMotor`` calibrated on a repertoire.

    swim(speed) plays the blend of do-nothing and go-straight that swims the speed. With a
    learned steering gait in the repertoire (steer-left/right), a demanded turn under
    ``STEER_MAX`` rad is steered while swimming (``LearnedMotor.steer``: the swim blended with
    the steering gait at the weight whose calibrated rate turns the angle in ``TURN_SECONDS``,
    chosen afresh every control period). A larger demanded turn, or without a steering gait
    any of at least ``TURN_MIN`` rad, starts the sharp turn of that side
    (``LearnedMotor.turn_signal``: the learned sharp turn from its own start), played for as
    long as the calibration says it takes to turn the angle (at least one control period, at
    most ``TURN_BURST``), then back to the swim; a demand to turn the other way ends it at
    once, and the next turn or steer (either side) starts only after ``TURN_REST`` s of
    swimming. The fold guard: a fish asked under ``GUARD_SPEED`` and bent under ``BEND_GUARD``
    (``Demand.bend``) swims straight, any turn under way ended. Fins hold the pitch. Same
    interface as ``MotorLocomotion``; the state is the turn under way, so each fish has its own
    (``motor`` is shared by the fishes of one body and repertoire).
    """

    def __init__(self, body: Body, motor: LearnedMotor, righting: bool = True) -> None:
        self.body = body
        self.motor = motor
        self.righting = righting  # the righting reflex (fins' lean from the demand's roll)
        self.turning: tuple[int, float, float] | None = None  # side, start s, duration s
        self.last: tuple[int, float] = (0, -np.inf)  # the last turn's side and end (s)

    @property
    def top_speed(self) -> float:
        """Return the fastest the learned swim reaches (m/s)."""
        return self.motor.top_speed

    @property
    def turn_radius(self) -> float:
        """Return the radius (m) of the sharp turn from a cruise (the routines plan with the
        sharpest turn, not the wider full steer)."""
        return self.motor.turn_radius

    def activations(self, demand: Demand, times: np.ndarray) -> np.ndarray:
        """Return activations (T, A) for the demand over the control period at ``times`` (s):
        the gait (``plan``), the fins leaning by the righting reflex."""
        return learned_activations([self], [demand], times)[0]


SWIM, STEER, TURN = 0, 1, 2  # the kinds of gait a learned motor plays (``Gaits.kind``)


@dataclass(frozen=True)
class Gaits:
    """What a learned motor plays for D fishes over a control period, (D,) each: the swim of
    weight ``a``, a steer (``w`` of the steering gait of ``side``, 0 left, 1 right) or the
    sharp turn of ``side`` that started at ``start`` s and lasts ``duration`` s (then the
    swim), as ``kind`` says (``SWIM``, ``STEER``, ``TURN``)."""

    a: np.ndarray
    kind: np.ndarray
    side: np.ndarray
    w: np.ndarray
    start: np.ndarray
    duration: np.ndarray


def plan(fishes: list[LearnedLocomotion], demands: list[Demand], times: np.ndarray) -> Gaits:
    """Return the gaits D fishes that share a learned motor play for their demands over the
    control period at ``times`` (s), and keep each fish's turn under way (``turning``,
    ``last``): the rules of ``LearnedLocomotion``, over arrays."""
    motor, t0 = fishes[0].motor, float(times[0])
    # one array of every fish's numbers, read apart (one conversion, not one a column)
    speed, turn, bent = np.array([(d.speed, d.turn, d.bend) for d in demands], float).T
    was = [f.turning for f in fishes]
    on = np.array([t is not None for t in was])
    state = [(*(t or (0, 0, 0)), f.last[1]) for t, f in zip(was, fishes, strict=True)]
    side, start, duration, last = np.array(state, float).T
    guard = (bent < BEND_GUARD) & (speed < GUARD_SPEED)  # fold guard: straighten
    other_way = np.where(side == 0, turn < -TURN_MIN, turn > TURN_MIN)
    end = on & (guard | (t0 - start >= duration - 1e-9) | other_way)
    # the turn ends now, or where it was to end if earlier: the rest counts from there
    last = np.where(end, np.minimum(t0, start + duration), last)
    on &= ~end
    steer = bool(motor.steers) & (np.abs(turn) < STEER_MAX)
    rested = t0 - last >= TURN_REST - 1e-9
    steering = ~guard & ~on & steer & rested
    new = ~guard & ~on & ~steer & (np.abs(turn) >= TURN_MIN) & rested
    a = motor.swims(speed)
    turn_side, turn_for = motor.turns(turn)
    turn_for = np.minimum(
        np.maximum(turn_for, float(times[-1] - t0) + fishes[0].body.dt), TURN_BURST
    )
    side = np.where(new, turn_side, side).astype(int)
    start, duration = np.where(new, t0, start), np.where(new, turn_for, duration)
    on |= new
    steer_side, w = (
        motor.steers_at(turn / STEER_SECONDS, a) if steering.any() else (side, np.zeros_like(a))
    )
    for k in np.flatnonzero(end | new).tolist():
        f = fishes[k]
        if end[k]:
            f.turning, f.last = None, (was[k][0], float(last[k]))
        if new[k]:
            f.turning = (int(side[k]), t0, float(duration[k]))
    kind = np.where(on, TURN, np.where(steering, STEER, SWIM))
    return Gaits(
        a, kind, np.where(steering, steer_side, side), np.where(steering, w, 0.0), start, duration
    )


def learned_activations(
    fishes: list[LearnedLocomotion], demands: list[Demand], times: np.ndarray
) -> np.ndarray:
    """Return activations (D, T, A) of D fishes that share a learned motor for their demands
    over the control period at ``times`` (s): each fish's gait (``LearnedLocomotion.plan``,
    which keeps its turn under way), the gaits blended for all at once, the fins at each
    demand's pitch leaning by the righting reflex."""
    motor = fishes[0].motor
    g = plan(fishes, demands, times)
    swim = motor.swim_raws(times, g.a)
    u = swim.copy()
    for side in (0, 1):
        rows = np.flatnonzero((g.kind == STEER) & (g.side == side))
        if len(rows):
            u[rows] = motor.steer_raws(side, times, swim[rows], g.w[rows])
    turns: dict[tuple[int, float], np.ndarray] = {}  # the sharp turns that started together
    for k in np.flatnonzero(g.kind == TURN).tolist():
        key = (int(g.side[k]), float(g.start[k]))
        if key not in turns:
            turns[key] = motor.bases[2 + key[0]].raw(times - key[1])
        u[k] = LEARNED_STRENGTH * turns[key]
        u[k] += (1 - LEARNED_STRENGTH) * swim[k]
        after = times - key[1] >= g.duration[k]
        u[k, after] = swim[k, after]  # the swim once the turn is over
    lean = [
        righting(d.roll, d.roll_rate) if f.righting else np.nan
        for f, d in zip(fishes, demands, strict=True)
    ]
    return motor.fins(u, [d.fin_pitch for d in demands], np.array(lean, float))


_LEARNED_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # body -> {dir: motor}


@lru_cache(maxsize=64)
def _resolved(directory: str, cwd: str) -> str:
    """Return the absolute path of ``directory`` (relative to ``cwd``, the working directory
    it was named in), links resolved: once for a tank's thousand fishes of one species."""
    return str(Path(cwd, directory).resolve())


def learned_motor(body: Body, directory: str | Path) -> LearnedMotor:
    """Return ``LearnedMotor.calibrate`` on the repertoire in ``directory`` (checked against
    the body), cached per body object and directory for the process (a tank of one species
    calibrates once; an edited body is another object, calibrated afresh)."""
    where = _resolved(str(directory), os.getcwd())
    cached = _LEARNED_CACHE.setdefault(body, {})
    if where not in cached:
        cached[where] = LearnedMotor.calibrate(body, Repertoire.load(directory, body))
    return cached[where]
