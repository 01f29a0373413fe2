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
and it plays the weighted sum of the two signals). The nodes are the entries' own steady
speeds, measured (``gait_speeds``), and w is linear in the asked speed between them.
"""

from __future__ import annotations

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
    """The straight swims of one repertoire, slowest first: entry names and steady speeds."""

    names: tuple[str, ...]
    speeds: np.ndarray  # (S,) m/s, increasing

    @classmethod
    def measure(cls, body: Body, rep: Repertoire) -> SpeedNodes:
        """Measure the repertoire's ``SPEED_ENTRIES`` (those it has; at least two)."""
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
        names = [names[i] for i in order]
        speeds = speeds[order]
        if np.any(np.diff(speeds) <= 0):
            raise ZoeticError(f"two straight swims have the same speed: {speeds.round(3)}")
        return cls(tuple(names), speeds)

    def table(self) -> dict[str, float]:
        """Return each entry's steady speed (m/s), slowest first."""
        return {n: float(v) for n, v in zip(self.names, self.speeds, strict=True)}

    def neighbours(self, speed: float) -> tuple[int, float]:
        """Return (i, w): the asked ``speed`` (m/s) lies w of the way from node i to i + 1
        (w = 0 on node i; the fastest node is i = S - 2, w = 1)."""
        lo, hi = float(self.speeds[0]), float(self.speeds[-1])
        if not np.isfinite(speed) or not lo <= speed <= hi:
            raise ZoeticError(
                f"speed {speed:g} m/s: the learned straight swims reach {lo:.3g} to {hi:.3g} m/s "
                f"({', '.join(f'{n} {v:.3g}' for n, v in self.table().items())})"
            )
        i = int(np.clip(np.searchsorted(self.speeds, speed, side="right") - 1, 0, len(self) - 2))
        return i, float((speed - self.speeds[i]) / (self.speeds[i + 1] - self.speeds[i]))

    def __len__(self) -> int:
        return len(self.names)


def swim_at(rep: Repertoire, nodes: SpeedNodes, speed: float) -> tuple[AbstractController, dict]:
    """Return (controller, how) swimming about ``speed`` m/s: the blend of the two learned
    straight swims around it (``motor.blend``, weight linear in speed between their measured
    speeds), or the entry itself at a node; ``how`` names the two entries and the weight."""
    i, w = nodes.neighbours(speed)
    a, b = nodes.names[i], nodes.names[i + 1]
    how = {"speed_m_s": float(speed), "from": a, "to": b, "weight": round(w, 4)}
    if w <= 0.0:
        return rep.controllers[a], how
    if w >= 1.0:
        return rep.controllers[b], how
    return blend(rep.controllers[a], rep.controllers[b], w), how
