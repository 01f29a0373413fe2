"""Parameterised motor controllers built from a learned repertoire: swim(speed), turn(angle),
pitch(angle), as the artificial fish has (Tu & Terzopoulos 94, section 5).

An abstracted entry is a sum of cosines per actuator, so a blend of two entries,
(1 - w) u_a + w u_b, is again one (offsets mixed, modes of both kept with scaled amplitudes):
``blend``. ``MotorControllers.calibrate`` measures, in one batched simulation from rest, the
speed of blends of do-nothing and go-straight and the turning rate of blends of go-straight
and the sharp turns; ``swim`` and ``turn`` invert those tables by interpolation. ``pitch``
holds the pectoral fins (actuators of kind "fin") at the activation of an angle on top of the
go-straight gait. Every result is an ordinary AbstractController: playable, savable, and an
entry a repertoire (and so greedy tracking) can use (``motor_repertoire``).
"""

from __future__ import annotations

import weakref
from bisect import bisect_left, bisect_right
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.tracking import body_length
from zoetic.bodies import Body
from zoetic.control.abstract import AbstractController
from zoetic.errors import ZoeticError
from zoetic.learning.objective import heading_angles
from zoetic.physics import simulate

WEIGHTS = np.linspace(0.0, 1.0, 6)
CALIBRATION_SECONDS = 3.0


def blend(a: AbstractController, b: AbstractController, w: float) -> AbstractController:
    """Return the controller playing (1 - w) a + w b (w in [0, 1])."""
    if tuple(a.actuators) != tuple(b.actuators):
        raise ZoeticError("blend: the two controllers drive different actuators")
    w = float(np.clip(w, 0.0, 1.0))
    return AbstractController(
        a.animal, a.actuators, (1 - w) * a.offset + w * b.offset,
        np.concatenate([a.freq, b.freq], axis=1), np.concatenate([(1 - w) * a.amp, w * b.amp], 1),
        np.concatenate([a.phase, b.phase], axis=1), max(a.period, b.period),
    )  # fmt: skip


def fin_rows(body: Body) -> list[tuple[int, float, float, float]]:
    """Return each fin's (actuator, angle at activation 0, angle at 1, side) as Python numbers;
    side is 1 for a fin on the left, -1 on the right, 0 on neither (its actuator's side)."""
    sides = {"left": 1.0, "right": -1.0}
    return [(int(a), float(lo), float(hi), sides.get(body.actuator_side[int(a)], 0.0))
            for a, (lo, hi) in zip(body.fin_actuator.tolist(), body.fin_angle.tolist(),
                                   strict=True)]  # fmt: skip


def fin_activation(body: Body, angle: float, rows: list[tuple[int, float, float, float]]
                   | None = None, lean: float = 0.0) -> dict[int, float]:  # fmt: skip
    """Return, per fin actuator, the activation that sets its fins to ``angle`` rad (clipped),
    the left fins ``lean`` rad more and the right ones ``lean`` less (``righting``: a
    differential pitch rolls the fish); ``rows``: ``fin_rows(body)`` when kept (a caller many
    times a second)."""
    out = {}
    for act, lo, hi, side in fin_rows(body) if rows is None else rows:
        a = angle + side * lean
        # np.clip's result for a scalar, without its per-call overhead
        out[act] = min(max(float((a - lo) / (hi - lo)), 0.0), 1.0) if hi != lo else 0.0
    return out


# The righting reflex. The water model has no restoring roll moment (a fish laid on its side
# stays there), but the pectoral fins pitched differentially (the left fin ``lean`` rad nose
# up, the right one ``lean`` nose down) roll a swimming fish (its right side down): on the zoo
# shark swimming at 0.3 m/s from rest, 0.25 rad of lean rolls it 20 degrees in 3 s, 0.5 rad
# 33 degrees (0.1 m/s: 4 and 6 degrees; the moment grows with the speed squared). Fed back as
# a PD on the roll (``righting``), a fish started 45 degrees rolled is upright (under 5
# degrees) 4 s later at 0.3 m/s, with no overshoot beyond 3 degrees (gains 4 and 2; 1 and 0:
# 17 degrees of overshoot; without the reflex it stays at 45 degrees).
RIGHTING_GAIN = 4.0  # rad of lean per rad of roll
RIGHTING_DAMPING = 2.0  # rad of lean per rad/s of roll rate
RIGHTING_MAX = 0.5  # rad: the most lean (the zoo fishes' fins pitch +-0.5 rad)


def righting(roll: float, roll_rate: float = 0.0) -> float:
    """Return the fins' lean (rad, ``fin_activation``) that rights a fish rolled ``roll`` rad
    (``tasks.terms.roll_angle``: positive with its left side down) turning at ``roll_rate``
    rad/s: a PD on the roll, clipped to +-``RIGHTING_MAX``."""
    lean = RIGHTING_GAIN * roll + RIGHTING_DAMPING * roll_rate
    return min(max(lean, -RIGHTING_MAX), RIGHTING_MAX)


@dataclass
class MotorControllers:
    """swim / turn / pitch for one body, calibrated on one repertoire's entries."""

    body: Body
    rep: Repertoire
    speeds: np.ndarray  # (W,) m/s of blend(do-nothing, go-straight, w) over WEIGHTS
    rates: np.ndarray  # (W,) deg/s of blend(go-straight, sharp-turn-left, w) over WEIGHTS

    @classmethod
    def calibrate(cls, body: Body, rep: Repertoire) -> MotorControllers:
        """Measure the blends' speeds and turning rates (one batched run from rest)."""
        need = ("do-nothing", "go-straight", "sharp-turn-left", "sharp-turn-right")
        missing = [n for n in need if n not in rep.controllers]
        if missing:
            raise ZoeticError(f"motor controllers need the entries {missing} in the repertoire")
        c = rep.controllers
        ctrls = [blend(c["do-nothing"], c["go-straight"], w) for w in WEIGHTS]
        ctrls += [blend(c["go-straight"], c["sharp-turn-left"], w) for w in WEIGHTS]
        steps = int(round(CALIBRATION_SECONDS / body.dt))
        tr = simulate(body, np.stack([k.table(steps, body.dt) for k in ctrls]), record_every=10)
        com = tr.com(body)
        dist = np.linalg.norm(np.diff(com[..., [0, 2]], axis=1), axis=-1).sum(axis=1)
        heading = np.degrees(heading_angles(body, tr.positions))
        n = len(WEIGHTS)
        return cls(body, rep, dist[:n] / CALIBRATION_SECONDS,
                   (heading[n:, -1] - heading[n:, 0]) / CALIBRATION_SECONDS)  # fmt: skip

    def swim(self, speed: float) -> AbstractController:
        """Return a gait swimming about ``speed`` m/s (clipped to what the entries reach)."""
        order = np.argsort(self.speeds)
        w = np.interp(speed, self.speeds[order], WEIGHTS[order])
        c = self.rep.controllers
        return blend(c["do-nothing"], c["go-straight"], float(w))

    def turn(self, angle: float, seconds: float = 1.5) -> tuple[AbstractController, float]:
        """Return (controller, duration s) turning ``angle`` degrees (positive left).

        The blend whose rate turns ``angle`` in ``seconds``; beyond the sharp turn's rate the
        sharp turn itself, for as long as it needs.
        """
        rates = np.abs(self.rates)
        need = abs(angle) / seconds
        order = np.argsort(rates)
        w = float(np.interp(need, rates[order], WEIGHTS[order]))
        top = float(rates.max())
        duration = seconds if need <= top else abs(angle) / max(top, 1e-9)
        c = self.rep.controllers
        side = "sharp-turn-left" if angle >= 0 else "sharp-turn-right"
        return blend(c["go-straight"], c[side], w), duration

    def pitch(self, angle: float, speed: float | None = None) -> AbstractController:
        """Return the gait (``swim(speed)``, default go-straight) with the fins at ``angle`` rad
        (positive: nose up)."""
        if len(self.body.fin_actuator) == 0:
            raise ZoeticError(f"the {self.body.name} has no fins to pitch with")
        gait = self.rep.controllers["go-straight"] if speed is None else self.swim(speed)
        offset, amp = gait.offset.copy(), gait.amp.copy()
        for k, a in fin_activation(self.body, angle).items():
            offset[k], amp[k] = a, 0.0
        return AbstractController(
            gait.animal, gait.actuators, offset, gait.freq, amp, gait.phase, gait.period
        )

    def summary(self) -> dict:
        """Return the calibration tables (speeds in m/s and BL/s, rates in deg/s)."""
        bl = body_length(self.body)
        return {
            "weights": WEIGHTS.round(2).tolist(),
            "speed_m_s": self.speeds.round(3).tolist(),
            "speed_bl_s": (self.speeds / bl).round(3).tolist(),
            "turn_deg_s": self.rates.round(1).tolist(),
        }


def motor_repertoire(motor: MotorControllers, speeds=(), turns=(), pitches=()) -> Repertoire:
    """Return the repertoire with added parameterised entries ("swim-0.5", "turn-45",
    "pitch-0.3", ...), e.g. for greedy tracking to choose among."""
    rep = Repertoire(motor.rep.animal, motor.rep.actuators)
    for name in motor.rep.names:
        rep.add(name, motor.rep.controllers[name], motor.rep.durations[name],
                **motor.rep.info.get(name, {}))  # fmt: skip
    period = motor.rep.durations["go-straight"]
    for v in speeds:
        rep.add(f"swim-{v:g}", motor.swim(v), period, source="motor")
    for a in turns:
        ctrl, duration = motor.turn(a)
        rep.add(f"turn-{a:g}", ctrl, duration, source="motor")
    for p in pitches:
        rep.add(f"pitch-{p:g}", motor.pitch(p), period, source="motor")
    return rep


# ============================================================ the built-in motor controllers
# Without a learned repertoire: the body's own travelling wave (``control.steered_wave``), its
# swing scaled by an amplitude and a left/right bias added to the muscles, calibrated once per
# body and frequency so that swim(speed) and turn(angle) mean what they say.

WAVE_AMPLITUDES = np.array([0.2, 0.4, 0.6, 0.8, 1.0])
WAVE_BIASES = np.array([0.0, 0.1, 0.2, 0.3, 0.4, 0.5])
WAVE_SETTLE = 2.0  # s from rest before the speed and turning rate are measured
WAVE_MEASURE = 3.0  # s over which they are measured
# calibrations per body object (an edited body is another object), then per settings
_WAVE_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_AMPS, _BIASES = WAVE_AMPLITUDES.tolist(), WAVE_BIASES.tolist()


def _interp(x: float, xp: list, fp: list) -> float:
    """Return ``np.interp(x, xp, fp)`` for a float and short lists (xp non-decreasing)."""
    if x <= xp[0]:
        return fp[0]
    if x >= xp[-1]:
        return fp[-1]
    j = bisect_right(xp, x) - 1  # xp[j] <= x < xp[j + 1]
    return (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j]) * (x - xp[j]) + fp[j]


def grid_rates(com: np.ndarray, heading: np.ndarray, t: np.ndarray,
               shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Return the speed (m/s: path length over the window) and turning rate (rad/s, less the
    row's first column, at least 0, made non-decreasing along each row) of a grid of runs:
    com (K, R, 2) and heading (K, R) recorded at times t (R,) over the window, K runs laid out
    as ``shape`` (rows: a swim level; columns: a rising steer)."""
    span = t[-1] - t[0]
    speed = (np.linalg.norm(np.diff(com, axis=1), axis=-1).sum(1) / span).reshape(shape)
    rate = ((heading[:, -1] - heading[:, 0]) / span).reshape(shape)
    return speed, np.maximum.accumulate(np.maximum(rate - rate[:, :1], 0.0), axis=1)


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
    def _tables(self) -> tuple[list, list, list, list]:
        """The tables as Python lists (the per-demand scalar work skips numpy's overhead):
        speeds sorted, their amplitudes, the sharpest turn per amplitude, the rate rows."""
        order = np.argsort(self.speeds)
        return (self.speeds[order].tolist(), WAVE_AMPLITUDES[order].tolist(),
                self.rates[:, -1].tolist(), self.rates.tolist())  # fmt: skip

    def swim(self, speed: float) -> float:
        """Return the amplitude that swims ``speed`` m/s (clipped to the calibrated range)."""
        speeds, amps = self._tables[0], self._tables[1]
        return _interp(float(speed), speeds, amps)

    def turn(self, angle: float, seconds: float = 1.0, amplitude: float = 1.0
             ) -> tuple[float, float]:  # fmt: skip
        """Return (amplitude, bias) turning ``angle`` rad (left positive) in ``seconds`` s at
        least at ``amplitude``: the smallest bias whose rate turns it in time; a wave too weak
        to turn that fast beats harder (up to amplitude 1), beyond that the sharpest turn."""
        need = abs(angle) / max(seconds, 1e-9)
        amps, biases = _AMPS, _BIASES
        amp = min(max(float(amplitude), amps[0]), 1.0)
        reach, rates = self._tables[2], self._tables[3]
        if need > _interp(amp, amps, reach):
            # the smallest amplitude whose sharpest turn is fast enough (or full amplitude)
            ok = [a for a, r in zip(amps, reach, strict=True) if r >= need]
            amp = max(amp, ok[0] if ok else 1.0)
        k = min(max(bisect_left(amps, amp) - 1, 0), len(amps) - 2)
        w = (amp - amps[k]) / (amps[k + 1] - amps[k])
        row = [(1 - w) * a + w * b for a, b in zip(rates[k], rates[k + 1], strict=True)]
        bias = _interp(need, row, biases) if row[-1] > row[0] else 0.0
        return amp, bias if angle >= 0 else -bias

    def fins(self, pitch: float, lean: float = 0.0) -> np.ndarray:
        """Return (A,) what to add to each fin's held (level) activation to pitch it ``pitch``
        rad, the left fins ``lean`` rad more and the right ones less (``fin_activation`` of
        the angle less that of level; 0 on the muscles and without fins)."""
        out = np.zeros(self.body.n_actuators)
        level = fin_activation(self.body, 0.0, self._fin_rows)
        for act, v in fin_activation(self.body, pitch, self._fin_rows, lean).items():
            out[act] = v - level[act]
        return out

    @cached_property
    def _fin_rows(self) -> list[tuple[int, float, float, float]]:
        """``fin_rows(body)``, kept (``fins`` runs once a fish and control period)."""
        return fin_rows(self.body)

    def activations(self, times: np.ndarray, speed: float, turn: float = 0.0,
                    pitch: float = 0.0, seconds: float = 1.0) -> np.ndarray:  # fmt: skip
        """Return activations (T, A): swim at ``speed`` m/s while turning ``turn`` rad in
        ``seconds`` s, fins pitched ``pitch`` rad (nose up positive)."""
        from zoetic.control import steered_wave

        amp, bias = self.turn(turn, seconds, self.swim(speed))
        return steered_wave(self.body, times, amp, bias, self.fins(pitch), self.frequency)

    def activations_many(self, times: np.ndarray, speeds, turns, pitches,
                         seconds: float = 1.0, leans=None) -> np.ndarray:  # fmt: skip
        """Return activations (D, T, A) of ``activations`` for D (speed, turn, pitch) demands
        at once (``leans``: each one's fin lean, ``fins``; default none): one
        ``steered_wave`` evaluation broadcast over the demands."""
        from zoetic.control import steered_wave

        ab = [self.turn(t, seconds, self.swim(v)) for v, t in zip(speeds, turns, strict=True)]
        amp = np.array([a for a, _ in ab])[:, None, None]
        bias = np.array([b for _, b in ab])[:, None, None]
        leans = [0.0] * len(pitches) if leans is None else leans
        fins = np.array([self.fins(p, q) for p, q in zip(pitches, leans, strict=True)])[:, None]
        return steered_wave(self.body, times, amp, bias, fins, self.frequency)

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
# blend (1 - a) do-nothing + a go-straight (a blend of abstracted entries is linear in their
# signals before the clip to [0, 1]); turn(angle) plays the learned sharp turn of that side from
# its own start (``LEARNED_STRENGTH`` of it on the swim gait) for as long as it takes to turn
# the angle (the turn was learned as a manoeuvre from its start; played on as a periodic gait
# it hardly turns); pitch holds the fins.
# Calibrated once per body and repertoire: the speed of each swim weight, and the angle each
# side's sharp turn has turned when stopped after each of a few durations.

LEARNED_SWIM = np.array([0.05, 0.1, 0.2, 0.35, 0.5, 1.0])  # swim weights a
LEARNED_TURN = np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.75, 1.0, 1.5])  # s the sharp turn is played
LEARNED_SETTLE = 2.0  # s of swimming (at ``LEARNED_CRUISE``) before a turn, or the measure
LEARNED_AFTER = 1.5  # s of swimming after a turn (the new heading is measured over the last 1 s)
LEARNED_CRUISE = 0.1  # the swim weight the turns are calibrated from
LEARNED_STRENGTH = 1.0  # the sharp turn's share of a turn's blend (the swim gait the rest)
LEARNED_BASES = ("do-nothing", "go-straight", "sharp-turn-left", "sharp-turn-right")
# The steer while swimming, when the repertoire has a learned steering gait (the aquarium's
# "steer-left" task and its mirror): the blend (1 - w) swim(a) + w steer of the two periodic
# gaits, both at the clock's time, so a demand can change w every control period; its turning
# rate is calibrated per swim weight a (``LEARNED_SWIM``) and steer weight w (``STEER_WEIGHTS``)
# from rest, over ``STEER_MEASURE`` s after ``LEARNED_SETTLE`` s.
LEARNED_STEER = ("steer-left", "steer-right")
STEER_WEIGHTS = np.array([0.0, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0])
STEER_MEASURE = 2.0
_LEARNED_MOTOR_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # as _WAVE_CACHE


@dataclass(frozen=True)
class LearnedMotor:
    """swim / turn / pitch for one body from a learned repertoire's do-nothing, go-straight
    and sharp turns, calibrated (``calibrate``).

    speeds (S,): m/s of the swim gait at each of ``LEARNED_SWIM``; turned (2, D): rad the sharp
    turn left (row 0, positive) and right (row 1, negative) has turned when played for each of
    ``LEARNED_TURN`` s from a cruise (made monotonic: a longer turn never turns less).
    """

    body: Body
    bases: tuple[AbstractController, ...]  # the entries of LEARNED_BASES, in that order
    speeds: np.ndarray
    turned: np.ndarray
    # the entries of LEARNED_STEER (empty when the repertoire has none) and the turning rates
    # (S, W), rad/s, of steering left at swim weight LEARNED_SWIM[s] and steer weight
    # STEER_WEIGHTS[w] (made monotonic in w; the right side is its mirror image)
    steers: tuple[AbstractController, ...] = ()
    steer_rates: np.ndarray | None = None
    steer_speeds: np.ndarray | None = None  # (S, W) m/s of the same steers
    # the gaits' raw signals at the latest control period's times (``_raw``)
    _memo: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @classmethod
    def calibrate(cls, body: Body, rep: Repertoire) -> LearnedMotor:
        """Measure the swim gaits' speeds and the sharp turns' angles in one batched run from
        rest; cached per body and repertoire for the process."""
        missing = [n for n in LEARNED_BASES if n not in rep.controllers]
        if missing:
            raise ZoeticError(f"motor controllers need the entries {missing} in the repertoire")
        bases = tuple(rep.controllers[n] for n in LEARNED_BASES)
        steers = tuple(rep.controllers[n] for n in LEARNED_STEER if n in rep.controllers)
        steers = steers if len(steers) == len(LEARNED_STEER) else ()
        key = tuple(np.concatenate([c.offset, c.freq.ravel(), c.amp.ravel(),
                                    c.phase.ravel()]).tobytes() for c in bases + steers)
        cached = _LEARNED_MOTOR_CACHE.setdefault(body, {})
        if key in cached:
            return cached[key]
        motor = cls(body, bases, np.zeros(len(LEARNED_SWIM)), np.zeros((2, len(LEARNED_TURN))))
        total = LEARNED_SETTLE + LEARNED_TURN[-1] + LEARNED_AFTER
        times = np.arange(int(round(total / body.dt))) * body.dt
        rows = [motor.swim_signal(times, a, 0.0) for a in LEARNED_SWIM]
        for side in (0, 1):
            for d in LEARNED_TURN:
                u = motor.swim_signal(times, LEARNED_CRUISE, 0.0)
                on = (times >= LEARNED_SETTLE) & (times < LEARNED_SETTLE + d)
                u[on] = motor.turn_signal(times[on] - LEARNED_SETTLE, times[on], side,
                                          LEARNED_CRUISE, 0.0)  # fmt: skip
                rows.append(u)
        steering = cls(body, bases, motor.speeds, motor.turned, steers)
        grid = [(a, w) for a in LEARNED_SWIM for w in STEER_WEIGHTS] if steers else []
        rows += [steering.steer_signal(times, a, w, 0, 0.0) for a, w in grid]
        every = max(1, int(round(0.05 / body.dt)))
        tr = simulate(body, np.stack(rows), record_every=every)
        t = np.arange(tr.positions.shape[1]) * every * body.dt
        com = tr.com(body)[..., [0, 2]]
        n = len(LEARNED_SWIM)
        sel = t >= LEARNED_SETTLE
        span = t[sel][-1] - t[sel][0]
        speed = np.linalg.norm(np.diff(com[:n, sel], axis=1), axis=-1).sum(1) / span
        rec = every * body.dt
        k, k_s = int(round(LEARNED_SETTLE / rec)), int(round(1.0 / rec))

        def travel(r, k0, k1):  # direction of travel (rad, yaw: left positive) of row r
            d = com[n + r, k1] - com[n + r, k0]
            return np.arctan2(d[1], d[0])

        turned = np.zeros(2 * len(LEARNED_TURN))
        for r, d in enumerate(np.tile(LEARNED_TURN, 2)):
            e = min(int(round((LEARNED_SETTLE + d + LEARNED_AFTER) / rec)), len(t) - 1)
            turned[r] = np.angle(np.exp(1j * (travel(r, e - k_s, e) - travel(r, k - k_s, k))))
        turned = turned.reshape(2, len(LEARNED_TURN))
        turned[0] = np.maximum.accumulate(np.maximum(turned[0], 0.0))
        turned[1] = np.minimum.accumulate(np.minimum(turned[1], 0.0))
        rates = speeds = None
        if steers:
            m, shape = n + 2 * len(LEARNED_TURN), (len(LEARNED_SWIM), len(STEER_WEIGHTS))
            heading = heading_angles(body, tr.positions[m:])
            k1 = min(int(round((LEARNED_SETTLE + STEER_MEASURE) / rec)), len(t) - 1)
            w = slice(k, k1 + 1)
            speeds, rates = grid_rates(com[m:, w], heading[:, w], t[w], shape)
        motor = cls(body, bases, speed, turned, steers, rates, speeds)
        cached[key] = motor
        return motor

    @property
    def top_speed(self) -> float:
        """Return the fastest straight speed (m/s) the swim gait reaches."""
        return float(self.speeds.max())

    @property
    def turn_radius(self) -> float:
        """Return the radius (m) of the sharp turn from a cruise: cruise speed over the
        slower side's mean rate over its whole duration."""
        rate = float(np.abs(self.turned[:, -1]).min()) / float(LEARNED_TURN[-1])
        cruise = float(np.interp(LEARNED_CRUISE, LEARNED_SWIM, self.speeds))
        return cruise / max(rate, 1e-6)

    def swim(self, speed: float) -> float:
        """Return the swim weight that swims ``speed`` m/s (clipped to the calibrated range;
        below the smallest weight's speed, scaled down towards rest)."""
        lo = float(self.speeds[0])
        if speed < lo:
            return float(LEARNED_SWIM[0] * max(speed, 0.0) / max(lo, 1e-9))
        sp, w = self._swim_table
        return float(_interp(float(speed), sp, w))

    @cached_property
    def _swim_table(self) -> tuple[list[float], list[float]]:
        """The speeds (ascending) and swim weights ``swim`` interpolates: the weights up to
        the fastest, sorted by speed (computed once, not once a fish and period)."""
        top = int(np.argmax(self.speeds))
        sp, w = self.speeds[: top + 1], LEARNED_SWIM[: top + 1]
        order = np.argsort(sp)
        return sp[order].tolist(), w[order].tolist()

    def turn(self, angle: float) -> tuple[int, float]:
        """Return (side, seconds): play sharp-turn-left (0) or -right (1) for that long from its
        start to turn ``angle`` rad (left positive); the whole turn when it turns less."""
        side = 0 if angle >= 0 else 1
        x = np.concatenate([[0.0], np.abs(self.turned[side])])
        y = np.concatenate([[0.0], LEARNED_TURN])
        keep = np.concatenate([[True], np.diff(x) > 0])  # interp needs increasing angles
        return side, float(np.interp(abs(angle), x[keep], y[keep]))

    @property
    def steer_top(self) -> float:
        """Return the fastest steady steer (rad/s) at any swim weight (0 without steering)."""
        return 0.0 if self.steer_rates is None else float(self.steer_rates[:, -1].min())

    @property
    def steer_radius(self) -> float:
        """Return the radius (m) of the full steer: its speed over its rate, the widest over
        the swim weights (inf without steering)."""
        if self.steer_rates is None or self.steer_speeds is None:
            return float("inf")
        return float(np.max(self.steer_speeds[:, -1] / np.maximum(self.steer_rates[:, -1],
                                                                   1e-6)))  # fmt: skip

    def steer(self, rate: float, a: float) -> tuple[int, float]:
        """Return (side, weight w): steer left (0) or right (1) at ``rate`` rad/s (left
        positive) while swimming at swim weight ``a``: the smallest steer weight whose
        calibrated rate is reached (the rates at ``a`` interpolated between swim weights);
        beyond the table, w = 1."""
        if self.steer_rates is None:
            raise ZoeticError("this repertoire has no steering entries (steer-left/right)")
        side = 0 if rate >= 0 else 1
        sw = LEARNED_SWIM.tolist()
        a = min(max(float(a), sw[0]), sw[-1])
        j = min(max(bisect_left(sw, a) - 1, 0), len(sw) - 2)
        f = (a - sw[j]) / (sw[j + 1] - sw[j])
        row = ((1 - f) * self.steer_rates[j] + f * self.steer_rates[j + 1]).tolist()
        if row[-1] <= row[0]:
            return side, 0.0
        return side, _interp(abs(float(rate)), row, STEER_WEIGHTS.tolist())

    def steer_signal(self, times: np.ndarray, a: float, w: float, side: int,
                     pitch: float) -> np.ndarray:  # fmt: skip
        """Return activations (T, A): (1 - w) of the swim gait of weight ``a`` plus ``w`` of
        the steering gait of ``side`` (0 left, 1 right), both at ``times``; fins at ``pitch``."""
        u = (1 - w) * self._swim_raw(times, a)
        return self._fins(u + w * self._steer_raw(side, times), pitch)

    def _steer_raw(self, side: int, times: np.ndarray) -> np.ndarray:
        """The steering gait of ``side`` at ``times``, the right one ``steer_lag`` s ahead."""
        return self._raw(self.steers[side], times, self.steer_lag if side else 0.0)

    @cached_property
    def steer_lag(self) -> float:
        """Return the time shift (s) at which the swim gait's mirror image is itself:
        go-straight mirrored left for right equals go-straight ``steer_lag`` s later (half its
        period for a symmetric stroke; the least squared difference on the body's time step).
        The right steering gait (steer-left mirrored) is played that far ahead of the clock,
        so that it beats in phase with the swim gait it is blended with, and the right steer
        is the left steer's mirror image. Played at the clock's time it beat in anti-phase
        (the shipped repertoire's right steer against go-straight: correlations down to -0.8
        where the left one's are up to 0.96), and a fish switching between the two steers
        every 0.1 to 1 s rolled over (up to 180 degrees, on its side half the time); with the
        lag it stays within 1 degree of upright."""
        gait = self.bases[1]
        t = np.arange(max(1, int(round(gait.period / self.body.dt)))) * self.body.dt
        mirrored = self.body.mirror_actuators(gait.raw(t))
        err = [float(np.sum((mirrored - gait.raw(t + s)) ** 2)) for s in t.tolist()]
        return float(t[int(np.argmin(err))])

    def swim_signal(self, times: np.ndarray, a: float, pitch: float) -> np.ndarray:
        """Return activations (T, A) of the swim gait of weight ``a``, fins at ``pitch``."""
        return self._fins(self._swim_raw(times, a), pitch)

    def _swim_raw(self, times: np.ndarray, a: float) -> np.ndarray:
        """The swim gait of weight ``a`` (do-nothing blended with go-straight), unclipped."""
        return (1 - a) * self._raw(self.bases[0], times) + a * self._raw(self.bases[1], times)

    def _raw(self, gait: AbstractController, times: np.ndarray,
             shift: float = 0.0) -> np.ndarray:  # fmt: skip
        """Return ``gait.raw(times + shift)`` (read-only), evaluated once for the same times:
        the fishes of one motor play their periodic gaits at the same clock times in a control
        period, so a tank evaluates each gait once a period, not once a fish (only the latest
        times are kept)."""
        key = times.tobytes()
        memo = self._memo
        if memo.get("times") != key:
            memo.clear()
            memo["times"] = key
        out = memo.get((id(gait), shift))
        if out is None:
            out = memo[(id(gait), shift)] = gait.raw(times + shift if shift else times)
            out.flags.writeable = False
        return out

    def turn_signal(self, since: np.ndarray, times: np.ndarray, side: int, a: float,
                    pitch: float) -> np.ndarray:  # fmt: skip
        """Return activations (T, A) of a turn of ``side`` (0 left, 1 right): the sharp turn at
        ``since`` s from its start, ``LEARNED_STRENGTH`` of it, on the swim gait of weight
        ``a`` at ``times``; fins at ``pitch``."""
        w = LEARNED_STRENGTH
        u = w * self.bases[2 + side].raw(since) + (1 - w) * self._swim_raw(times, a)
        return self._fins(u, pitch)

    def _fins(self, u: np.ndarray, pitch: float) -> np.ndarray:
        return np.clip(self.lean(u, pitch, 0.0), 0.0, 1.0)

    def lean(self, u: np.ndarray, pitch: float, lean: float) -> np.ndarray:
        """Set the fins of activations ``u`` (T, A; changed in place and returned) to
        ``pitch`` rad, the left ones ``lean`` rad more and the right ones less
        (``righting``)."""
        for k, act in fin_activation(self.body, float(pitch), self._fin_rows, lean).items():
            u[:, k] = act
        return u

    @cached_property
    def _fin_rows(self) -> list[tuple[int, float, float, float]]:
        """``fin_rows(body)``, kept (``_fins`` runs once a fish and control period)."""
        return fin_rows(self.body)

    def summary(self) -> dict:
        """Return the calibration tables (speeds in m/s, angles turned in degrees)."""
        return {
            "swim_weights": LEARNED_SWIM.tolist(),
            "speed_m_s": self.speeds.round(3).tolist(),
            "turn_seconds": LEARNED_TURN.tolist(),
            "turned_left_deg": np.degrees(self.turned[0]).round(1).tolist(),
            "turned_right_deg": np.degrees(self.turned[1]).round(1).tolist(),
            **({} if self.steer_rates is None else {
                "steer_weights": STEER_WEIGHTS.tolist(),
                "steer_deg_s": np.degrees(self.steer_rates).round(1).tolist(),
                "steer_speed_m_s": np.asarray(self.steer_speeds).round(3).tolist(),
                "steer_radius_m": round(self.steer_radius, 3)}),
        }  # fmt: skip
