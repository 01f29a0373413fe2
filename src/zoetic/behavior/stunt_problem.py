"""A trick over a repertoire as a search problem: plans of repertoire entries played in a World
beside the trick's objects, recorded through the one closed-loop driver and scored by the
trick's style terms (which here also see the World's contact record and the balls). A trick
without objects has nothing to touch: its plans are recorded by the open-loop kernel, which
steps them as the World would.

With a trick's ``jitter`` (and ``robust``) each plan is played from its start and two perturbed ones
(``SEARCH_SIGNS``) and its E is the worst of them: the search then prefers plans that do not
hinge on the exact start (a somersault found from one start turned 174-376 deg when its start
moved a few cm or degrees). ``CHECK_SIGNS`` are the starts a found plan is checked from."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from zoetic.behavior.macro import MacroProblem
from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.targets import TrackingError
from zoetic.behavior.tricks import Trick
from zoetic.bodies import Body
from zoetic.control.loop import Observer, Schedule, drive
from zoetic.physics import Trajectory, get_medium
from zoetic.physics.objects import Ball
from zoetic.physics.simulate import State, kernel_layout, simulate_laid_out
from zoetic.physics.world import World
from zoetic.tasks import check_fits, start_state
from zoetic.tasks.terms import BodyFrame, Signals, evaluate_terms, term_names

# each start as signs of the trick's jitter (depth, heading, pitch): the start itself, one
# deeper, turned left and nose up, one shallower, turned right and nose down
SEARCH_SIGNS = ((0, 0, 0), (1, 1, 1), (-1, -1, -1))
# a found plan's check: one jitter at a time, each way (none of them a search start)
CHECK_SIGNS = ((1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1))


def starts_per_plan(trick: Trick) -> int:
    """Return how many starts the search plays each plan of the trick from (3 robust, else 1)."""
    return len(SEARCH_SIGNS) if trick.robust and any(trick.jitter) else 1


def jittered_starts(trick: Trick, body: Body, signs) -> State:
    """Return the trick's start moved by ``signs`` (K, 3) x its jitter (depth m, heading and
    pitch deg), one start per row (K, N, 3)."""
    st = trick.task.starts[0]
    dd, dh, dp = trick.jitter
    each = []
    for a, b, c in signs:
        moved = dataclasses.replace(
            st,
            depth=None if st.depth is None else st.depth + a * dd,
            heading=st.heading + math.radians(b * dh),
            pitch=st.pitch + math.radians(c * dp),
        )
        each.append(start_state(dataclasses.replace(trick.task, starts=(moved,)), body))
    return State(
        np.concatenate([s.positions for s in each]), np.concatenate([s.velocities for s in each])
    )


@dataclass
class StuntRecord:
    """A batch of stunts as the terms see them: trajectories plus the world's records."""

    traj: Trajectory  # positions (B, R, N, 3), times (R,)
    activations: np.ndarray  # (B, R, A) at the records
    contacts: np.ndarray  # (B, R) node-object contacts since the previous record
    balls: np.ndarray  # (B, R, nb, 3)
    failed: np.ndarray  # (B,)
    touch: np.ndarray | None = None  # (B, R, N, O) |impulse| (N s) each node got from each object


class _Frames(Observer):
    """At each record: the animal's positions, the balls, the node-object contacts and the
    |impulse| (N s) each node got from each object since the previous record."""

    def __init__(self, world: World) -> None:
        self.times: list[float] = []
        self.positions: list[np.ndarray] = []
        self.balls: list[np.ndarray] = []
        self.counts: list[np.ndarray] = []
        self.touch: list[np.ndarray] = []
        self._count = np.zeros(world.batch, dtype=np.int64)
        self._impulse = np.zeros((world.batch, world.bodies[0].n_nodes, len(world.objects), 3))
        self._untouched = np.zeros(self._impulse.shape[:-1])  # |impulse| of no contact
        self._touched = False  # any node tested against the objects since the last record

    def slice(self, world: World, contacts) -> None:
        # the animal's impulses are zero in a slice that did not test its nodes (``near``)
        if world.objects and (contacts.near is None or 0 in contacts.near):
            self._count = self._count + contacts.count  # a new array: records keep the old
            self._impulse += contacts.impulse[0]
            self._touched = True

    def record(self, world: World) -> None:
        self.times.append(world.time)
        self.positions.append(world.positions(0))
        self.balls.append(world.ball_positions)
        self.counts.append(self._count)
        if not self._touched:  # the counts stay zero and nothing touched
            self.touch.append(self._untouched)
            return
        self.touch.append(np.linalg.norm(self._impulse, axis=-1))
        self._count = np.zeros_like(self._count)
        self._impulse = np.zeros_like(self._impulse)
        self._touched = False


class StuntProblem(MacroProblem):
    """A trick over a repertoire: plans of L (entry, duration) segments, scored in batches."""

    # a trick without objects is recorded by the open-loop kernel in one call per batch
    # (``_open_loop``); False: through its World, slice by slice, as a trick with objects
    open_loop = True

    def __init__(
        self,
        body: Body,
        repertoire: Repertoire,
        trick: Trick,
        segments: int | None = None,
        record_every: int | None = None,
        allowed: tuple[str, ...] | None = None,
    ):
        check_fits(trick.task, body)
        self.body, self.trick, self.task = body, trick, trick.task
        self.names = list(repertoire.names if allowed is None else allowed)
        missing = [n for n in self.names if n not in repertoire.controllers]
        if missing or not self.names:
            raise TrackingError(f"the repertoire has no entries {missing or self.names}")
        self.ctrls = [repertoire.controllers[n] for n in self.names]
        self.segments = int(segments or trick.segments)
        if self.segments < 1:
            raise TrackingError("a plan needs at least one segment")
        self.lower, self.upper = trick.durations
        every = record_every or max(1, int(round(1.0 / (trick.task.record_hz * body.dt))))
        self.record_every = int(every)
        self.steps = max(1, int(round(trick.task.horizon / body.dt / every))) * every
        self.start = start_state(trick.task, body)
        # the starts every plan is scored from (the worst counts): the start, and with a
        # jitter, two perturbed ones
        robust = starts_per_plan(trick) > 1
        self.starts = jittered_starts(trick, body, SEARCH_SIGNS) if robust else self.start
        self.frame = BodyFrame.of(body)
        self.level = get_medium(body.medium).water_level
        self.radius = 0.0

    def world(self, batch: int, starts: State | None = None) -> World:
        """Return the trick's World (the objects, the animal in B lanes): lane b starts from
        ``starts`` row b mod K (default: the trick's start state)."""
        w = World([self.body, *self.trick.objects], medium=self.body.medium, batch=batch)
        st = w.initial_state()
        starts = self.start if starts is None else starts
        rows = np.arange(batch) % len(starts.positions)
        pos = np.array(starts.positions[rows], float)
        vel = np.array(starts.velocities[rows], float)
        w.restore(dataclasses.replace(st, positions=(pos,), velocities=(vel,)))
        return w

    def record(
        self, entries, durations, record_every: int | None = None, starts: State | None = None
    ) -> StuntRecord:
        """Return what plans (B, L) do over the trick's duration: each plan's activation
        table played in one control period from each of ``starts`` (K rows; default the
        trick's start state), lanes plan-major (B K), recorded every ``record_every`` steps
        (default the problem's)."""
        e, d = np.atleast_2d(entries), np.atleast_2d(durations)
        k = 1 if starts is None else len(starts.positions)
        dt = self.body.dt
        tables = np.repeat(self.tables(e, d), k, axis=0)
        every = int(record_every or self.record_every)
        if not self.trick.objects and self.open_loop:
            return self._open_loop(tables, starts, every)
        world = self.world(len(tables), starts)
        seconds = self.steps * dt
        frames = _Frames(world)
        schedule = Schedule(seconds, record_every=every, record_end=False)
        drive(world, lambda w, period: [tables], seconds, schedule, (frames,))
        st = world.state
        traj = Trajectory(
            times=np.array(frames.times) - frames.times[0],
            positions=np.stack(frames.positions, axis=1),
            final=State(st.positions[0], st.velocities[0]),
            failed_step=st.failed_step[0],
            dt=world.dt,
        )
        rows = np.minimum(np.arange(traj.positions.shape[1]) * every, self.steps - 1)
        touch = np.stack(frames.touch, axis=1) if world.objects else None
        return StuntRecord(
            traj,
            tables[:, rows],
            np.stack(frames.counts, axis=1),
            np.stack(frames.balls, axis=1),
            world.failed(0),
            touch,
        )

    def _open_loop(self, tables: np.ndarray, starts: State | None, every: int) -> StuntRecord:
        """``record`` of a trick without objects: nothing to touch, so the World would step
        the animal slice after slice through the kernel as the open-loop simulation does in
        one call (``simulate_laid_out``, on this thread; records in the kernel): the same
        steps, without a slice's bookkeeping. One exception: a lane that blows up is found
        by the kernel's own check, every few steps, not at the end of each slice, so its
        ``failed`` step (and the records it spoils) may differ by those few steps."""
        starts = self.start if starts is None else starts
        rows = np.arange(len(tables)) % len(starts.positions)
        state = State(starts.positions[rows], starts.velocities[rows])
        act_t = kernel_layout(self.steps, self.body.n_actuators, len(tables))
        if self.body.n_actuators:
            act_t[...] = tables.transpose(1, 2, 0)
        traj = simulate_laid_out(
            self.body, act_t, self.body.medium, self.body.dt, state, every, threads=False
        )
        n_rec = traj.positions.shape[1]
        recs = np.minimum(np.arange(n_rec) * every, self.steps - 1)
        b = len(tables)
        return StuntRecord(
            traj,
            tables[:, recs],
            np.zeros((b, n_rec), dtype=np.int64),
            np.zeros((b, n_rec, 0, 3)),
            traj.failed,
            None,
        )

    def ball_index(self) -> int | None:
        """Return the index in the trick's objects of its first ball (None without one)."""
        return next((i for i, ob in enumerate(self.trick.objects) if isinstance(ob, Ball)), None)

    def signals(self, rec: StuntRecord) -> Signals:
        """Return the terms' view of a batch of stunts."""
        k = self.ball_index()
        touch = None if rec.touch is None or k is None else rec.touch[..., k]
        return Signals(
            np,
            self.frame,
            rec.traj.positions,
            rec.activations,
            rec.traj.times,
            self.level,
            self.task.horizon,
            rec.contacts.astype(float),
            rec.balls,
            touch,
        )

    def terms(self, rec: StuntRecord) -> dict[str, np.ndarray]:
        """Return each style term's raw value (B,) by name."""
        vals = evaluate_terms(np, self.signals(rec), self.task.terms)
        return dict(zip(term_names(self.task.terms), vals, strict=True))

    def evaluate(self, entries: np.ndarray, durations: np.ndarray) -> dict:
        """Return E ('cost', inf for a blow-up) of plans (B, L), one batch: the worst over
        the problem's starts; the terms (and 'nominal', the E) from the trick's own start."""
        e = np.atleast_2d(entries)
        k = len(self.starts.positions)
        sc = self.scores(self.record(e, durations, starts=self.starts))
        out = {name: v.reshape(len(e), k)[:, 0] for name, v in sc.items()}
        out["nominal"] = out["cost"]
        out["cost"] = sc["cost"].reshape(len(e), k).max(axis=1)
        return out

    def scores(self, rec: StuntRecord) -> dict:  # type: ignore[override]
        """Return E ('cost', inf for a blow-up or a non-finite E) and each term's value (B,)."""
        terms = self.terms(rec)
        cost = sum(t.weight * v for t, v in zip(self.task.terms, terms.values(), strict=True))
        ok = ~rec.failed & np.isfinite(cost)
        return {"cost": np.where(ok, cost, np.inf), **terms}
