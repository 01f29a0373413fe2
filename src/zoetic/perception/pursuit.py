"""Vision-guided pursuit (seed 003, section 3.2): a predator fish that sees with its eyes,
a reddish prey that wanders and flees, and a yellowish distractor that passes behind it.

Steering is the paper's (section 3.2): "The theta angles are used to compute the left/right
turn angle theta_P shown in Fig. 6, and the phi angles are similarly used to compute an
up/down turn angle phi_P. The fish's turn motor controllers (see Section 2) are invoked to
execute a left/right turn -- left-turn-MC for an above-threshold positive theta_P and
right-turn-MC for negative theta_P -- with |theta_P| as parameter. Up/down turn motor commands
are issued to the fish's pectoral fins, with an above-threshold positive phi_P interpreted as
'up' and negative as 'down'." So the predator hands its motor system the demand the
aquarium's fishes hand theirs (``behavior.aquarium.locomotion.Demand``: speed, turn angle, fin
pitch, and the roll its righting reflex answers) through the same motor skills: built-in
(``MotorLocomotion``: the body's wave calibrated so that a demanded turn is the angle turned)
or learned (``LearnedLocomotion``: a repertoire's steers and sharp turns). The turn is theta_P
above threshold, the fin pitch ``fin_gain`` phi_P; the paper gives no rule for the speed, so
the swim motor controller is asked for the fastest the skills swim. Both turn angles are the
gaze relative to the body's mean heading (``eyes.body_frame``): the head's wag does not steer."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from zoetic.behavior.aquarium.locomotion import (
    Demand,
    LearnedLocomotion,
    Locomotion,
    MotorLocomotion,
    learned_motor,
)
from zoetic.behavior.aquarium.species import BUILT_IN, LEARNED, SKILLS_DIR
from zoetic.bodies import Body, load_animal
from zoetic.control import steered_wave
from zoetic.control.loop import Observer, Schedule, drive
from zoetic.control.policy import Period
from zoetic.control.sensors import observe, wrap_angle
from zoetic.errors import ZoeticError
from zoetic.perception.eyes import EyeSpec, body_frame, gaze_angles, head_frame, look
from zoetic.perception.gaze import GazeController, GazeState, fixation
from zoetic.perception.recognition import histogram
from zoetic.physics.objects import Ball, Box, Cylinder
from zoetic.physics.world import Animal, World
from zoetic.render import Cameras, look_rotation, render, world_mesh
from zoetic.render.scene import Mesh, merge

PREDATOR, PREY, DISTRACTOR = (0.45, 0.5, 0.58), (0.85, 0.22, 0.16), (0.9, 0.8, 0.2)
FOG = (0.05, 0.25, 0.35)
SEABED_LEVEL, SEABED_EXTENT = -2.0, 30.0


def steer(
    body: Body, times: np.ndarray, bias: float, amplitude: float = 1.0, pitch: float = 0.0
) -> np.ndarray:
    """Return activations (T, A): the body's own wave steered (``control.steered_wave``):
    ``bias`` > 0 turns left, ``pitch`` > 0 tilts the fins nose up (the animal rises)."""
    return steered_wave(body, times, amplitude, bias, pitch)


@dataclass
class Scenery:
    """The fixed part of the picture and the animals' colours."""

    colors: tuple
    floor: tuple = (0.0, 0.0, SEABED_LEVEL, SEABED_EXTENT)
    _static: dict = field(default_factory=dict, repr=False)

    def mesh(self, world: World, positions=None) -> Mesh:
        """Return the world's triangles now (lane 0), or with the animals at ``positions``
        (one (N, 3) array each); the fixed objects and seabed are built once."""
        key = id(world)
        if key not in self._static:
            fixed = [o for o in world.objects if not isinstance(o, Ball)]
            self._static[key] = world_mesh([], [], [], fixed, None, self.floor)
        pos = positions or [world.positions(a)[0] for a in range(len(world.animals))]
        moving = world_mesh(world.bodies, pos, self.colors, world.balls, world.ball_positions[0])
        return merge(moving, self._static[key])


@dataclass
class VisionRecord:
    """One frame of the predator's vision: gaze angles (2, 2), the locks, the turn angles,
    the triangulated range (m), the component images (2, L, S, S, 3), the cameras' view
    directions and positions (2, 3) that took them, and the gaze rays (2, 3) after the frame
    (the ones the range triangulates)."""

    time: float
    angles: np.ndarray
    locked: np.ndarray
    theta_p: float
    phi_p: float
    range: float
    images: np.ndarray
    eye_dirs: np.ndarray
    eye_pos: np.ndarray
    gaze_dirs: np.ndarray


@dataclass
class PredatorPolicy:
    """A Policy: the predator renders what its eyes see each control period, foveates the
    prey by its colour model, and turns toward the gaze direction (theta_P) through its turn
    motor controllers.

    locomotion: the fish's motor skills (default the built-in ``MotorLocomotion`` asked to
    turn a demanded angle in ``turn_seconds`` s: the gaze is re-read every frame, so this sets
    how hard it steers); threshold: |theta_P|, |phi_P| (rad) below which it swims straight
    and level; search_turn: the turn (rad, left positive) demanded while nothing is in sight;
    fin_gain: fin pitch (rad) per rad of phi_P (the motor layer holds it within
    ``locomotion.MAX_PITCH``); vor: hold the eyes' world directions against the head's own
    rotation between frames (``GazeController.hold``). The roll it feels (sensor "roll") and
    its rate since the last frame go with the demand to the righting reflex, as in the tank.
    """

    world: World
    animal: int
    scenery: Scenery
    gaze: GazeController
    locomotion: Locomotion | None = None
    turn_seconds: float = 0.6
    threshold: float = np.radians(3.0)
    search_turn: float = np.radians(20.0)
    vor: bool = True
    fin_gain: float = 2.0
    sensors: tuple[str, ...] = ("roll",)
    state: GazeState = field(default_factory=GazeState)
    log: list = field(default_factory=list)
    _roll: tuple[float, float] | None = None  # the last roll (rad) felt and when (s)

    def __post_init__(self) -> None:
        if self.locomotion is None:
            body = self.world.bodies[self.animal]
            self.locomotion = MotorLocomotion(body, turn_seconds=self.turn_seconds)

    def reset(self, seed: int | None = None) -> None:
        """Start with the eyes looking ahead, an empty log and no roll felt yet."""
        self.state = GazeState()
        self.log = []
        self._roll = None

    def demand(self, theta_p: float, phi_p: float, roll: float, t: float) -> Demand:
        """Return the motor demand for turn angles theta_P, phi_P (rad) and the roll felt
        (rad) at ``t`` s: theta_P to the turn motor controllers and ``fin_gain`` phi_P to the
        fins when above threshold (the search turn while nothing is locked), at top speed."""
        locked = bool(self.state.locked.any())
        if locked:
            turn = theta_p if abs(theta_p) >= self.threshold else 0.0
        else:
            turn = self.search_turn
        pitch = self.fin_gain * phi_p if locked and abs(phi_p) >= self.threshold else 0.0
        last, self._roll = self._roll, (roll, t)
        rate = 0.0 if last is None or t <= last[1] else wrap_angle(roll - last[0]) / (t - last[1])
        return Demand(self.locomotion.top_speed, turn, pitch, roll, float(rate))

    def act(self, observation: Mapping[str, np.ndarray], period: Period) -> np.ndarray:
        """Return (1, T, A) activations: see, move the eyes, steer."""
        body = self.world.bodies[self.animal]
        pos = self.world.positions(self.animal)[0]
        frame = head_frame(body, pos)
        spec = self.gaze.spec
        if self.vor:
            self.state = self.gaze.hold(self.state, frame)
        images, cams = look(self.scenery.mesh(self.world), frame, self.state.angles, spec, FOG)
        self.state = self.gaze.step(self.state, frame, images, cams)
        a = self.state.angles
        # turn angles: the gaze relative to the body's mean heading, not the wagging head
        look_dir = self.state.directions.sum(0)
        th_p, ph_p = gaze_angles(body_frame(body, pos), look_dir)
        theta_p, phi_p = float(th_p), float(ph_p)
        _, rng = fixation(frame, a, spec) if self.state.locked.all() else (None, np.inf)
        demand = self.demand(theta_p, phi_p, float(observation["roll"][0]), period.t0)
        n = spec.levels
        self.log.append(
            VisionRecord(
                period.t0,
                a.copy(),
                self.state.locked.copy(),
                theta_p,
                phi_p,
                float(rng),
                images,
                cams.rotation[::n, 2].copy(),
                cams.eye[::n].copy(),
                self.state.directions.copy(),
            )
        )
        return self.locomotion.activations(demand, period.times)[None]


def predator_skills(body: Body, skills: str) -> Locomotion | None:
    """Return the predator's motor skills named as a tank species' ``[motor] skills``:
    ``"built-in"`` (None: the policy's own ``MotorLocomotion``), ``"learned"`` (the repertoire
    shipped for the body) or a learned repertoire's directory."""
    if skills == BUILT_IN:
        return None
    directory = SKILLS_DIR / body.name if skills == LEARNED else Path(skills).expanduser()
    if not (directory / "repertoire.json").is_file():
        raise ZoeticError(
            f"skills {skills!r}: no learned repertoire at {directory} (give {BUILT_IN!r}, "
            f"{LEARNED!r} or a directory made by zoetic repertoire train)"
        )
    return LearnedLocomotion(body, learned_motor(body, directory))


@dataclass
class WanderFleePolicy:
    """A Policy for the prey: wanders (a new heading every few seconds), flees straight away
    from the predator when it comes within ``flee_radius``, stays within ``arena`` of the
    start; swims with its wave at ``amplitude`` (slower than a full wave)."""

    world: World
    animal: int
    predator: int
    seed: int = 0
    amplitude: float = 0.5
    flee_radius: float = 1.2
    arena: float = 8.0
    wander_every: float = 4.0
    sensors: tuple[str, ...] = ("com", "heading")
    _rng: np.random.Generator = field(default=None, repr=False)  # type: ignore[assignment]
    _goal: float = 0.0
    _next: float = 0.0
    _home: np.ndarray | None = None

    def reset(self, seed: int | None = None) -> None:
        """Reseed the wandering."""
        self._rng = np.random.default_rng(self.seed if seed is None else seed)
        self._next = 0.0
        self._home = None

    def act(self, observation: Mapping[str, np.ndarray], period: Period) -> np.ndarray:
        """Return (1, T, A) activations steering toward the current goal heading."""
        com, heading = observation["com"][0], float(observation["heading"][0])
        if self._home is None:
            self._home = com.copy()
            self._goal = heading
        pred = self.world.positions(self.predator)[0].mean(0)
        away = com - pred
        if np.hypot(away[0], away[2]) < self.flee_radius:
            self._goal = float(np.arctan2(away[2], away[0]))
        elif np.hypot(*(com - self._home)[[0, 2]]) > self.arena:
            back = self._home - com
            self._goal = float(np.arctan2(back[2], back[0]))
        elif period.t0 >= self._next:
            self._goal = heading + self._rng.uniform(-1.0, 1.0)
            self._next = period.t0 + self.wander_every
        bias = float(np.clip(0.8 * wrap_angle(self._goal - heading), -0.4, 0.4))
        return steer(self.world.bodies[self.animal], period.times, bias, self.amplitude)[None]


@dataclass
class CruisePolicy:
    """A Policy that swims its wave straight at ``amplitude`` (the distractor)."""

    body: Body
    amplitude: float = 0.8
    sensors: tuple[str, ...] = ()

    def reset(self, seed: int | None = None) -> None:
        """Nothing to reset."""

    def act(self, observation: Mapping[str, np.ndarray], period: Period) -> np.ndarray:
        """Return (1, T, A) activations of the wave."""
        return steer(self.body, period.times, 0.0, self.amplitude)[None]


def learn_model(
    body: Body, positions: np.ndarray, color, spec: EyeSpec, distances=(0.6, 1.2, 2.4, 4.0)
) -> np.ndarray:
    """Return the colour histogram of the prey seen alone from the side through the same
    water, its pixels only (by the depth buffer), pooled over views at ``distances`` m (the
    fog shifts its colours with range)."""
    mesh = world_mesh([body], [positions], [color])
    com = positions.mean(0)
    eyes = np.array([com + np.array([0.0, 0.15 * d, d]) for d in distances])
    cam = Cameras(
        eyes,
        look_rotation(com - eyes),
        np.full(len(eyes), np.radians(50.0)),
        (spec.size, spec.size),
    )
    img, depth = render(
        mesh.vertices, mesh.triangles, mesh.colors, cam, FOG, spec.visibility, with_depth=True
    )
    hist = np.mean([histogram(i, np.isfinite(d)) for i, d in zip(img, depth, strict=True)], 0)
    return hist / hist.sum()


@dataclass
class Chase:
    """A pursuit scene: the world (predator 0, prey 1, distractors after), the policies."""

    world: World
    policies: list
    scenery: Scenery
    predator: PredatorPolicy


def make_chase(
    seed: int = 0,
    distractors: int = 1,
    visibility: float = 6.0,
    spec: EyeSpec | None = None,
    start_distance: float | None = None,
    rocks: bool = True,
    prey_height: float = 0.0,
    skills: str = BUILT_IN,
) -> Chase:
    """Return a chase scene: a shark with eyes, a reddish prey ahead of it (off to one side,
    in its periphery, ``prey_height`` m above it), yellowish distractors crossing behind the
    prey, rocks and seaweed; the shark swims by ``skills`` (``predator_skills``)."""
    if distractors < 0:
        raise ZoeticError(f"distractors must be 0 or more, got {distractors}")
    rng = np.random.default_rng(seed)
    shark = load_animal("shark")
    spec = spec or EyeSpec.of(shark, visibility=visibility)
    d = start_distance if start_distance is not None else rng.uniform(2.5, 3.5)
    bearing = rng.choice([-1, 1]) * rng.uniform(0.35, 0.6)
    prey_at = np.array([d * np.cos(bearing), prey_height, d * np.sin(bearing)])
    members: list = [
        Animal(shark, (0.0, 0.0, 0.0), 0.0),
        Animal(shark, tuple(prey_at), float(rng.uniform(-0.8, 0.8))),
    ]
    for k in range(distractors):
        side = -1.0 if k % 2 == 0 else 1.0
        start = prey_at + np.array([2.0 + 0.8 * k, 0.3 * k, 3.0 * side])
        members.append(Animal(shark, tuple(start), float(-side * np.pi / 2)))
    if rocks:
        for k in range(6):
            x, z = rng.uniform(-3, 12), rng.choice([-1, 1]) * rng.uniform(3.0, 8.0)
            h = rng.uniform(0.3, 0.7)
            members.append(
                Box((x, SEABED_LEVEL + h, z), (h, h, rng.uniform(0.3, 0.8)), name=f"rock{k}")
            )
        for k in range(10):
            x, z = rng.uniform(-3, 14), rng.choice([-1, 1]) * rng.uniform(2.5, 9.0)
            ln = rng.uniform(1.0, 1.8)
            members.append(Cylinder((x, SEABED_LEVEL + 0.5 * ln, z), 0.04, ln, name=f"seaweed{k}"))
    world = World(members, medium="water")
    colors = (PREDATOR, PREY) + (DISTRACTOR,) * distractors
    scenery = Scenery(colors)
    model = learn_model(shark, world.positions(1)[0], PREY, spec)
    loco = predator_skills(shark, skills)
    pred = PredatorPolicy(world, 0, scenery, GazeController(model, spec), loco)
    pols = [pred, WanderFleePolicy(world, 1, 0, seed=seed)]
    pols += [CruisePolicy(shark) for _ in range(distractors)]
    return Chase(world, pols, scenery, pred)


@dataclass
class ChaseResult:
    """What a chase recorded: times (R,), positions per animal (R, N, 3), the predator's
    vision log (one record per frame), caught and when (s, or None), the prey's surface
    triangles (F, 3) (what its range is measured to)."""

    times: np.ndarray
    positions: list
    log: list
    caught: bool
    time_to_catch: float | None
    catch_radius: float
    prey_faces: np.ndarray


def gazed_range(faces: np.ndarray, nodes: np.ndarray, eyes: np.ndarray, gaze: np.ndarray) -> float:
    """Return the range (m, from the midpoint of the eyes ``eyes`` (2, 3)) of the point the
    left eye looks at on an animal: the nearest crossing of its gaze ray (unit ``gaze`` (3,))
    with the animal's surface triangles ``faces`` on ``nodes`` (Moller-Trumbore); a ray that
    misses the body takes the node nearest to it."""
    o = eyes[0]
    a, b, c = nodes[faces[:, 0]], nodes[faces[:, 1]], nodes[faces[:, 2]]
    e1, e2 = b - a, c - a
    p = np.cross(gaze, e2)
    det = np.einsum("fk,fk->f", e1, p)
    ok = np.abs(det) > 1e-12
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = o - a
    u = np.einsum("fk,fk->f", s, p) * inv
    q = np.cross(s, e1)
    v = (q @ gaze) * inv
    t = np.einsum("fk,fk->f", e2, q) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    if hit.any():
        point = o + t[hit].min() * gaze
    else:
        rel = nodes - o
        miss = np.linalg.norm(rel - (rel @ gaze)[:, None] * gaze, axis=1)
        point = nodes[np.argmin(miss)]
    return float(np.linalg.norm(point - eyes.mean(0)))


def _off_gaze(dirs: np.ndarray, eyes: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """Return per eye (2,) the smallest angle (rad) between its gaze and an animal's node."""
    to = nodes[None] - eyes[:, None]
    to = to / np.linalg.norm(to, axis=-1, keepdims=True)
    return np.arccos(np.clip((to * dirs[:, None]).sum(-1), -1.0, 1.0)).min(1)


class _Frames(Observer):
    """Every animal's positions (lane 0) at each record, and the times."""

    def __init__(self, world: World) -> None:
        self.times: list[float] = []
        self.positions: list[list[np.ndarray]] = [[] for _ in world.animals]

    def record(self, world: World) -> None:
        self.times.append(world.time)
        for a, p in enumerate(self.positions):
            p.append(world.positions(a)[0])


@dataclass
class _Catch:
    """The stop condition of a chase: the predator's head within ``radius`` m of a prey node
    (a blown-up predator or prey raises)."""

    radius: float
    time: float | None = None

    def __call__(self, world: World) -> bool:
        if world.failed(0)[0] or world.failed(1)[0]:
            raise ZoeticError("the chase blew up (an animal's state went non-finite)")
        head = world.positions(0)[0][world.bodies[0].head]
        gap = np.linalg.norm(world.positions(1)[0] - head, axis=-1).min()
        if gap < self.radius:
            self.time = world.time
        return self.time is not None


def run_chase(
    chase: Chase, seconds: float, fps: float = 30.0, seed: int = 0, catch_radius: float = 0.3
) -> ChaseResult:
    """Run the chase for ``seconds`` (stopping at a catch: the predator's head within
    ``catch_radius`` m of a prey node) with every policy asked ``fps`` times a second; the
    positions are recorded at the start of each control period (the frames the eyes saw)."""
    world = chase.world
    for p in chase.policies:
        p.reset(seed)

    def decide(world: World, period: Period) -> list[np.ndarray]:
        return [p.act(observe(world, a, p.sensors), period) for a, p in enumerate(chase.policies)]

    frames, catch = _Frames(world), _Catch(catch_radius)
    drive(world, decide, seconds, Schedule(1.0 / fps, fixed=True), (frames,), stop=catch)
    # the driver also records the state after the last period, which no policy saw
    positions = [np.stack(p[:-1]) for p in frames.positions]
    return ChaseResult(
        np.array(frames.times[:-1]),
        positions,
        chase.predator.log,
        catch.time is not None,
        catch.time,
        catch_radius,
        world.bodies[1].faces,
    )


def summarize(result: ChaseResult, spec: EyeSpec) -> dict:
    """Return the chase's figures: caught, time to catch, fraction of frames with the prey
    foveated (some node of it inside both foveas' field of view), distractor fixations
    (frames on which the eyes, aimed by a lock when the image was taken, held a distractor,
    not the prey, in a fovea: frame 0, seen straight ahead before any lock, does not count),
    the relative error of the triangulated range (against ``gazed_range``: where the left
    gaze ray that it triangulates meets the prey's surface at the frame's time) while
    foveated, as mean and median."""
    half = 0.5 * spec.fovs[-1]
    prey = result.positions[1].mean(1)
    faces = result.prey_faces
    fov, distr, rng_err = [], 0, []
    for i, rec in enumerate(result.log):
        off = _off_gaze(rec.eye_dirs, rec.eye_pos, result.positions[1][i])
        fov.append(bool((off < half).all()))
        for a in range(2, len(result.positions)):
            o = _off_gaze(rec.eye_dirs, rec.eye_pos, result.positions[a][i])
            aimed = i > 0 and result.log[i - 1].locked.any()  # the gaze came from a lock
            if aimed and (o < half).any() and not (off < half).any():
                distr += 1
        if np.isfinite(rec.range) and fov[-1]:
            true = gazed_range(faces, result.positions[1][i], rec.eye_pos, rec.gaze_dirs[0])
            rng_err.append(abs(rec.range - true) / true)
    head = result.positions[0][:, 0]
    dist = np.linalg.norm(prey - head, axis=-1)
    verg = [r.angles[1, 0] - r.angles[0, 0] for r in result.log]
    th = np.array([r.angles[:, 0] for r in result.log])
    corr = float(np.corrcoef(th[:, 0], th[:, 1])[0, 1]) if len(th) > 2 else float("nan")
    return {
        "caught": result.caught,
        "time_to_catch_s": result.time_to_catch,
        "frames": len(result.log),
        "foveated_fraction": float(np.mean(fov)) if fov else 0.0,
        "distractor_fixations": distr,
        "start_distance_m": float(dist[0]),
        "final_distance_m": float(dist[-1]),
        "mean_range_error": float(np.mean(rng_err)) if rng_err else None,
        "median_range_error": float(np.median(rng_err)) if rng_err else None,
        "max_vergence_deg": float(np.degrees(np.max(verg))) if verg else 0.0,
        "gaze_correlation_theta": corr,
    }
