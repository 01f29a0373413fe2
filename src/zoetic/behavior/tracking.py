"""Greedy target tracking with a repertoire of abstracted controllers (section 3.1, Fig. 5).

At each re-evaluation point the animal simulates every repertoire entry forward from its
current state over the next interval, all entries as one batch, and keeps the one with the
greatest immediate gain: the drop in its cost to go, which is the 3D distance from its centre
of mass to the current target, plus the bearing of the target off its heading, plus a depth
term once it is further than a band above or below the target's depth, plus an attitude term
once it rolls or pitches past what swimming needs, the roll judged also where its rate at the
end of the window leads (less a penalty for time spent inside obstacle discs). Besides each
entry it tries the entry with the pectoral fins tilted apart either way (``righting_entries``):
swimming leaves the body no roll stiffness and little roll damping, so a roll left by a turn
stays or grows unless the fins roll it back. When the centre of mass comes within the
reaching radius of the target, in 3D, it moves on to the next target.

Targets are (x, y, z): x forward, z to the animal's left, both m from the origin where the
animal starts, and y m above the depth it starts at (0: hold the start depth; negative:
deeper). The chosen entries are recorded as a SequenceController: a newly chosen entry starts
at its own t = 0 and is cross-faded with the previous one over 5% of the previous one's
length, so the recorded controller, played from rest, reproduces the tracked motion.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.targets import TrackingError, as_targets
from zoetic.bodies import Body
from zoetic.control import Controller
from zoetic.control.abstract import AbstractController, SequenceController
from zoetic.control.loop import Observer, Schedule, drive
from zoetic.control.measure import locomotion, motion_scalars
from zoetic.control.policy import Period
from zoetic.control.rollout import rollout
from zoetic.errors import SimulationError
from zoetic.physics import State, Trajectory, get_medium, rest_state, simulate
from zoetic.physics.world import World

RESTART = 2.0  # s an entry plays before the tracker restarts it (keeps cross-fades short)
OVERLAP = 0.05  # cross-fade: fraction of each controller's length shared with the next


def body_length(body: Body) -> float:
    """Return the animal's length (m) along its forward axis in the rest pose (``Body.length``)."""
    return body.length


def obstacle_seconds(com_xz: np.ndarray, obstacles: np.ndarray, dt: float) -> np.ndarray:
    """Return the time (s) each path (..., R, 2) spends inside any obstacle disc (x, z, r)."""
    if obstacles is None or len(obstacles) == 0:
        return np.zeros(com_xz.shape[:-2])
    obs = np.asarray(obstacles, float).reshape(-1, 3)
    d = np.linalg.norm(com_xz[..., None, :] - obs[:, :2], axis=-1)  # (..., R, O)
    inside = np.any(d < obs[:, 2], axis=-1)
    return inside[..., 1:].sum(axis=-1) * dt


def cost_to_go(
    body: Body,
    positions: np.ndarray,
    target: np.ndarray,
    turn_radius: float,
    record_dt: float,
    config: TrackConfig,
    attitude: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """Return the distance (m) still to swim at the end of each path (B, R, N, 3) to ``target``
    (x, y, z in the world).

    That is the centre of mass's 3D distance to the target, plus ``turn_radius`` times the
    bearing (rad) of the target off the heading in the horizontal plane (faded out within a
    reaching radius or two of the target's x, z, where any heading will do), plus
    ``config.depth_weight`` times the depth error past ``config.depth_band``, plus
    ``config.attitude_weight`` times the worst roll and pitch (rad) past what swimming needs
    (``attitude``: roll and pitch (B, R) in degrees over each path). The heading (nose minus
    centre of mass) is averaged over the last half second, so one gait cycle's head swing
    cancels out.
    """
    w = body.mass / body.total_mass
    tail = positions[:, -max(1, int(round(0.5 / record_dt))) :]
    com3 = np.einsum("brnk,n->brk", tail, w)
    com = com3[..., [0, 2]]
    goal = np.asarray(target, float)
    d = np.linalg.norm(com3[:, -1] - goal, axis=-1)
    cost = d + upright_cost(com3[:, -1, 1], goal[1], record_dt, config, attitude)
    if turn_radius <= 0:
        return cost
    h = tail[:, :, body.head, :][..., [0, 2]] - com
    h = (h / (np.linalg.norm(h, axis=-1, keepdims=True) + 1e-12)).mean(axis=1)
    g = goal[[0, 2]] - com[:, -1]
    dxz = np.linalg.norm(g, axis=-1)
    cos = np.sum(h * g, axis=-1) / (np.linalg.norm(h, axis=-1) * dxz + 1e-12)
    fade = np.clip(dxz / (2.0 * config.radius_or(body)), 0.0, 1.0)
    return cost + fade * turn_radius * np.arccos(np.clip(cos, -1.0, 1.0))


def upright_cost(
    height: np.ndarray,
    goal_height: float,
    record_dt: float,
    config: TrackConfig,
    attitude: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """Return the cost (m) of where each path (B,) ends up off depth and upright:
    ``config.depth_weight`` times the end height's (m) error from ``goal_height`` past
    ``config.depth_band``, plus ``config.attitude_weight`` times the worst roll and pitch (rad)
    past what swimming needs (``attitude``: roll and pitch (B, R) deg over each path), the roll
    judged also ``config.roll_lookahead`` s past the end at its rate there."""
    dy = np.abs(np.asarray(height, float) - goal_height)
    cost = config.depth_weight * np.maximum(dy - config.depth_band, 0.0)
    if attitude is not None:
        roll, pitch = (np.nanmax(np.abs(a), axis=1) for a in attitude)
        roll = np.maximum(roll, np.abs(_ahead(attitude[0], record_dt, config.roll_lookahead)))
        over = np.maximum(roll - config.roll_ok, 0) + np.maximum(pitch - config.pitch_ok, 0)
        cost = cost + config.attitude_weight * np.radians(over)
    return cost


def _ahead(angle: np.ndarray, record_dt: float, seconds: float) -> np.ndarray:
    """Return angles (B, R) deg extrapolated ``seconds`` past the end at their mean rate over
    the last half second (B,): where a roll that is still gathering pace will be."""
    n = max(1, min(angle.shape[1] - 1, int(round(0.5 / record_dt))))
    rate = (angle[:, -1] - angle[:, -1 - n]) / (n * record_dt)
    return angle[:, -1] + seconds * rate


@dataclass(frozen=True)
class TrackConfig:
    """Knobs of greedy tracking: re-evaluation interval (s), reaching radius (m), time limit."""

    interval: float = 1.0
    radius: float | None = None  # default: half the body length
    time_limit: float = 120.0
    record_every: int = 4
    turn_radius: float | None = None  # m per rad of bearing in the cost-to-go; None: 1.5 lengths
    obstacles: np.ndarray | None = None  # (O, 3) discs x, z, r that the gain penalises
    obstacle_weight: float = 1.0  # m of gain lost per second inside an obstacle
    allowed: tuple[str, ...] | None = None  # entries it may use (default: all)
    # the depth and attitude terms and the fins' righting, set so that the default shark
    # repertoire holds depth within 0.5 m and roll within 30 degrees over the courses of
    # ``zoetic bench track`` (without the righting variants and the look-ahead it rolled 64)
    depth_band: float = 0.15  # m above or below the target's depth that costs nothing
    depth_weight: float = 6.0  # m of cost per m of depth error past the band
    roll_ok: float = 15.0  # deg of roll that costs nothing
    pitch_ok: float = 20.0  # deg of pitch that costs nothing (climbing and diving need some)
    attitude_weight: float = 6.0  # m of cost per rad of roll or pitch past those
    roll_lookahead: float = 0.5  # s: the roll is also judged where its rate at the end leads
    fin_tilt: float = 0.3  # activation the righting variants tilt the fins apart (0: none)

    def radius_or(self, body: Body) -> float:
        """Return the reaching radius (m): the configured one, else half the body length."""
        return float(self.radius) if self.radius is not None else 0.5 * body_length(body)


@dataclass
class TrackResult:
    """What tracking produced: the path, the recorded controller and how fast it ran."""

    times: np.ndarray  # (R,) s
    positions: np.ndarray  # (R, N, 3) m
    com: np.ndarray  # (R, 3) m
    targets: np.ndarray  # (M, 3) x, y, z in the world (y: the target's height, m)
    radius: float
    sequence: SequenceController
    names: list[str]  # the entry name of each sequence item
    starts: np.ndarray  # (n,) s: when each item started
    reached: np.ndarray  # (M,) s: when each target was reached, NaN if never
    evaluations: list[str] = field(default_factory=list)  # entry chosen at each re-evaluation
    wall: float = 0.0  # s spent tracking (simulation and choice; no compile, no video)
    compile_wall: float = 0.0
    record_every: int = 1  # simulation steps between recorded positions
    motion: dict = field(default_factory=dict)  # locomotion(): depth change, worst roll, pitch

    @property
    def sim_time(self) -> float:
        """Return the simulated time (s)."""
        return float(self.times[-1])

    @property
    def realtime_factor(self) -> float:
        """Return simulated seconds per wall-clock second."""
        return self.sim_time / max(self.wall, 1e-9)

    @property
    def start_indices(self) -> np.ndarray:
        """Return the indices into the recorded path where each controller started."""
        return np.searchsorted(self.times, self.starts - 1e-9)

    def summary(self) -> dict:
        """Return the numbers worth printing and saving."""
        done = np.isfinite(self.reached)
        return {
            "targets": len(self.targets),
            "reached": int(done.sum()),
            "reach_times_s": [round(float(t), 2) if np.isfinite(t) else None for t in self.reached],
            "simulated_s": round(self.sim_time, 2),
            "wall_s": round(self.wall, 3),
            "realtime_factor": round(self.realtime_factor, 1),
            "compile_s": round(self.compile_wall, 2),
            "controllers": len(self.names),
            "re_evaluations": len(self.evaluations),
            "radius_m": round(self.radius, 3),
            "reached_in": "3D",
            **self.motion,
        }


def _candidate_tables(ctrls, current, t, steps, dt, restart: bool = False) -> np.ndarray:
    """Return (K, steps, A): each entry started at time t, cross-faded from the current one;
    the current one carries on, or with ``restart`` starts afresh like the others."""
    tables = []
    for k, ctrl in enumerate(ctrls):
        if current is None:
            tables.append(ctrl.table(steps, dt))
            continue
        ci, start = current
        held = t - start
        if k == ci and not restart:
            tables.append(ctrls[ci].table(steps, dt, t0=held))
            continue
        window = steps * dt
        seq = SequenceController(
            ctrl.animal,
            ctrl.actuators,
            ((ctrls[ci], held / (1 - OVERLAP)), (ctrl, window / (1 - OVERLAP) + 1.0)),
            OVERLAP,
        )
        tables.append(seq.table(steps, dt, t0=held))
    return np.stack(tables)


def righting_entries(
    body: Body, names: list[str], ctrls: list[Controller], tilt: float, gentle: float = 1.0
) -> tuple[list[str], list[Controller]]:
    """Return the entries followed by each one's two fin-righting variants: the same muscle
    actions with the pectoral fins' activations ``tilt`` apart, the left one raised and the
    right one lowered ("+roll-left": the back rolls toward the animal's left, negative roll
    as the sensors count it) or the other way ("+roll-right").

    The swimming body has no roll stiffness and, while its muscles undulate, little roll
    damping: a roll left by a turn stays or grows. The fins, tilted apart, roll it back as
    a fish's pectoral fins do; the tracker picks a variant when its own simulation of the next
    window says it keeps the animal nearer upright. Entries that are not abstractions (no
    offsets to shift) or do not swim (no modes: fins roll nothing without a flow past them),
    and bodies without a left and a right fin, get none. With ``gentle`` < 1 each also gets
    "+gentle" variants, its muscles' stroke amplitudes scaled by ``gentle``, with and without
    the fins tilted: a hard stroke can spin the body faster than the fins roll it back."""
    kind, side = np.array(body.actuator_kind), np.array(body.actuator_side)
    fins = kind == "fin"
    if tilt <= 0 or not (np.any(fins & (side == "left")) and np.any(fins & (side == "right"))):
        return names, ctrls
    shift = np.where(fins & (side == "left"), 0.5, 0.0) - np.where(
        fins & (side == "right"), 0.5, 0.0
    )
    soft = np.where(kind == "muscle", gentle, 1.0)[:, None]
    out_n, out_c = list(names), list(ctrls)
    for name, ctrl in zip(names, ctrls, strict=True):
        if not isinstance(ctrl, AbstractController) or ctrl.modes == 0:
            continue
        kinds = [(name, ctrl)] + [
            (f"{name}+gentle", dataclasses.replace(ctrl, amp=ctrl.amp * soft))
        ]
        for base, c in kinds[: 1 + (gentle < 1)]:
            if c is not ctrl:
                out_n.append(base)
                out_c.append(c)
            for label, sign in (("roll-left", 1.0), ("roll-right", -1.0)):
                out_n.append(f"{base}+{label}")
                out_c.append(dataclasses.replace(c, offset=c.offset + sign * tilt * shift))
    return out_n, out_c


def _entries(repertoire: Repertoire, allowed) -> tuple[list[str], list[Controller]]:
    names = list(repertoire.names if allowed is None else allowed)
    missing = [n for n in names if n not in repertoire.controllers]
    if missing or not names:
        raise TrackingError(
            f"the repertoire has no entries {missing or names}; it holds {repertoire.names}"
        )
    return names, [repertoire.controllers[n] for n in names]


class PathRecorder(Observer):
    """The animal's positions (lane 0) at each record, and the records' times (s)."""

    def __init__(self) -> None:
        self.frames: list[np.ndarray] = []
        self.times: list[float] = []

    def record(self, world: World) -> None:
        self.frames.append(world.positions(0)[0])
        self.times.append(world.time)


@dataclass
class _Greedy:
    """The tracker's decisions: at each re-evaluation it simulates every entry over the next
    window from the world's state (one batch) and plays the one of greatest gain."""

    body: Body
    ctrls: list[Controller]
    names: list[str]
    targets: np.ndarray
    config: TrackConfig
    radius: float
    turn_radius: float
    progress: Callable[[float, int], None] | None = None
    t: float = 0.0  # s, the start of the next window
    fade_end: float = 0.0  # s, when the last cross-fade ends
    goal: int = 0  # the target being tracked
    items: list[list] = field(default_factory=list)  # [entry index, start time]
    chosen: list[str] = field(default_factory=list)  # entry chosen at each re-evaluation
    times: list[float] = field(default_factory=lambda: [0.0])  # s, of the records

    def __post_init__(self) -> None:
        self.reached = np.full(len(self.targets), np.nan)
        self.medium = get_medium(self.body.medium)

    def window(self, world: World) -> int:
        """Return the steps of the next window: the interval, or to the end of a cross-fade,
        in whole records."""
        dt, rec = self.body.dt, int(self.config.record_every)
        window = max(self.config.interval, self.fade_end - self.t, rec * dt)
        return int(np.ceil(window / dt / rec)) * rec

    def __call__(self, world: World, period: Period) -> list[np.ndarray]:
        """Return the activations (1, T, A) of the entry of greatest gain over ``period``."""
        body, dt, rec, k = self.body, self.body.dt, int(self.config.record_every), len(self.ctrls)
        current = None if not self.items else (self.items[-1][0], self.items[-1][1])
        # an entry held long is restarted at each choice, so that the cross-fade into the next
        # one (a share of the held time) stays short and a correction takes effect at once
        restart = current is not None and self.t - current[1] >= RESTART
        tables = _candidate_tables(self.ctrls, current, self.t, period.steps, dt, restart)
        state = State(world.positions(0), world.velocities(0))
        traj = simulate(body, tables, state=repeat_state(state, k), record_every=rec)
        com3 = np.einsum("brnk,n->brk", traj.positions, body.mass / body.total_mass)
        com = com3[..., [0, 2]]
        m = motion_scalars(body, traj.positions, traj.times, self.medium)
        # the cost-to-go at the start is the same for every entry, so the gain ranks as its drop
        gain = -cost_to_go(
            body,
            traj.positions,
            self.targets[self.goal],
            self.turn_radius,
            rec * dt,
            self.config,
            (m["roll"], m["pitch"]),
        )
        gain -= self.config.obstacle_weight * obstacle_seconds(com, self.config.obstacles, rec * dt)
        gain[traj.failed] = -np.inf
        if not np.isfinite(gain).any():
            raise SimulationError(f"every repertoire entry blew up at t = {self.t:.2f} s")
        best = int(np.argmax(gain))
        self.chosen.append(self.names[best])
        if current is None or best != current[0] or restart:
            if current is not None:
                self.fade_end = self.t + (self.t - current[1]) * OVERLAP / (1 - OVERLAP)
            self.items.append([best, self.t])
        for r in range(1, traj.positions.shape[1]):
            while (
                self.goal < len(self.targets)
                and np.linalg.norm(com3[best, r] - self.targets[self.goal]) < self.radius
            ):
                self.reached[self.goal] = self.t + r * rec * dt
                self.goal += 1
        self.times.extend(self.t + np.arange(1, traj.positions.shape[1]) * rec * dt)
        self.t += period.steps * dt
        return [tables[best][None]]

    def done(self, world: World) -> bool:
        """Report progress; return True once every target is reached or time is up."""
        if self.progress is not None:
            self.progress(self.t, self.goal)
        return self.goal >= len(self.targets) or self.t >= self.config.time_limit - 1e-9


def track(
    body: Body,
    repertoire: Repertoire,
    targets: np.ndarray,
    config: TrackConfig = TrackConfig(),
    progress: Callable[[float, int], None] | None = None,
) -> TrackResult:
    """Return the path of the animal greedily tracking ``targets`` in turn, its World run
    through the one closed-loop driver (each window one control period).

    targets: (M, 3) x, y, z, y relative to the start depth, or (M, 2) x, z at the start
    depth. progress(t, reached) is called after every re-evaluation.
    """
    targets = as_targets(targets)
    if len(targets) == 0:
        raise TrackingError("give at least one target")
    names, ctrls = righting_entries(body, *_entries(repertoire, config.allowed), config.fin_tilt)
    radius = config.radius_or(body)
    if not radius > 0 or not config.interval > 0 or not config.time_limit > 0:
        raise TrackingError("radius, interval and time limit must be positive")
    dt, rec = body.dt, int(config.record_every)
    lam = 1.5 * body_length(body) if config.turn_radius is None else float(config.turn_radius)
    t0 = time.perf_counter()
    state = rest_state(body, 1)
    targets = targets + [0.0, float(state.positions[0].T[1] @ body.mass / body.total_mass), 0.0]
    simulate(
        body, np.zeros((len(ctrls), rec, body.n_actuators)), state=repeat_state(state, len(ctrls))
    )
    compile_wall = time.perf_counter() - t0

    world = World([body])
    greedy = _Greedy(body, ctrls, names, targets, config, float(radius), lam, progress)
    path = PathRecorder()
    # the run ends at ``done``; a window that starts before the time limit plays whole, so
    # the driver's own end lies past the longest window that can start then
    longest = max(config.interval, config.time_limit * OVERLAP / (1 - OVERLAP)) + 2 * rec * dt
    schedule = Schedule(config.interval, record_every=rec, record_end=False, plan=greedy.window)
    start = time.perf_counter()
    drive(world, greedy, config.time_limit + longest, schedule, (path,), stop=greedy.done)
    wall = time.perf_counter() - start
    seq, starts = sequence_of(ctrls, greedy.items, greedy.t)
    positions = np.array(path.frames)
    w = body.mass / body.total_mass
    return TrackResult(
        times=np.array(greedy.times),
        positions=positions,
        com=np.einsum("rnk,n->rk", positions, w),
        targets=targets,
        radius=float(radius),
        sequence=seq,
        names=[names[i] for i, _ in greedy.items],
        starts=starts,
        reached=greedy.reached,
        evaluations=greedy.chosen,
        wall=wall,
        compile_wall=compile_wall,
        record_every=rec,
        motion=locomotion(body, positions, np.array(greedy.times)),
    )


def repeat_state(state: State, k: int) -> State:  # the state over k lanes
    return State(np.repeat(state.positions, k, axis=0), np.repeat(state.velocities, k, axis=0))


def sequence_of(ctrls, items, t_end: float, overlap: float = OVERLAP):
    """Return the items ([index into ``ctrls``, start s]) as one SequenceController, each
    lasting to the next one's start plus the cross-fade (``overlap`` of its length), the
    last to ``t_end``, and the items' starts (s)."""
    starts = np.array([s for _, s in items], float)
    ends = np.append(starts[1:], t_end)
    seq_items = []
    for i, (k, s) in enumerate(items):
        last = i == len(items) - 1
        seq_items.append((ctrls[k], (ends[i] - s) if last else (ends[i] - s) / (1 - overlap)))
    ctrl = ctrls[0]
    return SequenceController(ctrl.animal, ctrl.actuators, tuple(seq_items), overlap), starts


def replay(body: Body, result: TrackResult) -> Trajectory:
    """Return the trajectory of the recorded sequence played from rest in a World (for checks,
    video), recorded every ``result.record_every`` steps."""
    steps = int(round(result.sim_time / body.dt))
    table = result.sequence.table(steps, body.dt)
    seconds = steps * body.dt
    ro = rollout(World([body]), table[None], seconds, seconds, record_every=result.record_every)
    return ro.trajectory(0)
