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
the goal, the roll judged also where its rate leads); ties go to the entry as planned, so the
planned entry is simulated first and its variants only where it costs anything. The choices
are recorded as a SequenceController (``tracking.sequence_of``) which, played from rest,
reproduces the run. Plans whose items start on the same windows (a macro search's batch) play
side by side, one lane each of one World, every stage of every window simulated in one batch.

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
from zoetic.control.loop import Observer, Schedule, drive
from zoetic.control.measure import locomotion
from zoetic.control.policy import Period
from zoetic.control.sensors import SENSORS, Senses
from zoetic.errors import SimulationError
from zoetic.physics import State, Trajectory, get_medium, simulate
from zoetic.physics.world import World

from .tracking import (
    RESTART,
    TrackConfig,
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


def attitude(body: Body, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the roll and pitch (K, T) deg of animals sharing ``body`` over ``positions``
    (K, T, N, 3) m: ``motion_scalars``' roll and pitch, without what else it measures."""
    pos = np.asarray(positions, float)
    k, t, n = pos.shape[:3]
    flat = pos.reshape(k * t, n, 3)
    s = Senses(
        body, flat, np.zeros_like(flat), get_medium(body.medium), 0.0, np.zeros((k * t, 0), bool)
    )
    return tuple(np.degrees(SENSORS[q](s)).reshape(k, t) for q in ("roll", "pitch"))


def has_fins(body: Body, ctrls: list[Controller], tilt: float) -> bool:
    """Return whether any of the entries ``ctrls`` has fin-righting variants on this body."""
    return len(righting_entries(body, [""] * len(ctrls), list(ctrls), tilt)[1]) > len(ctrls)


def has_righting(body: Body, plan: SequenceController, tilt: float) -> bool:
    """Return whether any planned entry has fin-righting variants on this body."""
    return has_fins(body, [c for c, _ in plan.items], tilt)


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
class _Lane:
    """One plan's part in the reflex: what it played so far and the entry of each window."""

    names: list[str]  # the plan's entry names
    plan: SequenceController
    ctrls: list[Controller] = field(default_factory=list)  # the items' controllers
    items: list[list] = field(default_factory=list)  # [index into ctrls, start s]
    playing: tuple[int, str] = (-1, "")  # the last item's plan item and entry name
    labels: list[str] = field(default_factory=list)  # each item's entry name
    chosen: list[str] = field(default_factory=list)  # the entry played in each window
    blown: float | None = None  # s: when the plan and all its variants blew up

    def planned(self, i: int, t: float) -> Controller:
        """Return plan item ``i``'s entry carried on from ``t`` (mid-stroke where it is)."""
        ctrl, start = self.plan.items[i][0], self.plan.starts()[i]
        if isinstance(ctrl, AbstractController) and t != start:
            ctrl = ctrl.resumed(t - start)
        return ctrl

    def table(self, ctrl: Controller | None, t: float, steps: int, dt: float) -> np.ndarray:
        """Return the activations (steps, A) from ``t`` with ``ctrl`` taking over then (None:
        the items as they are, the last one carrying on)."""
        ctrls, items = self.ctrls + [ctrl], self.items + [[len(self.ctrls), t]]
        if ctrl is None:
            ctrls, items = self.ctrls, self.items
        seq = sequence_of(ctrls, items, t + steps * dt + 1.0, self.plan.overlap)[0]
        return seq.table(steps, dt, t0=t)

    def take(self, i: int, name: str, ctrl: Controller, t: float) -> bool:
        """Record ``name`` (``ctrl``) as the entry of the window from ``t``; return True when it
        starts a new item, False when the item playing carries on."""
        held = t - self.items[-1][1] if self.items else 0.0
        self.chosen.append(name)
        if self.items and self.playing == (i, name) and held < RESTART:
            return False
        self.ctrls.append(ctrl)
        self.items.append([len(self.ctrls) - 1, t])
        self.labels.append(name)
        self.playing = (i, name)
        return True


@dataclass
class _Righting:
    """The reflex's decisions for plans played side by side (one lane each) in shared
    windows: at each, of a plan's planned entry and its righting variants, the one whose
    simulation of the window keeps the animal nearest upright and at its start depth."""

    body: Body
    lanes: list[_Lane]
    config: TrackConfig
    decisions: list[tuple[float, list[int]]]  # the windows: start s, each lane's plan item
    height: float  # m, the start depth's height: the depth term's goal
    gentle: float = 1.0  # the stroke amplitude the gentle variants keep (1: none)
    done: int = 0  # windows decided
    known: dict = field(default_factory=dict)  # id of an entry: whether it has variants

    def window(self, world: World) -> int:
        """Return the steps of the next window (to the run's end after the last start)."""
        if self.done + 1 >= len(self.decisions):
            return 2**31 - 1  # the driver cuts it at the run's end
        return int(round((self.decisions[self.done + 1][0] - world.time) / self.body.dt))

    def varies(self, ctrl: Controller) -> bool:
        """Return whether the entry ``ctrl`` has righting variants (remembered per entry)."""
        key = id(ctrl)
        if key not in self.known:
            self.known[key] = has_fins(self.body, [ctrl], self.config.fin_tilt)
        return self.known[key]

    def __call__(self, world: World, period: Period) -> list[np.ndarray]:
        """Return each lane's activations (B, T, A): its chosen entry over ``period``."""
        t, body, steps = world.time, self.body, period.steps
        items = self.decisions[self.done][1]
        self.done += 1
        rows = np.empty((len(self.lanes), steps, body.n_actuators))
        failed = world.failed(0)
        asks = []  # (lane, plan item, the planned entry) of the lanes that choose
        for b, lane in enumerate(self.lanes):
            i = items[b]
            fixed = not self.varies(lane.plan.items[i][0])
            if lane.items and (failed[b] or (lane.playing[0] == i and fixed)):
                lane.chosen.append(lane.names[i])  # nothing to choose: the item plays on
                rows[b] = lane.table(None, t, steps, body.dt)
                continue
            asks.append((b, i, lane.planned(i, t)))
        if asks:
            self._choose(world, asks, rows, t, steps)
        return [rows]

    def _costs(self, world: World, lanes: list[int], tables: list[np.ndarray]) -> np.ndarray:
        """Return the reflex's cost (``upright_cost``) of each table (steps, A) simulated from
        its lane's state (``lanes``), all in one batch (inf where it blew up)."""
        body, rec = self.body, int(self.config.record_every)
        state = State(world.positions(0)[lanes], world.velocities(0)[lanes])
        traj = simulate(body, np.stack(tables), state=state, record_every=rec)
        height = np.einsum("bnk,n->bk", traj.positions[:, -1], body.mass / body.total_mass)[:, 1]
        att = attitude(body, traj.positions)
        cost = upright_cost(height, self.height, rec * body.dt, self.config, att)
        cost[traj.failed] = np.inf
        return cost

    def _choose(self, world: World, asks: list, rows: np.ndarray, t: float, steps: int) -> None:
        """Put each asking lane's chosen activations in ``rows``: the planned entry where its
        own simulation of the window costs nothing (it would win a tie with any variant),
        else the cheapest of it and its righting variants (the first of equals: as planned),
        every simulation of a stage in one batch from the lanes' states."""
        dt, tilt = self.body.dt, self.config.fin_tilt
        planned = [self.lanes[b].table(c, t, steps, dt) for b, _, c in asks]
        first = self._costs(world, [b for b, _, _ in asks], planned)
        for k, (b, i, ctrl) in enumerate(asks):
            lane = self.lanes[b]
            names, ctrls, tabs, c = [lane.names[i]], [ctrl], [planned[k]], [first[k]]
            if first[k] > 0 and self.varies(lane.plan.items[i][0]):
                names, ctrls = righting_entries(self.body, names, ctrls, tilt, self.gentle)
                tabs += [lane.table(x, t, steps, dt) for x in ctrls[1:]]
            asks[k] = (b, i, names, ctrls, tabs, c)
        tried = [a for a in asks if len(a[2]) > 1]  # the lanes that try their variants
        if tried:
            lanes = [a[0] for a in tried for _ in a[2][1:]]
            rest = self._costs(world, lanes, [x for a in tried for x in a[4][1:]])
            at = np.cumsum([0] + [len(a[2]) - 1 for a in tried])
            for n, a in enumerate(tried):
                a[5].extend(rest[at[n] : at[n + 1]])
        for b, i, names, ctrls, tabs, c in asks:
            lane = self.lanes[b]
            c = np.array(c)
            best = int(np.argmin(c)) if np.isfinite(c).any() else 0
            if not np.isfinite(c).any() and lane.blown is None:
                lane.blown = t
            new = lane.take(i, names[best], ctrls[best], t)
            rows[b] = tabs[best] if new else lane.table(None, t, steps, dt)


def shared_windows(plans: list[SequenceController], seconds: float, interval: float, grid: float):
    """Return the windows of plans played side by side: (start s, each plan's item); refuse
    plans whose windows differ (each item's start must fall on the same grid of windows)."""
    each = [_decisions(p, seconds, interval, grid) for p in plans]
    times = [t for t, _ in each[0]]
    for d in each[1:]:
        if len(d) != len(times) or not np.allclose([t for t, _ in d], times):
            raise ValueError("plans played side by side must share their windows")
    return [(t, [d[k][1] for d in each]) for k, t in enumerate(times)]


class _Paths(Observer):
    """The animal's positions in every lane (B, N, 3) at each record, and the times (s)."""

    def __init__(self) -> None:
        self.frames: list[np.ndarray] = []
        self.times: list[float] = []

    def record(self, world: World) -> None:
        self.frames.append(world.positions(0))
        self.times.append(world.time)


@dataclass
class RightedPlans:
    """Plans played side by side with the righting reflex: the recorded paths and choices."""

    body: Body
    times: np.ndarray  # (R,) s
    positions: np.ndarray  # (B, R, N, 3) m
    lanes: list[_Lane]
    seconds: float

    @property
    def failed(self) -> np.ndarray:
        """Return (B,) bools: True where a plan and all its variants blew up."""
        blown = np.array([lane.blown is not None for lane in self.lanes])
        return blown | ~np.isfinite(self.positions).all(axis=(1, 2, 3))

    def trajectory(self) -> Trajectory:
        """Return the paths as a physics Trajectory (no final state; failed lanes at step 0)."""
        failed = np.where(self.failed, 0, -1)
        return Trajectory(self.times, self.positions, None, failed, self.body.dt)

    def result(self, b: int = 0) -> UprightResult:
        """Return plan ``b`` as played: its recorded controller, items, path and motion."""
        lane = self.lanes[b]
        seq, starts = sequence_of(lane.ctrls, lane.items, self.seconds, lane.plan.overlap)
        return UprightResult(
            sequence=seq,
            names=lane.labels,
            starts=starts,
            times=self.times,
            positions=self.positions[b],
            evaluations=lane.chosen,
            motion=locomotion(self.body, self.positions[b], self.times),
        )


def right_plans(
    body: Body,
    plans: list[tuple[list[str], SequenceController]],
    seconds: float,
    config: TrackConfig = TrackConfig(),
    gentle: float = GENTLE,
) -> RightedPlans:
    """Return plans (each its items' entry names and the plan) played side by side for
    ``seconds`` with the fins' righting reflex, one lane each, through the one closed-loop
    driver; the plans' items must start on the same windows (``shared_windows``)."""
    rec, dt = int(config.record_every), body.dt
    world = World([body], batch=len(plans))
    height = float(world.positions(0)[0].T[1] @ body.mass / body.total_mass)
    decisions = shared_windows([p for _, p in plans], seconds, config.interval, rec * dt)
    lanes = [_Lane(list(n), p) for n, p in plans]
    reflex = _Righting(body, lanes, config, decisions, height, gentle)
    path = _Paths()
    schedule = Schedule(config.interval, record_every=rec, plan=reflex.window)
    drive(world, reflex, seconds, schedule, (path,))
    positions = np.stack(path.frames, axis=1)
    return RightedPlans(body, np.array(path.times), positions, lanes, float(seconds))


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
    played = right_plans(body, [(names, plan)], seconds, config, gentle)
    blown = played.lanes[0].blown
    if blown is not None:
        raise SimulationError(f"the plan and its righting variants blew up at t = {blown:.2f} s")
    return played.result(0)
