"""The motor layer of the aquarium: motor demands (speed, turn, pitch) in, muscle activations out.

``Locomotion`` is the small interface the behaviour routines' demands go through;
``MotorLocomotion`` is the built-in motor skill: the parameterised controllers of
``behavior.motor.WaveMotor`` (swim at a speed, turn by an angle, pitch with the fins), the
body's own steered wave calibrated once per body and frequency, so that a demanded speed is
the speed swum and a demanded turn the angle turned (in ``TURN_SECONDS``, or as fast as the
body can).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np

from zoetic.behavior.motor import WEIGHTS, MotorControllers, WaveMotor, blend, fin_activation
from zoetic.behavior.repertoire import Repertoire
from zoetic.bodies import Body
from zoetic.control.abstract import AbstractController

TURN_SECONDS = 1.0  # s a demanded heading change is to take (the routines re-aim every period)
MAX_PITCH = 0.5  # rad: the largest fin pitch a routine may ask for


@dataclass(frozen=True)
class Demand:
    """What a behaviour routine asks of the motor system: forward speed (m/s), the heading
    change wanted (rad, left positive) and the pitch wanted (rad, nose up positive)."""

    speed: float
    turn: float = 0.0
    pitch: float = 0.0


class Locomotion(Protocol):
    """Turns motor demands into activations."""

    def activations(self, demand: Demand, times: np.ndarray) -> np.ndarray:
        """Return activations (T, A) for the times (T,) s of a control period."""
        ...


class MotorLocomotion:
    """The built-in motor skill: ``WaveMotor.calibrate(body, frequency)``'s swim, turn and
    pitch controllers (``turn_seconds``: the time a demanded turn is to take)."""

    def __init__(self, body: Body, frequency: float | None = None,
                 turn_seconds: float = TURN_SECONDS) -> None:  # fmt: skip
        self.body = body
        self.motor = WaveMotor.calibrate(body, frequency)
        self.turn_seconds = float(turn_seconds)

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
            times, [d.speed for d in demands], [d.turn for d in demands],
            [min(max(d.pitch, -MAX_PITCH), MAX_PITCH) for d in demands], self.turn_seconds,
        )  # fmt: skip


TURN_DEADBAND = 0.02  # rad: a smaller demanded turn swims straight (the blend's rate is ~0 there)


class LearnedLocomotion:
    """A learned motor skill: ``behavior.motor.MotorControllers`` calibrated on a repertoire
    (swim(speed) blends do-nothing and go-straight; turn(angle) blends go-straight and the sharp
    turn of that side; pitch holds the fins at the angle's activation on top of the gait).

    Same interface as ``MotorLocomotion``; ``motor`` is the MotorControllers (fishes sharing
    one are batched by the tank).
    """

    def __init__(self, body: Body, motor: MotorControllers,
                 turn_seconds: float = TURN_SECONDS) -> None:  # fmt: skip
        self.body = body
        self.motor = motor
        self.turn_seconds = float(turn_seconds)
        self.has_fins = len(body.fin_actuator) > 0

    @property
    def top_speed(self) -> float:
        """Return the fastest the learned swim reaches (m/s)."""
        return float(self.motor.speeds.max())

    @property
    def turn_radius(self) -> float:
        """Return the radius (m) of the sharpest learned turn."""
        rate = float(np.radians(np.abs(self.motor.rates).max()))
        return float(self.motor.speeds[-1] / max(rate, 1e-6))

    def controller(self, demand: Demand) -> AbstractController:
        """Return the blended controller meeting the demand (turn first, else swim; fins at
        the pitch when the body has fins)."""
        if abs(demand.turn) > TURN_DEADBAND:
            c = self.motor.rep.controllers
            side = "sharp-turn-left" if demand.turn > 0 else "sharp-turn-right"
            gait = blend(c["go-straight"], c[side], self.turn_weight(demand.turn))
        else:
            gait = self.motor.swim(demand.speed)
        pitch = min(max(demand.pitch, -MAX_PITCH), MAX_PITCH)
        if not self.has_fins or pitch == 0.0:
            return gait
        offset, amp = gait.offset.copy(), gait.amp.copy()
        for k, a in fin_activation(self.body, pitch).items():
            offset[k], amp[k] = a, 0.0
        return AbstractController(gait.animal, gait.actuators, offset, gait.freq, amp,
                                  gait.phase, gait.period)  # fmt: skip

    def turn_weight(self, angle: float) -> float:
        """Return the blend weight of go-straight and the sharp turn that turns ``angle`` rad
        in ``turn_seconds`` (the sharp turn itself beyond its rate).

        A learned repertoire's blends need not turn monotonically with the weight (the
        calibration of a trained shark: -4.5, -20.6, -0.4, -7.2, 26.5, 38.3 deg/s), so only the
        weights that turn left of go-straight faster than every smaller weight are used (right
        turns mirror left ones): between two such neighbours the weight is interpolated; where
        a wrong-way weight lies between them, the faster one is taken, which turns more than
        asked (the routines re-aim every period) but never the wrong way.
        """
        extra = self.motor.rates - self.motor.rates[0]
        need = abs(float(np.degrees(angle))) / self.turn_seconds
        records = [0]
        for k in range(1, len(extra)):
            if extra[k] > extra[records[-1]]:
                records.append(k)
        for a, b in zip(records, records[1:], strict=False):
            if need <= extra[b]:
                if b - a > 1:
                    return float(WEIGHTS[b])
                f = (need - extra[a]) / (extra[b] - extra[a])
                return float(WEIGHTS[a] + max(f, 0.0) * (WEIGHTS[b] - WEIGHTS[a]))
        return float(WEIGHTS[records[-1]]) if len(records) > 1 else 1.0

    def activations(self, demand: Demand, times: np.ndarray) -> np.ndarray:
        """Return activations (T, A) of the demand's controller at the (absolute) times."""
        return self.controller(demand).sample(times)

    def activations_many(self, demands: list[Demand], times: np.ndarray) -> np.ndarray:
        """Return activations (D, T, A) for several demands."""
        return np.stack([self.activations(d, times) for d in demands])


_LEARNED_CACHE: dict[tuple, MotorControllers] = {}


def learned_motor(body: Body, directory: str | Path) -> MotorControllers:
    """Return ``MotorControllers.calibrate`` on the repertoire in ``directory`` (checked
    against the body), cached per body and directory for the process (a tank of one species
    calibrates once)."""
    where = str(Path(directory).resolve())
    key = (body.name, body.n_nodes, body.n_actuators, round(float(body.dt), 9), where)
    if key not in _LEARNED_CACHE:
        _LEARNED_CACHE[key] = MotorControllers.calibrate(body, Repertoire.load(directory, body))
    return _LEARNED_CACHE[key]
