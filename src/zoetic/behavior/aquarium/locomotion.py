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
from typing import Protocol

import numpy as np

from zoetic.behavior.motor import WaveMotor
from zoetic.bodies import Body

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
