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
and it plays the weighted sum of the two signals), the faster entry shifted in time to beat
in step with the slower. The entries' own steady speeds (``gait_speeds``) and those of a few
blends between each two (``CALIBRATION_WEIGHTS``) are measured once (``SpeedNodes``), and w
is read off them, linear between calibrated weights: the speed of a blend is not linear in w
(for the shark's medium-to-fast blend, w = 0.5 swims 1.13 m/s, not the 1.02 halfway).
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np

from zoetic.behavior.motor import best_lag, blend
from zoetic.behavior.repertoire import Repertoire
from zoetic.bodies import Body
from zoetic.control.abstract import AbstractController
from zoetic.errors import ZoeticError

# the repertoire's straight swims, slowest first by design: the nodes a speed interpolates
SPEED_ENTRIES = ("swim-slow", "swim-medium", "go-straight")
GAIT_SECONDS = 6.0  # s a gait is played from rest; its speed is that of the second half
# the blend weights of two neighbouring swims whose speeds are measured (ends: the entries)
CALIBRATION_WEIGHTS = (0.0, 0.25, 0.5, 0.75, 1.0)
# measured nodes per body object, then per content of its repertoire's straight swims
_NODES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def gait_speeds(body: Body, ctrls: list) -> np.ndarray:
    """Return the steady forward speed (m/s) of each controller played from rest for
    ``GAIT_SECONDS``: the mean, over the second half, of the forward speed ``control.measure``
    reads from the recorded motion (one batched simulation)."""
    from zoetic.control.measure import motion_scalars
    from zoetic.physics import get_medium, simulate

    steps = int(round(GAIT_SECONDS / body.dt))
    every = max(1, int(round(0.05 / body.dt)))
    table = np.stack([c.table(steps, body.dt) for c in ctrls])
    tr = simulate(body, table, record_every=every)
    speed = motion_scalars(body, tr.positions, tr.times, get_medium(body.medium))["speed"]
    late = tr.times >= tr.times[-1] / 2.0
    return np.where(tr.failed, np.nan, speed[:, late].mean(axis=1))


@dataclass(frozen=True)
class SpeedNodes:
    """The straight swims of one repertoire, slowest first, and the speeds of their blends.

    Gap i joins entries i and i + 1: entry i + 1 is played ``lags[i]`` s ahead (``motor.
    best_lag``: where its stroke best matches entry i's), so that the two beat together; two
    independently learned gaits blended out of step swim slower or faster than either in
    turn. ``curve[i]`` holds the measured speeds of the blends at ``CALIBRATION_WEIGHTS``
    (entry i's own speed first, entry i + 1's last), which ``neighbours`` inverts.
    """

    names: tuple[str, ...]
    speeds: np.ndarray  # (S,) m/s of the entries, increasing
    lags: np.ndarray  # (S - 1,) s
    curve: np.ndarray  # (S - 1, W) m/s of the blends of each gap

    @classmethod
    def measure(cls, body: Body, rep: Repertoire) -> SpeedNodes:
        """Measure the repertoire's ``SPEED_ENTRIES`` (those it has; at least two) and the
        blends of each two neighbours at ``CALIBRATION_WEIGHTS`` (two batched simulations)."""
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
        lags = np.array(
            [best_lag(a.raw, b, body.dt) for a, b in zip(gaits[:-1], gaits[1:], strict=True)]
        )
        inner = CALIBRATION_WEIGHTS[1:-1]
        blends = [
            blend(a, b.ahead(s), w)
            for a, b, s in zip(gaits[:-1], gaits[1:], lags, strict=True)
            for w in inner
        ]
        mid = gait_speeds(body, blends).reshape(len(names) - 1, len(inner))
        curve = np.column_stack([speeds[:-1], mid, speeds[1:]])
        return cls(tuple(names), speeds, lags, curve)

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
                f"speed {speed:g} m/s: the learned straight swims reach {lo:.3g} to {hi:.3g} m/s "
                f"({', '.join(f'{n} {v:.3g}' for n, v in self.table().items())})"
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
    straight swims around it (``motor.blend``, the faster one in step with the slower, at the
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
