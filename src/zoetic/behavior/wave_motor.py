"""The built-in motor controllers: swim / turn / pitch from the body's own travelling wave.

Without a learned repertoire a fish swims by its body's wave (``control.steered_wave``), its
swing scaled by an amplitude and a left/right bias added to the muscles; ``WaveMotor`` is that
wave calibrated once per body and frequency, so that swim(speed) and turn(angle) mean what
they say.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from zoetic.behavior.motor import (
    fin_activations,
    fin_rows,
    grid_rates,
    interps,
)
from zoetic.bodies import Body
from zoetic.learning.objective import heading_angles
from zoetic.physics import simulate

WAVE_AMPLITUDES = np.array([0.2, 0.4, 0.6, 0.8, 1.0])
WAVE_BIASES = np.array([0.0, 0.1, 0.2, 0.3, 0.4, 0.5])
WAVE_SETTLE = 2.0  # s from rest before the speed and turning rate are measured
WAVE_MEASURE = 3.0  # s over which they are measured
# calibrations per body object (an edited body is another object), then per frequency
_WAVE_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


@dataclass(frozen=True)
class WaveMotor:
    """swim / turn / pitch for one body from its own steered wave, calibrated (``calibrate``).

    speeds (K,): m/s of the straight wave at each of ``WAVE_AMPLITUDES``; rates (K, J):
    rad/s (left positive) of the wave at each amplitude with each of ``WAVE_BIASES`` (the
    rate at a negative bias is the mirror image).
    """

    body: Body
    frequency: float
    speeds: np.ndarray
    rates: np.ndarray

    @classmethod
    def calibrate(cls, body: Body, frequency: float | None = None) -> WaveMotor:
        """Measure the wave's speed per amplitude and turning rate per (amplitude, bias) in one
        batched run from rest (settled ``WAVE_SETTLE`` s, measured over ``WAVE_MEASURE`` s);
        cached per body and frequency for the process."""
        freq = float(frequency or body.wave_frequency)
        cached = _WAVE_CACHE.setdefault(body, {})
        if freq in cached:
            return cached[freq]
        from zoetic.control import steered_wave

        steps = int(round((WAVE_SETTLE + WAVE_MEASURE) / body.dt))
        times = np.arange(steps) * body.dt
        grid = [(a, b) for a in WAVE_AMPLITUDES for b in WAVE_BIASES]
        acts = np.stack([steered_wave(body, times, a, b, 0.0, freq) for a, b in grid])
        every = max(1, int(round(0.05 / body.dt)))
        tr = simulate(body, acts, record_every=every)
        t = np.arange(tr.positions.shape[1]) * every * body.dt
        sel = t >= WAVE_SETTLE
        com = tr.com(body)[:, sel][..., [0, 2]]
        heading = heading_angles(body, tr.positions)[:, sel]
        shape = (len(WAVE_AMPLITUDES), len(WAVE_BIASES))
        speed, rate = grid_rates(com, heading, t[sel], shape)
        motor = cls(body, freq, speed[:, 0].copy(), rate)
        cached[freq] = motor
        return motor

    @property
    def top_speed(self) -> float:
        """Return the fastest straight speed (m/s) the wave reaches."""
        return float(self.speeds.max())

    @cached_property
    def _tables(self) -> tuple[np.ndarray, np.ndarray]:
        """The speeds sorted (m/s) and their amplitudes: what ``interps`` reads a swim by."""
        order = np.argsort(self.speeds)
        return self.speeds[order], WAVE_AMPLITUDES[order]

    def swim(self, speed: float) -> float:
        """Return the amplitude that swims ``speed`` m/s (clipped to the calibrated range)."""
        return float(interps(np.array([speed], float), *self._tables)[0])

    def turn(
        self, angle: float, seconds: float = 1.0, amplitude: float = 1.0
    ) -> tuple[float, float]:
        """Return (amplitude, bias) turning ``angle`` rad (left positive) in ``seconds`` s at
        least at ``amplitude``: ``turns`` of one angle."""
        amp, bias = self.turns(np.array([angle], float), seconds, np.array([amplitude], float))
        return float(amp[0]), float(bias[0])

    def fins(self, pitch: float, lean: float = 0.0) -> np.ndarray:
        """Return (A,) what to add to each fin's held (level) activation to pitch it ``pitch``
        rad, the left fins ``lean`` rad more and the right ones less: ``fins_many`` of one."""
        return self.fins_many(np.array([pitch], float), np.array([lean], float))[0]

    @cached_property
    def _fin_rows(self) -> list[tuple[int, float, float, float]]:
        """``fin_rows(body)``, kept (``fins`` runs once a fish and control period)."""
        return fin_rows(self.body)

    def activations(
        self,
        times: np.ndarray,
        speed: float,
        turn: float = 0.0,
        pitch: float = 0.0,
        seconds: float = 1.0,
    ) -> np.ndarray:
        """Return activations (T, A): swim at ``speed`` m/s while turning ``turn`` rad in
        ``seconds`` s, fins pitched ``pitch`` rad (nose up positive)."""
        from zoetic.control import steered_wave

        amp, bias = self.turn(turn, seconds, self.swim(speed))
        return steered_wave(self.body, times, amp, bias, self.fins(pitch), self.frequency)

    def activations_many(
        self, times: np.ndarray, speeds, turns, pitches, seconds: float = 1.0, leans=None
    ) -> np.ndarray:
        """Return activations (D, T, A) of ``activations`` for D (speed, turn, pitch) demands
        at once (``leans``: each one's fin lean, ``fins``; default none): one
        ``steered_wave`` evaluation broadcast over the demands."""
        from zoetic.control import steered_wave

        speeds, turns = np.asarray(speeds, float), np.asarray(turns, float)
        amp, bias = self.turns(turns, seconds, interps(speeds, *self._tables))
        pitches = np.asarray(pitches, float)
        fins = self.fins_many(pitches, np.zeros_like(pitches) if leans is None else leans)
        return steered_wave(
            self.body, times, amp[:, None, None], bias[:, None, None], fins[:, None], self.frequency
        )

    def fins_many(self, pitch: np.ndarray, lean: np.ndarray) -> np.ndarray:
        """Return (D, A) what to add to each fin's held (level) activation to pitch D fishes'
        fins ``pitch`` (D,) rad, the left fins ``lean`` (D,) rad more and the right ones less
        (``fin_activations`` of the angles less those of level; 0 on the muscles and without
        fins)."""
        pitch, lean = np.asarray(pitch, float), np.asarray(lean, float)
        out = np.zeros((len(pitch), self.body.n_actuators))
        level = dict(fin_activations(self._fin_rows, np.zeros_like(pitch), np.zeros_like(lean)))
        for act, v in fin_activations(self._fin_rows, pitch, lean):
            out[:, act] = v - level[act]
        return out

    def turns(
        self, angle: np.ndarray, seconds: float, amplitude: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Return the amplitudes and biases (D,) turning D ``angle`` (D,) rad (left positive) in
        ``seconds`` s at least at ``amplitude`` (D,): the smallest bias whose rate turns it in
        time; a wave too weak to turn that fast beats harder (up to amplitude 1), beyond that
        the sharpest turn. The rate rows are non-decreasing (``grid_rates``), so ``interps``
        of each fish's row finds its bias."""
        need = np.abs(angle) / max(seconds, 1e-9)
        amps, biases, rates = WAVE_AMPLITUDES, WAVE_BIASES, self.rates
        reach = rates[:, -1]  # the sharpest turn (rad/s) at each amplitude
        amp = np.minimum(np.maximum(amplitude, amps[0]), 1.0)
        # too weak to turn that fast: the smallest amplitude whose sharpest turn is (or full)
        ok = reach[None, :] >= need[:, None]
        least = np.where(ok.any(axis=1), amps[np.argmax(ok, axis=1)], 1.0)
        amp = np.where(need > interps(amp, amps, reach), np.maximum(amp, least), amp)
        k = np.clip(np.searchsorted(amps, amp, side="left") - 1, 0, len(amps) - 2)
        w = (amp - amps[k]) / (amps[k + 1] - amps[k])
        row = (1 - w)[:, None] * rates[k] + w[:, None] * rates[k + 1]
        bias = np.where(row[:, -1] > row[:, 0], interps(need, row, biases), 0.0)
        return amp, np.where(angle >= 0, bias, -bias)

    def summary(self) -> dict:
        """Return the calibration tables (speeds in m/s, turning rates in deg/s)."""
        return {
            "frequency_hz": self.frequency,
            "amplitudes": WAVE_AMPLITUDES.tolist(),
            "biases": WAVE_BIASES.tolist(),
            "speed_m_s": self.speeds.round(3).tolist(),
            "turn_deg_s": np.degrees(self.rates).round(1).tolist(),
        }


# ============================================================ learned motor controllers
# With a learned repertoire, as the artificial fish's motor controllers: swim(speed) plays the
