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

The fins' activations (``fin_activation``), the righting reflex (``righting``) and the table
helpers here serve the aquarium's two motors too: ``wave_motor.WaveMotor`` (the body's own
steered wave) and ``learned_motor.LearnedMotor`` (a learned repertoire's gaits).
"""

from __future__ import annotations

from dataclasses import dataclass

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
        a.animal,
        a.actuators,
        (1 - w) * a.offset + w * b.offset,
        np.concatenate([a.freq, b.freq], axis=1),
        np.concatenate([(1 - w) * a.amp, w * b.amp], 1),
        np.concatenate([a.phase, b.phase], axis=1),
        max(a.period, b.period),
    )


def fin_rows(body: Body) -> list[tuple[int, float, float, float]]:
    """Return each fin's (actuator, angle at activation 0, angle at 1, side) as Python numbers;
    side is 1 for a fin on the left, -1 on the right, 0 on neither (its actuator's side)."""
    sides = {"left": 1.0, "right": -1.0}
    return [
        (int(a), float(lo), float(hi), sides.get(body.actuator_side[int(a)], 0.0))
        for a, (lo, hi) in zip(body.fin_actuator.tolist(), body.fin_angle.tolist(), strict=True)
    ]


def fin_activation(
    body: Body,
    angle: float,
    rows: list[tuple[int, float, float, float]] | None = None,
    lean: float = 0.0,
) -> dict[int, float]:
    """Return, per fin actuator, the activation that sets its fins to ``angle`` rad (clipped),
    the left fins ``lean`` rad more and the right ones ``lean`` less (``righting``: a
    differential pitch rolls the fish); ``rows``: ``fin_rows(body)`` when kept (a caller many
    times a second). ``fin_activations`` of one fish."""
    got = fin_activations(
        fin_rows(body) if rows is None else rows, np.array([angle], float), np.array([lean], float)
    )
    return {act: float(v[0]) for act, v in got}


def fin_activations(
    rows: list[tuple[int, float, float, float]], angle: np.ndarray, lean: np.ndarray
) -> list[tuple[int, np.ndarray]]:
    """Return for D fishes, per fin actuator of ``rows`` (``fin_rows``), the activations (D,)
    in [0, 1] that set its fins to ``angle`` (D,) rad, the left fins ``lean`` (D,) rad more
    and the right ones less (0 for a fin whose angle range is empty)."""
    out = []
    for act, lo, hi, side in rows:
        a = angle + side * lean
        if hi == lo:
            out.append((act, np.zeros_like(a)))
        else:
            out.append((act, np.minimum(np.maximum((a - lo) / (hi - lo), 0.0), 1.0)))
    return out


# The righting reflex: the water model has no restoring roll moment (a fish laid on its side
# stays there), but the pectoral fins pitched differentially (the left fin ``lean`` rad nose
# up, the right one ``lean`` nose down) roll a swimming fish, with a moment that grows with
# its speed squared; fed back as a PD on the roll (``righting``) they right it. The gains are
# measured in docs/aquarium.md ("The righting reflex").
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
        return cls(
            body,
            rep,
            dist[:n] / CALIBRATION_SECONDS,
            (heading[n:, -1] - heading[n:, 0]) / CALIBRATION_SECONDS,
        )

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
        rep.add(
            name,
            motor.rep.controllers[name],
            motor.rep.durations[name],
            **motor.rep.info.get(name, {}),
        )
    period = motor.rep.durations["go-straight"]
    for v in speeds:
        rep.add(f"swim-{v:g}", motor.swim(v), period, source="motor")
    for a in turns:
        ctrl, duration = motor.turn(a)
        rep.add(f"turn-{a:g}", ctrl, duration, source="motor")
    for p in pitches:
        rep.add(f"pitch-{p:g}", motor.pitch(p), period, source="motor")
    return rep


def interp(x: float, xp, fp) -> float:
    """Return ``np.interp(x, xp, fp)`` for a float over points ``xp`` (P,) non-decreasing and
    values ``fp`` (P,): ``interps`` of one value."""
    return float(interps(np.array([x], float), xp, fp)[0])


def interps(x: np.ndarray, xp: np.ndarray, fp) -> np.ndarray:
    """Return ``np.interp`` of each of the values ``x`` (D,) at once: over the points ``xp``
    (P,) non-decreasing, or each value over its own row of ``xp`` (D, P); ``fp`` (P,)."""
    x, xp, fp = np.asarray(x, float), np.asarray(xp, float), np.asarray(fp, float)
    if xp.ndim == 1:  # one table for all: index it directly (no (D, P) copy of it)
        j = np.clip(np.searchsorted(xp, x, side="right") - 1, 0, len(xp) - 2)
        lo, hi, first, last = xp[j], xp[j + 1], xp[0], xp[-1]
    else:
        j = (xp <= x[:, None]).sum(axis=1) - 1  # bisect_right - 1: xp[j] <= x < xp[j + 1]
        j = np.clip(j, 0, xp.shape[1] - 2)
        lo = np.take_along_axis(xp, j[:, None], 1)[:, 0]
        hi = np.take_along_axis(xp, j[:, None] + 1, 1)[:, 0]
        first, last = xp[:, 0], xp[:, -1]
    with np.errstate(divide="ignore", invalid="ignore"):  # the ends are taken as they are
        mid = (fp[j + 1] - fp[j]) / (hi - lo) * (x - lo) + fp[j]
    return np.where(x <= first, fp[0], np.where(x >= last, fp[-1], mid))


def grid_rates(
    com: np.ndarray, heading: np.ndarray, t: np.ndarray, shape: tuple[int, int]
) -> tuple[np.ndarray, np.ndarray]:
    """Return the speed (m/s: path length over the window) and turning rate (rad/s, less the
    row's first column, at least 0, made non-decreasing along each row) of a grid of runs:
    com (K, R, 2) and heading (K, R) recorded at times t (R,) over the window, K runs laid out
    as ``shape`` (rows: a swim level; columns: a rising steer)."""
    span = t[-1] - t[0]
    speed = (np.linalg.norm(np.diff(com, axis=1), axis=-1).sum(1) / span).reshape(shape)
    rate = ((heading[:, -1] - heading[:, 0]) / span).reshape(shape)
    return speed, np.maximum.accumulate(np.maximum(rate - rate[:, :1], 0.0), axis=1)
