"""Learned motor controllers: swim / turn / steer / pitch played from a learned repertoire.

As the artificial fish's motor controllers: swim(speed) plays the blend (1 - a) do-nothing +
a go-straight (a blend of abstracted entries is linear in their signals before the clip to
[0, 1]); turn(angle) plays the learned sharp turn of that side from its own start
(``LEARNED_STRENGTH`` of it on the swim gait) for as long as it takes to turn the angle (the
turn was learned as a manoeuvre from its start; played on as a periodic gait it hardly turns);
pitch holds the fins. ``LearnedMotor`` is calibrated once per body and repertoire: the speed
of each swim weight, and the angle each side's sharp turn has turned when stopped after each
of a few durations.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from zoetic.behavior.motor import fin_activations, fin_rows, grid_rates, interps
from zoetic.behavior.repertoire import Repertoire
from zoetic.bodies import Body
from zoetic.control.abstract import AbstractController
from zoetic.errors import ZoeticError
from zoetic.learning.objective import heading_angles
from zoetic.physics import simulate

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
# motors per body object (an edited body is another object), then per repertoire's content
_LEARNED_MOTOR_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


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
        key = tuple(
            np.concatenate([c.offset, c.freq.ravel(), c.amp.ravel(), c.phase.ravel()]).tobytes()
            for c in bases + steers
        )
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
                u[on] = motor.turn_signal(
                    times[on] - LEARNED_SETTLE, times[on], side, LEARNED_CRUISE, 0.0
                )
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
        below the smallest weight's speed, scaled down towards rest): ``swims`` of one."""
        return float(self.swims(np.array([speed], float))[0])

    def swims(self, speed: np.ndarray) -> np.ndarray:
        """Return the swim weights (D,) that swim the speeds (D,) m/s (``swim`` of each)."""
        speed = np.asarray(speed, float)
        lo = float(self.speeds[0])
        sp, w = self._swim_table
        slow = LEARNED_SWIM[0] * np.maximum(speed, 0.0) / max(lo, 1e-9)
        return np.where(speed < lo, slow, interps(speed, sp, w))

    @cached_property
    def _swim_table(self) -> tuple[np.ndarray, np.ndarray]:
        """The speeds (ascending) and swim weights ``swim`` interpolates: the weights up to
        the fastest, sorted by speed (computed once, not once a fish and period)."""
        top = int(np.argmax(self.speeds))
        sp, w = self.speeds[: top + 1], LEARNED_SWIM[: top + 1]
        order = np.argsort(sp)
        return sp[order], w[order]

    def turn(self, angle: float) -> tuple[int, float]:
        """Return (side, seconds): play sharp-turn-left (0) or -right (1) for that long from its
        start to turn ``angle`` rad (left positive); the whole turn when it turns less."""
        side, seconds = self.turns(np.array([angle], float))
        return int(side[0]), float(seconds[0])

    def turns(self, angle: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return (side, seconds) (D,) of ``turn`` for each of the angles (D,) rad."""
        angle = np.asarray(angle, float)
        side = np.where(angle >= 0, 0, 1)
        (x0, y0), (x1, y1) = self._turn_table
        a = np.abs(angle)
        return side, np.where(side == 0, np.interp(a, x0, y0), np.interp(a, x1, y1))

    @cached_property
    def _turn_table(self) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
        """Per side, the angles turned (increasing, from 0) and the seconds played that
        ``turn`` interpolates (computed once, not once a fish and turn)."""
        out = []
        for side in (0, 1):
            x = np.concatenate([[0.0], np.abs(self.turned[side])])
            y = np.concatenate([[0.0], LEARNED_TURN])
            keep = np.concatenate([[True], np.diff(x) > 0])  # interp needs increasing angles
            out.append((x[keep], y[keep]))
        return tuple(out)

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
        return float(np.max(self.steer_speeds[:, -1] / np.maximum(self.steer_rates[:, -1], 1e-6)))

    def steer(self, rate: float, a: float) -> tuple[int, float]:
        """Return (side, weight w): steer left (0) or right (1) at ``rate`` rad/s (left
        positive) while swimming at swim weight ``a``: the smallest steer weight whose
        calibrated rate is reached (the rates at ``a`` interpolated between swim weights);
        beyond the table, w = 1 (``steers`` of one)."""
        side, w = self.steers_at(np.array([rate], float), np.array([a], float))
        return int(side[0]), float(w[0])

    def steers_at(self, rate: np.ndarray, a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return (side, w) (D,) of ``steer`` for each of the rates and swim weights (D,)."""
        if self.steer_rates is None:
            raise ZoeticError("this repertoire has no steering entries (steer-left/right)")
        rate = np.asarray(rate, float)
        sw, rates, weights = self._steer_table
        a = np.minimum(np.maximum(np.asarray(a, float), sw[0]), sw[-1])
        j = np.clip(np.searchsorted(sw, a, side="left") - 1, 0, len(sw) - 2)
        f = ((a - sw[j]) / (sw[j + 1] - sw[j]))[:, None]
        row = (1 - f) * rates[j] + f * rates[j + 1]  # the rates at ``a``
        w = interps(np.abs(rate), row, weights)
        return np.where(rate >= 0, 0, 1), np.where(row[:, -1] <= row[:, 0], 0.0, w)

    @cached_property
    def _steer_table(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The swim weights, steering rates and steer weights ``steer`` reads."""
        return LEARNED_SWIM, np.asarray(self.steer_rates, float), STEER_WEIGHTS

    def steer_signal(
        self, times: np.ndarray, a: float, w: float, side: int, pitch: float
    ) -> np.ndarray:
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
        is the left steer's mirror image (in anti-phase, a fish switching between the two
        steers rolls over: docs/aquarium.md)."""
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
        return self.swim_raws(times, np.array([a], float))[0]

    def swim_raws(self, times: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Return (D, T, A) the swim gaits of D weights ``a`` (D,) at ``times``, unclipped
        (each the same numbers as one weight's)."""
        w = np.asarray(a, float)[:, None, None]
        return (1 - w) * self._raw(self.bases[0], times) + w * self._raw(self.bases[1], times)

    def steer_raws(self, side: int, times: np.ndarray, u: np.ndarray, w: np.ndarray) -> np.ndarray:
        """Return (D, T, A): (1 - w) of the swim gaits ``u`` (D, T, A) plus ``w`` (D,) of the
        steering gait of ``side`` (0 left, 1 right) at ``times``, unclipped."""
        w = np.asarray(w, float)[:, None, None]
        return (1 - w) * u + w * self._steer_raw(side, times)[None]

    def fins(self, u: np.ndarray, pitch: np.ndarray, lean: np.ndarray | None = None) -> np.ndarray:
        """Return activations (D, T, A) from the raw blends ``u`` (D, T, A; changed in place):
        clipped to [0, 1], the fins of row k at ``pitch[k]`` rad and, where ``lean`` (D,) is
        given (not nan), the left ones ``lean[k]`` rad more and the right ones less
        (``righting``)."""
        pitch = np.asarray(pitch, float)
        for act, value in self._fin_values(pitch, np.zeros(len(pitch))):
            u[:, :, act] = value[:, None]
        np.clip(u, 0.0, 1.0, out=u)
        if lean is None:
            return u
        lean = np.asarray(lean, float)
        on = ~np.isnan(lean)
        for act, value in self._fin_values(pitch[on], lean[on]):
            u[on, :, act] = value[:, None]
        return u

    def _fin_values(self, pitch: np.ndarray, lean: np.ndarray) -> list[tuple[int, np.ndarray]]:
        """``fin_activations`` of each row's pitch and lean (D,), per fin actuator."""
        return fin_activations(self._fin_rows, pitch, lean)

    def _raw(self, gait: AbstractController, times: np.ndarray, shift: float = 0.0) -> np.ndarray:
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

    def turn_signal(
        self, since: np.ndarray, times: np.ndarray, side: int, a: float, pitch: float
    ) -> np.ndarray:
        """Return activations (T, A) of a turn of ``side`` (0 left, 1 right): the sharp turn at
        ``since`` s from its start, ``LEARNED_STRENGTH`` of it, on the swim gait of weight
        ``a`` at ``times``; fins at ``pitch``."""
        w = LEARNED_STRENGTH
        u = w * self.bases[2 + side].raw(since) + (1 - w) * self._swim_raw(times, a)
        return self._fins(u, pitch)

    def _fins(self, u: np.ndarray, pitch: float) -> np.ndarray:
        return self.fins(u[None], np.array([pitch], float))[0]

    @cached_property
    def _fin_rows(self) -> list[tuple[int, float, float, float]]:
        """``fin_rows(body)``, kept (``fins`` runs once a control period)."""
        return fin_rows(self.body)

    def summary(self) -> dict:
        """Return the calibration tables (speeds in m/s, angles turned in degrees)."""
        return {
            "swim_weights": LEARNED_SWIM.tolist(),
            "speed_m_s": self.speeds.round(3).tolist(),
            "turn_seconds": LEARNED_TURN.tolist(),
            "turned_left_deg": np.degrees(self.turned[0]).round(1).tolist(),
            "turned_right_deg": np.degrees(self.turned[1]).round(1).tolist(),
            **(
                {}
                if self.steer_rates is None
                else {
                    "steer_weights": STEER_WEIGHTS.tolist(),
                    "steer_deg_s": np.degrees(self.steer_rates).round(1).tolist(),
                    "steer_speed_m_s": np.asarray(self.steer_speeds).round(3).tolist(),
                    "steer_radius_m": round(self.steer_radius, 3),
                }
            ),
        }
