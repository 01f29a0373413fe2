"""The motor layer of the aquarium: motor demands (speed, turn, pitch) in, muscle activations out.

``Locomotion`` is the small interface the behaviour routines call; ``WaveLocomotion`` is the
built-in motor skill: the body's own travelling wave (``control.wave_controller``), its swing
scaled by the demanded speed and a left/right bias added to the muscles by the demanded turn
(left muscles shortened more turn the fish left). The parameterised swim(speed)/turn(angle)
controllers of ``behavior.motor`` can replace it behind the same interface.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from zoetic.bodies import Body
from zoetic.control import steered_wave


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


class WaveLocomotion:
    """The built-in motor skill: a travelling wave, amplitude for speed, a bias for turning.

    max_speed: speed (m/s) at full amplitude; turn_gain: bias per radian of turn wanted;
    max_bias: the largest bias; min_amplitude: the wave never stops (a fish keeps steerage).
    Fins (if the body has any) take their held level + pitch / pi (``control.steered_wave``).
    """

    def __init__(self, body: Body, frequency: float | None = None, max_speed: float = 0.36,
                 turn_gain: float = 1.0, max_bias: float = 0.5,
                 min_amplitude: float = 0.45) -> None:  # fmt: skip
        self.body = body
        self.frequency = float(frequency or body.wave_frequency)
        self.max_speed = float(max_speed)
        self.turn_gain, self.max_bias, self.min_amplitude = turn_gain, max_bias, min_amplitude

    def activations(self, demand: Demand, times: np.ndarray) -> np.ndarray:
        """Return activations (T, A): the wave at the demanded amplitude plus the turn bias."""
        amp = float(np.clip(demand.speed / self.max_speed, self.min_amplitude, 1.0))
        bias = float(np.clip(self.turn_gain * demand.turn, -self.max_bias, self.max_bias))
        fins = float(np.clip(demand.pitch, -1.5, 1.5)) / np.pi
        return steered_wave(self.body, times, amp, bias, fins, self.frequency)
