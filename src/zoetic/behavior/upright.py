"""The righting reflex of feed-forward plans: sequences of repertoire entries and macro plans.

A plan plays its entries without feedback, and a swimming fish's body has no roll stiffness
and little roll damping, so a roll left by a turn stays or grows until the fish swims on its
side or upside down. Here the plan is played in a World through the one closed-loop driver, in
windows of the tracker's interval (each plan item's first window starts where the item does).
At each window the planned entry is kept, and of it and its righting variants
(``tracking.righting_entries``: the pectoral fins tilted apart either way, and the same with
a gentler stroke), each carried on from where the plan is in its stroke
(``AbstractController.resumed``), the one is played whose own simulation of the window costs
least by the tracker's depth and attitude terms (``tracking.upright_cost``, the start depth
the goal, the roll judged also where its rate leads); ties go to the entry as planned. The
choices are recorded as a SequenceController (``tracking.sequence_of``) which, played from
rest, reproduces the run.

The gentle variants are there because the fins alone are too weak for a hard stroke: after
the README's sharp turn the shark's learned go-straight spins it at about 140 deg/s, and the
fins at full tilt slow that to about 50 deg/s but do not stop it; with the muscles' stroke
amplitude at 0.2 the shark swims on at most of its speed and the fins right it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from zoetic.bodies import Body
from zoetic.control import Controller
from zoetic.control.abstract import AbstractController, SequenceController
from zoetic.control.loop import Schedule, drive
from zoetic.control.measure import locomotion, motion_scalars
from zoetic.control.policy import Period
from zoetic.errors import SimulationError
from zoetic.physics import State, get_medium, simulate
from zoetic.physics.world import World

from .tracking import (
    RESTART,
    PathRecorder,
    TrackConfig,
    repeat_state,
    righting_entries,
    sequence_of,
    upright_cost,
)

GENTLE = 0.2  # the muscles' stroke amplitude the gentle variants keep


@dataclass
class UprightResult:
    """A plan played upright: the recorded controller, its items and the path it swam."""

    sequence: SequenceController
    names: list[str]  # each item's entry, "+roll-left" or "+roll-right" where the fins right
    starts: np.ndarray  # (n,) s: when each item started
    times: np.ndarray  # (R,) s
    positions: np.ndarray  # (R, N, 3) m
    evaluations: list[str] = field(default_factory=list)  # entry played in each window
    motion: dict = field(default_factory=dict)  # locomotion(): depth, roll, pitch, turn

    def summary(self) -> dict:
        """Return in how many windows a righting variant played (of them, how many with the
        gentler stroke), with the locomotion figures."""
        ev = self.evaluations
        return {
            "windows": len(ev),
            "windows_righted": sum("+roll-" in n or "+gentle" in n for n in ev),
            "windows_gentle": sum("+gentle" in n for n in ev),
            **self.motion,
        }


def has_righting(body: Body, plan: SequenceController, tilt: float) -> bool:
    """Return whether any planned entry has fin-righting variants on this body."""
    ctrls = [c for c, _ in plan.items]
    return len(righting_entries(body, [""] * len(ctrls), ctrls, tilt)[1]) > len(ctrls)


def _decisions(plan: SequenceController, seconds: float, interval: float, grid: float) -> list:
    """Return the windows as (start s on the record grid ``grid`` s, plan item): each plan
    item's start, then every ``interval`` within its span, the last window of a span at least
    half an interval long."""
    starts = plan.starts()
    ends = np.minimum(np.append(starts[1:], np.inf), seconds)
    out: dict[float, int] = {}
    for i, (s, e) in enumerate(zip(starts, ends, strict=True)):
        t = s
        while t < e and (t == s or t < e - 0.5 * interval):
            out[round(t / grid) * grid] = i  # a later item taking the same instant wins
            t += interval
    return sorted((t, i) for t, i in out.items() if t < seconds)


@dataclass
class _Righting:
    """The reflex's decisions: at each window, of the planned entry and its righting
    variants, the one whose simulation of the window keeps the animal nearest upright."""

    body: Body
    names: list[str]  # the plan's entry names
    plan: SequenceController
    config: TrackConfig
    decisions: list[tuple[float, int]]  # the windows: start s, plan item
    height: float  # m, the start depth's height: the depth term's goal
    gentle: float = 1.0  # the stroke amplitude the gentle variants keep (1: none)
    ctrls: list[Controller] = field(default_factory=list)  # the items' controllers
    items: list[list] = field(default_factory=list)  # [index into ctrls, start s]
    playing: tuple[int, str] = (-1, "")  # the last item's plan item and entry name
    labels: list[str] = field(default_factory=list)  # each item's entry name
    chosen: list[str] = field(default_factory=list)  # the entry played in each window

    def window(self, world: World) -> int:
        """Return the steps of the next window (to the run's end after the last start)."""
        k = len(self.chosen) + 1
        if k >= len(self.decisions):
            return 2**31 - 1  # the driver cuts it at the run's end
        return int(round((self.decisions[k][0] - world.time) / self.body.dt))

    def _candidates(self, i: int, t: float) -> tuple[list[str], list[Controller]]:
        """Return plan item ``i``'s entry and its righting variants, carried on from ``t``."""
        ctrl, start = self.plan.items[i][0], self.plan.starts()[i]
        if isinstance(ctrl, AbstractController) and t != start:
            ctrl = ctrl.resumed(t - start)
        tilt = self.config.fin_tilt
        return righting_entries(self.body, [self.names[i]], [ctrl], tilt, self.gentle)

    def _table(self, ctrl: Controller | None, t: float, steps: int) -> np.ndarray:
        """Return the activations (steps, A) from ``t`` with ``ctrl`` taking over then (None:
        the items as they are, the last one carrying on)."""
        ctrls, items = self.ctrls + [ctrl], self.items + [[len(self.ctrls), t]]
        if ctrl is None:
            ctrls, items = self.ctrls, self.items
        seq = sequence_of(ctrls, items, t + steps * self.body.dt + 1.0, self.plan.overlap)[0]
        return seq.table(steps, self.body.dt, t0=t)

    def __call__(self, world: World, period: Period) -> list[np.ndarray]:
        """Return the activations (1, T, A) of the chosen entry over ``period``."""
        t, body = world.time, self.body
        i = self.decisions[len(self.chosen)][1]
        names, ctrls = self._candidates(i, t)
        held = t - self.items[-1][1] if self.items else 0.0
        same = bool(self.items) and self.playing[0] == i
        if same and len(ctrls) == 1:  # nothing to choose: the planned entry plays on
            self.chosen.append(names[0])
            return [self._table(None, t, period.steps)[None]]
        rec = int(self.config.record_every)
        tables = np.stack([self._table(c, t, period.steps) for c in ctrls])
        state = State(world.positions(0), world.velocities(0))
        traj = simulate(body, tables, state=repeat_state(state, len(ctrls)), record_every=rec)
        m = motion_scalars(body, traj.positions, traj.times, get_medium(body.medium))
        height = np.einsum("bnk,n->bk", traj.positions[:, -1], body.mass / body.total_mass)
        att = (m["roll"], m["pitch"])
        cost = upright_cost(height[:, 1], self.height, rec * body.dt, self.config, att)
        cost[traj.failed] = np.inf
        if not np.isfinite(cost).any():
            raise SimulationError(f"the plan and its righting variants blew up at t = {t:.2f} s")
        best = int(np.argmin(cost))  # the first of equals: the entry as planned
        self.chosen.append(names[best])
        if same and self.playing[1] == names[best] and held < RESTART:
            return [self._table(None, t, period.steps)[None]]
        self.ctrls.append(ctrls[best])
        self.items.append([len(self.ctrls) - 1, t])
        self.labels.append(names[best])
        self.playing = (i, names[best])
        return [tables[best][None]]


def right_plan(
    body: Body,
    names: list[str],
    plan: SequenceController,
    seconds: float | None = None,
    config: TrackConfig = TrackConfig(),
    gentle: float = GENTLE,
) -> UprightResult:
    """Return ``plan`` (its items' entry ``names``) played for ``seconds`` (default its
    duration) with the fins' righting reflex, run through the one closed-loop driver;
    ``gentle``: the stroke amplitude of the gentle variants (1: fins only)."""
    seconds = plan.duration if seconds is None else float(seconds)
    rec, dt = int(config.record_every), body.dt
    world = World([body])
    height = float(world.positions(0)[0].T[1] @ body.mass / body.total_mass)
    decisions = _decisions(plan, seconds, config.interval, rec * dt)
    reflex = _Righting(body, list(names), plan, config, decisions, height, gentle)
    path = PathRecorder()
    schedule = Schedule(config.interval, record_every=rec, plan=reflex.window)
    drive(world, reflex, seconds, schedule, (path,))
    seq, starts = sequence_of(reflex.ctrls, reflex.items, seconds, plan.overlap)
    positions, times = np.array(path.frames), np.array(path.times)
    return UprightResult(
        sequence=seq,
        names=reflex.labels,
        starts=starts,
        times=times,
        positions=positions,
        evaluations=reflex.chosen,
        motion=locomotion(body, positions, times),
    )
