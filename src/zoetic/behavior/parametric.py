"""Parameterised motor skills: a swim at any speed between the learned straight swims.

The muscle paper's basic training (section 3.1): "Typically, our artificial animals are put
through a "basic training" regimen of primitive motor tasks that it must learn, such as
locomoting at different speeds and executing turns of different radii. They learn effective
low level controllers for each task and retain compact representations of these controllers
through controller abstraction." ``zoetic repertoire train --speeds`` learns straight swims at
steady speeds (``training.SPEED_PLAN``) beside go-straight, the fastest.

The paper blends abstracted controllers only in time (a sequence cross-fades each into the
next over about 5% of it). Here a speed between two learned ones is asked of a blend of the
two neighbouring entries' parameters: ``motor.blend``, (1 - w) a + w b, offsets mixed and each
mode's amplitude scaled (an abstracted entry is a sum of cosines, so the blend is again one,
and it plays the weighted sum of the two signals), the faster entry shifted in time by a lag
(``AbstractController.ahead``). Two independently learned gaits blended out of step swim
slower than either, or veer: the shark's slow and medium swims, each within 3 degrees of
straight over 6 s, blended half and half in step by least squares turned 33 degrees. So the
lag is the one, on the body's time step over a stroke, whose blends at the
``CALIBRATION_WEIGHTS`` swim straightest (least worst turn plus roll) while their speeds rise
from one entry's to the other's; those blends' speeds are kept (``SpeedNodes``, measured
once in one batched simulation), and w is read off them, linear between calibrated weights:
the speed of a blend is not linear in w.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np

from zoetic.behavior.motor import blend
from zoetic.behavior.repertoire import Repertoire
from zoetic.bodies import Body
from zoetic.control.abstract import AbstractController
from zoetic.errors import ZoeticError

# the repertoire's straight swims, slowest first by design: the nodes a speed interpolates
SPEED_ENTRIES = ("swim-slow", "swim-medium", "go-straight")
GAIT_SECONDS = 6.0  # s a gait is played from rest; its speed is that of the second half
# the blend weights of two neighbouring swims whose speeds are measured (ends: the entries)
CALIBRATION_WEIGHTS = (0.0, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 1.0)
# measured nodes per body object, then per content of its repertoire's straight swims
_NODES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def gait_motion(body: Body, ctrls: list) -> dict[str, np.ndarray]:
    """Return, per controller played from rest for ``GAIT_SECONDS`` (one batched simulation),
    what ``control.measure`` reads of the motion: "speed", the steady forward speed (m/s, the
    mean over the second half; NaN if it blew up), "turn" (deg, heading change, left positive)
    and "roll" (deg, the greatest either way)."""
    from zoetic.control.measure import motion_scalars
    from zoetic.physics import get_medium, simulate

    steps = int(round(GAIT_SECONDS / body.dt))
    every = max(1, int(round(0.05 / body.dt)))
    table = np.stack([c.table(steps, body.dt) for c in ctrls])
    tr = simulate(body, table, record_every=every)
    m = motion_scalars(body, tr.positions, tr.times, get_medium(body.medium))
    late = tr.times >= tr.times[-1] / 2.0
    return {
        "speed": np.where(tr.failed, np.nan, m["speed"][:, late].mean(axis=1)),
        "turn": m["heading"][:, -1] - m["heading"][:, 0],
        "roll": np.nanmax(np.abs(m["roll"]), axis=1),
    }


def gait_speeds(body: Body, ctrls: list) -> np.ndarray:
    """Return the steady forward speed (m/s) of each controller (``gait_motion``)."""
    return gait_motion(body, ctrls)["speed"]


def _straightest(
    body: Body, a: AbstractController, b: AbstractController, ends: np.ndarray
) -> tuple[float, np.ndarray, np.ndarray]:
    """Return (lag s, speeds m/s, turns deg) of the blends of ``a`` and ``b`` played ``lag``
    ahead at the inner ``CALIBRATION_WEIGHTS``: the lag (a multiple of the time step within
    b's stroke) whose blends swim straightest (least worst turn plus worst roll, deg) among
    those whose speeds rise strictly from ``ends[0]`` (a's) to ``ends[1]`` (b's)."""
    inner = CALIBRATION_WEIGHTS[1:-1]
    lags = np.arange(max(1, int(round(b.period / body.dt)))) * body.dt
    m = gait_motion(body, [blend(a, b.ahead(s), w) for s in lags for w in inner])
    speed, turn, roll = (m[q].reshape(len(lags), len(inner)) for q in ("speed", "turn", "roll"))
    chain = np.column_stack([np.full(len(lags), ends[0]), speed, np.full(len(lags), ends[1])])
    rising = np.all(np.diff(chain, axis=1) > 0, axis=1)
    score = np.abs(turn).max(axis=1) + roll.max(axis=1) + np.where(rising, 0.0, 1e6)
    k = int(np.nanargmin(np.where(np.isfinite(score), score, np.inf)))
    return float(lags[k]), chain[k], turn[k]


@dataclass(frozen=True)
class SpeedNodes:
    """The straight swims of one repertoire, slowest first, and the speeds of their blends.

    Gap i joins entries i and i + 1, entry i + 1 played ``lags[i]`` s ahead (the straightest
    lag, ``_straightest``); ``curve[i]`` holds the measured speeds of the blends at
    ``CALIBRATION_WEIGHTS`` (entry i's own speed first, entry i + 1's last), which
    ``neighbours`` inverts, and ``turns[i]`` the inner blends' heading changes over
    ``GAIT_SECONDS`` (deg).
    """

    names: tuple[str, ...]
    speeds: np.ndarray  # (S,) m/s of the entries, increasing
    lags: np.ndarray  # (S - 1,) s
    curve: np.ndarray  # (S - 1, W) m/s of the blends of each gap
    turns: np.ndarray  # (S - 1, W - 2) deg

    @classmethod
    def measure(cls, body: Body, rep: Repertoire) -> SpeedNodes:
        """Measure the repertoire's ``SPEED_ENTRIES`` (those it has; at least two) and the
        blends of each two neighbours at ``CALIBRATION_WEIGHTS`` over a stroke of lags (a
        batched simulation per gap)."""
        names = [n for n in SPEED_ENTRIES if n in rep.controllers]
        if len(names) < 2:
            raise ZoeticError(
                f"a swim at a chosen speed blends two straight swims of {', '.join(SPEED_ENTRIES)}"
                f"; the repertoire has {', '.join(names) or 'none'} (train it with --speeds)"
            )
        speeds = gait_speeds(body, [rep.controllers[n] for n in names])
        bad = [n for n, v in zip(names, speeds, strict=True) if not np.isfinite(v)]
        if bad:
            raise ZoeticError(f"entries {bad} blow up when played from rest")
        order = np.argsort(speeds)
        names, speeds = [names[i] for i in order], speeds[order]
        if np.any(np.diff(speeds) <= 0):
            raise ZoeticError(f"two straight swims have the same speed: {speeds.round(3)}")
        gaits = [rep.controllers[n] for n in names]
        gaps = [
            _straightest(body, a, b, speeds[i : i + 2])
            for i, (a, b) in enumerate(zip(gaits[:-1], gaits[1:], strict=True))
        ]
        lags, curve, turns = (np.array([g[k] for g in gaps]) for k in range(3))
        return cls(tuple(names), speeds, lags, curve, turns)

    def table(self) -> dict[str, float]:
        """Return each entry's steady speed (m/s), slowest first."""
        return {n: float(v) for n, v in zip(self.names, self.speeds, strict=True)}

    def neighbours(self, speed: float) -> tuple[int, float]:
        """Return (i, w): the blend of entries i and i + 1 at weight w swims ``speed`` m/s,
        by the calibrated blends (the first crossing, linear between calibrated weights);
        w = 0 on entry i, and the fastest entry is i = S - 2, w = 1."""
        lo, hi = float(self.speeds[0]), float(self.speeds[-1])
        if not np.isfinite(speed) or not lo <= speed <= hi:
            raise ZoeticError(
                f"speed {speed:g} m/s: the learned straight swims reach {lo:.3f} to {hi:.3f} m/s "
                f"({', '.join(f'{n} {v:.3f}' for n, v in self.table().items())})"
            )
        w = np.asarray(CALIBRATION_WEIGHTS)
        for i, row in enumerate(self.curve):
            if speed == row[0]:
                return i, 0.0
            for k in range(len(w) - 1):
                a, b = row[k], row[k + 1]
                if min(a, b) <= speed <= max(a, b) and a != b:
                    return i, float(w[k] + (w[k + 1] - w[k]) * (speed - a) / (b - a))
        return len(self) - 2, 1.0  # unreachable: the last row ends at the fastest speed

    def __len__(self) -> int:
        return len(self.names)


def speed_nodes(body: Body, rep: Repertoire) -> SpeedNodes:
    """Return ``SpeedNodes.measure(body, rep)``, measured once per body object and content of
    the repertoire's straight swims (a sequence of several swims at chosen speeds measures
    once)."""
    gaits = [rep.controllers[n] for n in SPEED_ENTRIES if n in rep.controllers]
    key = tuple(
        np.concatenate([c.offset, c.freq.ravel(), c.amp.ravel(), c.phase.ravel()]).tobytes()
        for c in gaits
    )
    cached = _NODES.setdefault(body, {})
    if key not in cached:
        cached[key] = SpeedNodes.measure(body, rep)
    return cached[key]


def swim_at(rep: Repertoire, nodes: SpeedNodes, speed: float) -> tuple[AbstractController, dict]:
    """Return (controller, how) swimming about ``speed`` m/s: the blend of the two learned
    straight swims around it (``motor.blend``, the faster one at its straightest lag, at the
    weight the calibrated blends give), or the entry itself at a node; ``how`` names the two
    entries and the weight."""
    i, w = nodes.neighbours(speed)
    a, b = nodes.names[i], nodes.names[i + 1]
    how = {"speed_m_s": float(speed), "from": a, "to": b, "weight": round(w, 4)}
    if w <= 0.0:
        return rep.controllers[a], how
    if w >= 1.0:
        return rep.controllers[b], how
    return blend(rep.controllers[a], rep.controllers[b].ahead(nodes.lags[i]), w), how
