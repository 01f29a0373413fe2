"""A tank of artificial fishes living together: each a brain (a Policy) over one World.

``build_tank(TankConfig(...))`` places prey fishes and predators, rocks and seaweed, food and
four walls in water; ``live(tank)`` runs it: every control period the perception oracle looks at
the world for every fish, each fish's brain (mind, focuser, behaviour routine, motor layer)
returns its activations, and the world steps them all in lockstep. What happens is recorded as
events (eat, catch, escape, mate, collision), mind timelines and positions.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from zoetic.behavior.aquarium.locomotion import (
    Demand,
    LearnedLocomotion,
    MotorLocomotion,
    bend_nodes,
    learned_motor,
)
from zoetic.behavior.aquarium.perception import obstacle_distance, perceive
from zoetic.behavior.aquarium.routines import (
    Around,
    Me,
    avoid,
    collision_ahead,
    escape,
    go_to,
    keep_depth,
    leave,
    probe_reach,
    probes_ahead,
    reach_cost,
    school,
    wander,
)
from zoetic.behavior.aquarium.species import (
    BUILT_IN,
    Species,
    SpeciesError,
    load_species,
    with_skills,
)
from zoetic.behavior.mind import (
    INTENTIONS,
    Drives,
    MindState,
    Situation,
    ate,
    drives,
    drives_many,
    focus,
    initial_mind,
    think,
)
from zoetic.behavior.mind import mated as mind_mated
from zoetic.bodies import Body, load_animal
from zoetic.control.policy import Period
from zoetic.errors import SimulationError
from zoetic.physics.bodycontact import deepest as deepest_into
from zoetic.physics.objects import Box, Cylinder, Food, pack_statics
from zoetic.physics.world import Animal, World
from zoetic.tasks.terms import BodyFrame, roll_angle

WALL = 0.25  # m: half thickness of the tank's walls
PERCEPTIONS = ("oracle", "vision")
NEAR = 2.5  # m between centres within which fishes may catch, touch or mate (1 m bodies)
APART = 1.0  # s: a touch counts as a new collision after this long apart
HEIGHT = 2.0  # m: half height of the walls, rocks and seaweed (all span the fishes' layer)


@dataclass(frozen=True)
class TankConfig:
    """A tank: how many fishes (predators among them), food particles and obstacles, for how
    long, from which seed; ``half_size`` (m, default grows with the crowd), the water
    current (m/s) that carries the food, the brains' control period and the record period
    (s; how often positions are kept: the run is the same whatever it is)."""

    fishes: int = 10
    predators: int = 1
    food: int = 15
    obstacles: int = 5
    seconds: float = 60.0
    seed: int = 0
    half_size: float | None = None
    current: tuple[float, float, float] = (0.02, 0.0, 0.0)
    control_period: float = 0.1
    record_period: float = 0.05
    prey_species: str = "minnow"
    predator_species: str = "shark"
    food_radius: float = 0.25
    food_margin: float = 3.0  # m from the walls food is dropped: 1.5 turning radii of a fish
    perception: str = "oracle"  # or "vision": the first predator sees with animat vision
    predator_skills: str | None = None  # a learned repertoire's directory for the predator
    # every species' motor skills ("built-in", "learned" or a repertoire's directory) instead
    # of what the species files say (``predator_skills`` then still names the predator's)
    skills: str | None = None
    fish_contact: bool = True  # fishes push each other apart (``physics.bodycontact``)
    # the motor layer's righting reflex: the fins lean against each fish's roll
    # (``behavior.motor.righting``)
    righting: bool = True

    def size(self) -> float:
        """Return the half width of the tank (m)."""
        if self.half_size is not None:
            return float(self.half_size)
        return 3.7 + 1.5 * math.sqrt(self.fishes + self.obstacles)


@dataclass(frozen=True)
class Fish:
    """A fish of the tank: its name, species and body."""

    name: str
    species: Species
    body: Body


@dataclass
class Tank:
    """A built tank: the world, its fishes (in the world's animal order), obstacles and walls."""

    config: TankConfig
    world: World
    fishes: list[Fish]
    kind: np.ndarray
    center: np.ndarray
    size: np.ndarray
    static_names: list[str]


def _check(cfg: TankConfig) -> None:
    if cfg.fishes < 1 or cfg.predators < 0 or cfg.predators > cfg.fishes:
        raise SimulationError(
            f"a tank needs at least one fish and at most as many predators as fishes "
            f"(got {cfg.fishes} fishes, {cfg.predators} predators)"
        )
    if cfg.food < 0 or cfg.obstacles < 0:
        raise SimulationError("--food and --obstacles must be at least 0")
    if cfg.fishes > 60 or cfg.food > 500 or cfg.obstacles > 60:
        raise SimulationError("at most 60 fishes, 500 food particles and 60 obstacles")
    if not 0 < cfg.seconds <= 3600:
        raise SimulationError(f"--seconds must be in (0, 3600], got {cfg.seconds:g}")
    if cfg.perception not in PERCEPTIONS:
        raise SimulationError(
            f"perception must be one of {', '.join(PERCEPTIONS)}, got {cfg.perception!r}"
        )
    if cfg.perception == "vision" and cfg.predators < 1:
        raise SimulationError("--perception vision gives a predator eyes: need --predators >= 1")
    if not 0 < cfg.control_period <= 1.0 or not 0 < cfg.record_period <= cfg.control_period:
        raise SimulationError("need 0 < record period <= control period <= 1 s")


def _place(rng, half: float, ok: Callable[[np.ndarray], bool], margin: float) -> np.ndarray:
    for _ in range(2000):
        p = np.array([rng.uniform(-half + margin, half - margin), 0.0,
                      rng.uniform(-half + margin, half - margin)])  # fmt: skip
        if ok(p):
            return p
    raise SimulationError(
        "the tank is too crowded to place everything; use fewer fishes or obstacles"
    )


def build_tank(cfg: TankConfig) -> Tank:
    """Return a tank as ``cfg`` describes it, laid out from its seed."""
    _check(cfg)
    rng = np.random.default_rng(cfg.seed)
    half = cfg.size()
    prey, pred = load_species(cfg.prey_species), load_species(cfg.predator_species)
    if not pred.predator:
        raise SpeciesError(f"{pred.source}: species {pred.name!r} is not a predator")
    if cfg.skills is not None:
        where = f"--skills {str(cfg.skills)!r}"
        prey, pred = with_skills(prey, cfg.skills, where), with_skills(pred, cfg.skills, where)
    if cfg.predator_skills is not None:
        pred = with_skills(pred, cfg.predator_skills,
                           f"--predator-skills {str(cfg.predator_skills)!r}")
    statics: list[Box | Cylinder] = []
    for sx, sz in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        c = (sx * (half + WALL), 0.0, sz * (half + WALL))
        hs = (WALL if sx else half + 2 * WALL, HEIGHT, WALL if sz else half + 2 * WALL)
        statics.append(Box(c, hs, name="wall"))
    rocks: list[np.ndarray] = []

    def clear_of_rocks(p, gap):
        return all(np.hypot(*(p - r)[[0, 2]]) > gap for r in rocks)

    for k in range(cfg.obstacles):
        p = _place(rng, half, lambda p: clear_of_rocks(p, 3.0), 1.5)
        rocks.append(p)
        r = float(rng.uniform(0.35, 0.7))
        if k % 2 == 0:
            statics.append(Box(tuple(p), (r, HEIGHT, float(rng.uniform(0.35, 0.7))), name="rock"))
        else:
            statics.append(Cylinder(tuple(p), r, 2 * HEIGHT, "y", name="seaweed"))
    kind, center, size = pack_statics(statics)

    def free(p, gap):
        return len(kind) == 0 or obstacle_distance(p, kind, center, size).min() > gap

    placed: list[np.ndarray] = []
    fishes, animals = [], []
    for i in range(cfg.fishes):
        spec = pred if i < cfg.predators else prey
        body = load_animal(spec.body)
        if body.medium not in ("water", "sea"):
            raise SpeciesError(f"{spec.source}: body {spec.body!r} does not live in water")
        p = _place(rng, half, lambda p: free(p, 1.5) and all(
            np.linalg.norm(p - q) > 2.0 for q in placed), 1.0)  # fmt: skip
        placed.append(p)
        yaw = float(rng.uniform(-np.pi, np.pi))
        # the offset places the rest pose; shift it so that the body's centre lands on p
        com0 = body.mass @ body.rest_pos / body.total_mass
        v0 = spec.motor.cruise_speed * np.array([np.cos(yaw), 0.0, np.sin(yaw)])
        animals.append(Animal(body, tuple(p - com0), yaw, tuple(v0)))
        fishes.append(Fish(f"{spec.name}_{i}", spec, body))
    foods = [
        Food(tuple(_place(rng, half, lambda p: free(p, 0.6), cfg.food_margin)), cfg.food_radius)
        for _ in range(cfg.food)
    ]
    world = World([*animals, *statics, *foods], medium="water", current=cfg.current,
                  animal_contact=cfg.fish_contact)
    names = [s.name for s in statics]
    return Tank(cfg, world, fishes, kind, center, size, names)


# ============================================================================ the brain


@dataclass(frozen=True)
class View:
    """One fish's percept for one control period (what the brain's ``act`` reads)."""

    me: Me
    fish_distance: np.ndarray  # (n,) inf where not perceived (itself included)
    fish_com: np.ndarray  # (n, 3)
    fish_forward: np.ndarray  # (n, 3)
    fish_velocity: np.ndarray  # (n, 3)
    fish_species: tuple[str, ...]
    food_distance: np.ndarray  # (F,)
    food: np.ndarray  # (F, 3)
    obstacle_distance: np.ndarray  # (S,)
    collision: bool
    away: np.ndarray | None


@dataclass(frozen=True)
class Thought:
    """What a brain decided in one period: its drives, intention and target."""

    hunger: float
    libido: float
    fear: float
    intention: str
    target: int | None


class FishBrain:
    """A fish's brain as a Policy: percept in (``observation["view"]``), activations out.

    Mind (drives, intention generator), focuser, behaviour routine and motor layer in one
    control period. A dead fish (``alive = False``) stops moving its muscles.
    """

    sensors: tuple[str, ...] = ()

    def __init__(self, species: Species, body: Body, hunted_by: frozenset[str],
                 righting: bool = True) -> None:  # fmt: skip
        self.species, self.body, self.hunted_by = species, body, hunted_by
        m = species.motor
        self.locomotion: MotorLocomotion | LearnedLocomotion
        if m.skills == BUILT_IN:
            self.locomotion = MotorLocomotion(body, m.frequency, righting=righting)
        else:  # a learned repertoire (checked when the species was read)
            self.locomotion = LearnedLocomotion(body, learned_motor(body, m.skills), righting)
        self.top = min(m.max_speed, self.locomotion.top_speed)
        self.cruise = min(m.cruise_speed, self.top)
        self.radius = self.locomotion.turn_radius
        self.constants = species.fear_constants()
        self.alive = True
        self.avoid_side = 0
        self.reset(0)

    def reset(self, seed: int | None = None) -> None:
        """Start a life: a fresh mind with the species' initial hunger, a reseeded wander."""
        self.rng = np.random.default_rng(seed)
        self.mind: MindState = initial_mind(self.species.mind.initial_hunger,
                                            self.species.mind.hunger_rate)  # fmt: skip
        self.alive = True
        self.thought = Thought(0.0, 0.0, 0.0, self.mind.intention, None)
        if isinstance(self.locomotion, LearnedLocomotion):
            self.locomotion.turning, self.locomotion.last = None, (0, -np.inf)

    def willing(self, t: float) -> bool:
        """Return True when the fish would mate at time t: its libido (which a mating resets)
        above the desire threshold, and it is not fleeing or avoiding."""
        lib = drives(self.mind, t, self.constants).libido
        return lib > self.species.mind.desire_threshold and self.thought.intention not in (
            "escape", "school", "avoid")

    def ate(self, t: float, particles: float = 1.0) -> None:
        """Record a meal at time t."""
        self.mind = ate(self.mind, t, particles)

    def mated(self, t: float) -> None:
        """Record a mating at time t."""
        self.mind = mind_mated(self.mind, t)

    def _kinds(self, names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return (same species, hunters, prey) masks over the tank's fishes (cached)."""
        if getattr(self, "_names", None) != names:
            arr = np.array(names)
            self._names = names
            self._masks = (arr == self.species.name, np.isin(arr, list(self.hunted_by)),
                           np.isin(arr, list(self.species.prey)))  # fmt: skip
        return self._masks

    def _situation(self, v: View) -> Situation:
        """The fish's ``Situation`` from its own view (``situations`` for one fish)."""
        same, hunters, prey = self._kinds(v.fish_species)
        h = self.species.habits
        sits, _ = situations(v.fish_distance[None], v.food_distance[None],
                             v.obstacle_distance[None], same[None], hunters[None], prey[None],
                             np.array([h.personal_space]), np.array([h.crowd]), [v.collision])
        return sits[0]

    def act(self, observation: Mapping, period: Period) -> np.ndarray:
        """Return activations (1, T, A) for the period from the fish's percept (the percept
        holds no roll, so the righting reflex rests here: ``live`` measures the rolls)."""
        demand = self.decide(observation, period)
        if demand is None:
            return np.zeros((1, period.steps, self.body.n_actuators))
        return self.locomotion.activations(demand, period.times)[None]

    def decide(self, observation: Mapping, period: Period, sit: Situation | None = None,
               d: Drives | None = None) -> Demand | None:  # fmt: skip
        """Return the motor demand for the period from the fish's percept (None: dead).
        ``sit`` and ``d``: the situation and drives when already computed for all the fishes
        at once (``situations``, ``mind.drives_many``); by default from the percept."""
        if not self.alive:
            return None
        v: View = observation["view"]
        sp = self.species
        same, hunters, prey = self._kinds(v.fish_species)
        if sit is None:
            sit = self._situation(v)
        self.mind, drives = think(self.mind, period.t0, self.constants, sp.habits, sit,
                                  sp.predator, d)  # fmt: skip
        intention = self.mind.intention
        if intention == "eat":
            candidates = reach_cost(v.me, v.food, v.food_distance)
        elif intention == "mate":
            candidates = np.where(same, v.fish_distance, np.inf)
        elif intention == "hunt":
            candidates = np.where(prey, v.fish_distance, np.inf)
        else:
            candidates = None
        target = None if candidates is None else focus(candidates, self.mind.target)
        if target != self.mind.target:
            self.mind = replace(self.mind, target=target)
        seen = np.isfinite(v.fish_distance)
        around = Around(
            fish=v.fish_com[seen], fish_forward=v.fish_forward[seen], same=same[seen],
            predators=v.fish_com[seen & hunters],
            target=None if target is None else (v.food if intention == "eat" else v.fish_com)[
                target],
            target_velocity=None if target is None or intention == "eat"
            else v.fish_velocity[target],
            away=v.away,
            obstacle=float(v.obstacle_distance.min()) if len(v.obstacle_distance) else np.inf,
        )  # fmt: skip
        me = v.me
        if intention == "avoid":
            demand = avoid(me, around)
        elif intention == "escape":
            demand = escape(me, around)
        elif intention == "school":
            demand = school(me, around)
        elif intention == "eat":
            demand = go_to(me, around, self.rng)
        elif intention == "mate":
            demand = go_to(me, around, self.rng, beside=0.6)
        elif intention == "hunt":
            demand = go_to(me, around, self.rng, lead=0.5)
        elif intention == "leave":
            demand = leave(me, around)
        else:
            demand = wander(me, around, self.rng)
        demand = keep_depth(me, demand, None if around.target is None else around.target[1])
        self.thought = Thought(drives.hunger, drives.libido, drives.fear, intention, target)
        return demand


def situations(fish: np.ndarray, food: np.ndarray, obstacles: np.ndarray, same: np.ndarray,
               hunters: np.ndarray, prey: np.ndarray, personal_space: np.ndarray,
               crowd: np.ndarray, collision: np.ndarray) -> tuple[list[Situation], np.ndarray]:
    """Return every fish's ``Situation`` from all the percepts at once, and (n, n) the
    distances of the predators each perceives (inf elsewhere, for ``mind.drives_many``).

    fish (n, M), food (n, F), obstacles (n, S): the distances perceived by each of n fishes
    (inf: not perceived, ``Percepts``; M = n in the tank, one row for ``FishBrain._situation``);
    same, hunters, prey (n, M): row i the masks of ``FishBrain._kinds`` of fish i;
    personal_space, crowd (n,): the habits; collision (n,) bools."""
    n = len(fish)
    inf = np.full(n, np.inf)
    seen = np.isfinite(fish)
    predators = np.where(hunters, fish, np.inf)
    food_near = food.min(axis=1) if food.shape[1] else inf
    mate = np.where(same, fish, np.inf).min(axis=1) if n else inf
    prey_near = np.where(prey, fish, np.inf).min(axis=1) if n else inf
    crowded = ((fish < personal_space[:, None]).sum(axis=1) > crowd).tolist()
    alone = (~seen.any(axis=1)).tolist()
    near_obstacle = ((obstacles.min(axis=1) < personal_space).tolist() if obstacles.shape[1]
                     else [False] * n)  # fmt: skip
    near_predators: list[list[float]] = [[] for _ in range(n)]
    ii, jj = np.nonzero(np.isfinite(predators))
    for i, x in zip(ii.tolist(), predators[ii, jj].tolist(), strict=True):
        near_predators[i].append(x)
    out = [
        Situation(bool(c), tuple(pd), f, m, q, bool(cr), bool(al), bool(no))
        for c, pd, f, m, q, cr, al, no in zip(
            collision, near_predators, food_near.tolist(), mate.tolist(), prey_near.tolist(),
            crowded, alone, near_obstacle, strict=True,
        )
    ]
    return out, predators


# ============================================================================ living


@dataclass
class Life:
    """What a tank's run recorded."""

    times: np.ndarray  # (R,) s
    positions: list[np.ndarray]  # per fish (R, N, 3)
    food: np.ndarray  # (R, F, 3)
    eaten: np.ndarray  # (R, F) bool
    brain_times: np.ndarray  # (K,) s
    drives: np.ndarray  # (K, n, 3) hunger, libido, fear
    intentions: np.ndarray  # (K, n) index into INTENTIONS
    alive: np.ndarray  # (K, n) bool
    targets: np.ndarray  # (K, n) the focused target's index (fish, food particle; -1: none)
    events: list[tuple[float, str, str, str]] = field(default_factory=list)
    wall_seconds: float = 0.0
    deepest: float = 0.0  # m: the deepest any node went into an obstacle (0 if none)
    deepest_fish: float = 0.0  # m: the deepest any node went inside another fish (0 if none)


def heading_weights(body: Body) -> np.ndarray:
    """Return c (N,) with sum_n c_n x_n = the best linear fit's image of the rest heading
    (``control.sensors.linear_fit`` applied to ``body.forward``, in one dot product)."""
    w = body.mass / body.total_mass
    r0 = body.rest_pos - w @ body.rest_pos
    m_inv = np.linalg.pinv(np.einsum("n,ni,nj->ij", w, r0, r0))
    return w * (r0 @ (m_inv @ body.forward))


def _kinematics(world: World, weights: list[np.ndarray], cw: list[np.ndarray],
                heads: list[int], allpos: np.ndarray | None = None):
    """Return each fish's node positions, and (n, 3) centres, unit headings, centre velocities
    and noses; weights: each fish's node masses over its total; ``allpos``:
    ``world.node_positions()`` when already taken this step."""
    allpos = world.node_positions(0) if allpos is None else allpos
    allvel = world.node_velocities(0)
    off = world.offsets.tolist()
    com, fwd, cv, nose, pos = [], [], [], [], []
    for a, (w, c, h) in enumerate(zip(weights, cw, heads, strict=True)):
        p, v = allpos[off[a]:off[a + 1]], allvel[off[a]:off[a + 1]]
        pos.append(p)
        com.append(w @ p)
        cv.append(w @ v)
        fr = c @ p
        fwd.append(fr / (math.sqrt(fr @ fr) + 1e-12))  # np.linalg.norm's formula
        nose.append(p[h])
    return pos, np.array(com), np.array(fwd), np.array(cv), np.array(nose)


def roll_pairs(bodies: list[Body], offsets: np.ndarray) -> list[tuple[np.ndarray, ...]]:
    """Return the fishes' mirror node pairs (``BodyFrame.left``, ``.right``) as indices into
    the world's node array (``offsets``: each fish's first node), grouped by pair count: a
    list of (fishes (k,), left (k, P), right (k, P)); fishes without pairs are left out."""
    groups: dict[int, list[tuple[int, np.ndarray, np.ndarray]]] = {}
    for a, body in enumerate(bodies):
        frame = BodyFrame.of(body)
        if len(frame.left):
            o = int(offsets[a])
            groups.setdefault(len(frame.left), []).append((a, o + frame.left, o + frame.right))
    return [(np.array([g[0] for g in grp]), np.stack([g[1] for g in grp]),
             np.stack([g[2] for g in grp])) for grp in groups.values()]  # fmt: skip


def fish_rolls(allpos: np.ndarray, fwd: np.ndarray,
               pairs: list[tuple[np.ndarray, ...]]) -> np.ndarray:  # fmt: skip
    """Return each fish's roll (n,), rad over +-pi (``tasks.terms.roll_angle`` against its
    heading ``fwd`` (n, 3)), from the world's node positions ``allpos``; pairs: ``roll_pairs``
    (one array expression a group of fishes with as many pairs; 0 for a fish without)."""
    out = np.zeros(len(fwd))
    for idx, left, right in pairs:
        out[idx] = roll_angle(np, allpos, left, right, fwd[idx])
    return out


def bend_indices(bodies: list[Body], offsets: np.ndarray
                 ) -> tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """Return what ``fish_bends`` needs: each fish's nose and tail node as indices into the
    world's node array (``offsets``: each fish's first node) and rest distance, for the fishes
    that ``locomotion.bend_nodes`` measures (after how many fishes)."""
    rows = [(a, int(offsets[a]) + nodes[0], int(offsets[a]) + nodes[1], nodes[2])
            for a, b in enumerate(bodies) if (nodes := bend_nodes(b)) is not None]  # fmt: skip
    idx, nose, tail, rest = (np.array([r[k] for r in rows], dtype=float if k == 3 else int)
                             for k in range(4))  # fmt: skip
    return len(bodies), idx, nose, tail, rest


def fish_bends(allpos: np.ndarray,
               bends: tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    """Return each fish's bend (n,) (``locomotion.bend``: nose to tail over rest, 1 for a fish
    without a tail node) from the world's node positions ``allpos``; bends: ``bend_indices``."""
    n, idx, nose, tail, rest = bends
    out = np.ones(n)
    if len(idx):
        out[idx] = np.linalg.norm(allpos[nose] - allpos[tail], axis=1) / rest
    return out


def _activations(brains: list[FishBrain], demands: list[Demand | None],
                 period: Period) -> list[np.ndarray]:  # fmt: skip
    """Return each fish's activations (1, T, A) for its demand (zeros when dead): fishes that
    share a motor (body and wave frequency) in one batched call."""
    rows: list[np.ndarray] = [np.empty(0)] * len(brains)
    groups: dict[int, list[int]] = {}
    times = period.times
    for i, (b, d) in enumerate(zip(brains, demands, strict=True)):
        if d is None:
            rows[i] = np.zeros((1, period.steps, b.body.n_actuators))
        elif isinstance(b.locomotion, LearnedLocomotion):
            # each fish its own turn under way; the gaits evaluated once for the fishes of a
            # motor (``LearnedMotor._raw``)
            rows[i] = b.locomotion.activations(d, times)[None]
        else:
            groups.setdefault(id(b.locomotion.motor), []).append(i)
    for idx in groups.values():
        acts = brains[idx[0]].locomotion.activations_many([demands[i] for i in idx], times)
        for k, i in enumerate(idx):
            rows[i] = acts[k : k + 1]
    return rows


def _eyes(tank: Tank):
    """Return animat-vision eyes for the tank's first predator (``aquarium.vision``)."""
    from zoetic.behavior.aquarium.vision import FishEyes

    a = next(i for i, f in enumerate(tank.fishes) if f.species.predator)
    me = tank.fishes[a]
    prey = next((f for f in tank.fishes if f.species.name in me.species.prey), None)
    prey_body, prey_color = (prey.body, prey.species.color) if prey else (me.body, me.species.color)
    colors = [np.array(f.species.color) / 255.0 for f in tank.fishes]
    rng, extent = me.species.senses.view_range, 2 * tank.config.size()
    return FishEyes.build(a, me.body, colors, prey_body, np.array(prey_color) / 255.0, rng,
                          -HEIGHT, extent)  # fmt: skip


def live(tank: Tank, seconds: float | None = None,
         progress: Callable[[float], None] | None = None) -> Life:  # fmt: skip
    """Run the tank for ``seconds`` (default the config's) and return what happened."""
    cfg, world, fishes = tank.config, tank.world, tank.fishes
    seconds = cfg.seconds if seconds is None else seconds
    n = len(fishes)
    hunted_by = {
        s.name: frozenset(f.species.name for f in fishes if s.name in f.species.prey)
        for s in {f.species.name: f.species for f in fishes}.values()
    }
    brains = [FishBrain(f.species, f.body, hunted_by[f.species.name], cfg.righting)
              for f in fishes]  # fmt: skip
    for i, b in enumerate(brains):
        b.reset(cfg.seed * 1000 + i)
    names = tuple(f.species.name for f in fishes)
    kind, center, size = tank.kind, tank.center, tank.size
    va = np.array([f.species.senses.view_angle for f in fishes])
    vr = np.array([f.species.senses.view_range for f in fishes])
    sr = np.array([f.species.senses.smell_range for f in fishes])
    cw = [heading_weights(f.body) for f in fishes]
    # each fish's kinds of fishes (rows: same species, hunters, prey), habits and constants
    kinds = [b._kinds(names) for b in brains]
    same, hunters, prey_of = (np.array([k[x] for k in kinds]) for x in range(3))
    space = np.array([f.species.habits.personal_space for f in fishes], float)
    crowd = np.array([f.species.habits.crowd for f in fishes])
    consts = [b.constants for b in brains]
    p0 = np.array([c.hunger_rate for c in consts], float)
    alpha = np.array([c.alpha for c in consts], float)
    p1 = np.array([c.libido_rate for c in consts], float)
    d0 = np.array([c.fear_distance for c in consts], float)
    dt = world.dt
    t_start = time.perf_counter()
    times, positions, foods, eaten = [], [[] for _ in fishes], [], []
    b_times, drive_rec, intents, alive_rec, target_rec = [], [], [], [], []
    events: list[tuple[float, str, str, str]] = []
    touching = np.full((n, len(world.objects)), -np.inf)  # when each pair last touched
    fish_touch = np.full((n, n), -np.inf)
    in_fear = np.zeros(n, bool)
    deepest = 0.0
    deepest_fish = 0.0
    # how far a fish's nodes reach from its centre (the bounding sphere of the deepest test)
    extent = np.array([1.25 * np.linalg.norm(f.body.rest_pos - f.body.mass @ f.body.rest_pos
                                            / f.body.total_mass, axis=1).max() for f in fishes])
    static_obj = [i for i, o in enumerate(world.objects) if isinstance(o, Box | Cylinder)]
    eyes = _eyes(tank) if cfg.perception == "vision" else None

    def record(pos):
        times.append(world.time)
        for a in range(n):
            positions[a].append(pos[a])
        foods.append(world.food_positions[0])
        eaten.append(world.food_eaten[0])

    off = world.offsets
    masses = [(f.body.mass, f.body.total_mass) for f in fishes]
    weights = [m / total for m, total in masses]
    heads_of = [f.body.head for f in fishes]
    # the world's node positions now: kept current at every period's start (below)
    allpos, recorded = world.node_positions(0), world.step_count
    pos, com, fwd, vel, nose = _kinematics(world, weights, cw, heads_of, allpos)
    last_roll: tuple[np.ndarray, float] | None = None  # the rolls at the last period's start
    record(pos)
    pairs = roll_pairs([f.body for f in fishes], off)
    bends = bend_indices([f.body for f in fishes], off)
    end = world.step_count + world.steps_for(seconds)
    rec_steps = max(1, int(round(cfg.record_period / dt)))
    k = 0
    while world.step_count < end:
        k += 1
        start = world.step_count
        steps = min(max(1, int(round(cfg.control_period / dt))), end - start)
        period = Period(start, steps, dt)
        t = period.t0
        alive = np.array([b.alive for b in brains])
        food_pos = world.food_positions[0]
        left = ~world.food_eaten[0]
        pc = perceive(nose, fwd, com, alive, food_pos, left, kind, center, size, va, vr, sr)
        seen_com = {}
        if eyes is not None and alive[eyes.animal]:
            a = eyes.animal
            prey = [j for j in range(n) if alive[j] and j != a
                    and fishes[j].species.name in fishes[a].species.prey]  # fmt: skip
            sight = eyes.see(world, np.array(prey, int))
            pc.fish[a, prey] = np.inf  # prey only as the eyes see it
            seen_com[a] = com.copy()
            if sight is not None:
                pc.fish[a, sight.fish] = sight.distance
                seen_com[a][sight.fish] = sight.point
        demands: list[Demand | None] = []
        mes, meals = [], []
        for i, b in enumerate(brains):
            mes.append(Me(com[i], nose[i], fwd[i], vel[i], b.cruise, b.top, b.radius))
            th = b.thought
            meals.append(pc.food[i, th.target] if th.intention == "eat" and th.target is not None
                         else None)  # fmt: skip
        # every fish's probes ahead against the obstacles in one call
        ahead = obstacle_distance(np.stack([probes_ahead(m, probe_reach(m, q))
                                            for m, q in zip(mes, meals, strict=True)]),
                                  kind, center, size)  # fmt: skip
        hits, aways = [], []
        for i, b in enumerate(brains):
            me = mes[i]
            others = com[np.isfinite(pc.fish[i])]
            prefer = b.avoid_side if b.thought.intention == "avoid" else 0
            hit, away = collision_ahead(me, kind, center, size, others, prefer, meals[i],
                                        ahead[i])  # fmt: skip
            if hit and away is not None:
                # the vertical component of fwd x away: which side the way out lies on
                b.avoid_side = 1 if fwd[i][2] * away[0] - fwd[i][0] * away[2] < 0 else -1
            hits.append(hit)
            aways.append(away)
        # every fish's situation and drives in one step over arrays
        sits, predators = situations(pc.fish, pc.food, pc.obstacles, same, hunters, prey_of,
                                     space, crowd, hits)  # fmt: skip
        mind_state = [b.mind for b in brains]
        hunger, libido, fear = (x.tolist() for x in drives_many(
            [m.eaten for m in mind_state], [m.meal_time for m in mind_state],
            [m.mating_time for m in mind_state], t, p0, alpha, p1, d0, predators))  # fmt: skip
        obs = {"time": np.array([t])}
        for i, b in enumerate(brains):
            view = View(mes[i], pc.fish[i], seen_com.get(i, com), fwd, vel, names, pc.food[i],
                        food_pos, pc.obstacles[i], hits[i], aways[i])  # fmt: skip
            demands.append(b.decide({**obs, "view": view}, period, sits[i],
                                    Drives(hunger[i], libido[i], fear[i])))  # fmt: skip
        # each fish's roll and roll rate (over the last period) for the motor layer's
        # righting reflex
        roll = fish_rolls(allpos, fwd, pairs)
        roll_rate = np.zeros(n) if last_roll is None else (
            np.angle(np.exp(1j * (roll - last_roll[0]))) / (t - last_roll[1]))  # fmt: skip
        last_roll = (roll, t)
        bend = fish_bends(allpos, bends)
        demands = [None if d is None else replace(d, roll=r, roll_rate=w, bend=c)
                   for d, r, w, c in zip(demands, roll.tolist(), roll_rate.tolist(),
                                         bend.tolist(), strict=True)]  # fmt: skip
        rows = _activations(brains, demands, period)
        th = [b.thought for b in brains]
        b_times.append(t)
        drive_rec.append([(x.hunger, x.libido, x.fear) for x in th])
        intents.append([INTENTIONS.index(x.intention) for x in th])
        alive_rec.append(alive)
        target_rec.append([-1 if x.target is None else x.target for x in th])
        # fear episodes that end with the fish alive are escapes
        for i, x in enumerate(th):
            afraid = alive[i] and x.intention in ("escape", "school")
            if in_fear[i] and not afraid and alive[i] and x.intention != "avoid":
                events.append((t, fishes[i].name, "escape", f"fear {x.fear:.2f}"))
            if x.intention != "avoid":
                in_fear[i] = afraid
        # the period is stepped in slices that end at the record times; what happened in it
        # (meals, touches) is taken at its end, so the record period changes nothing
        before = world.food_eaten[0]
        touched: set[tuple[int, int]] = set()
        fish_hit = np.zeros((n, n), bool)
        j = 0
        while j < steps:
            m = min(steps - j, rec_steps - (world.step_count % rec_steps))
            contacts = world.step(m * dt, [r[:, j:j + m] for r in rows])
            j += m
            if contacts.between is not None:  # fish against fish (the world's skin contact)
                fish_hit |= (contacts.between[0] + contacts.between[0].T) > 0.0
            if contacts.impulse and contacts.impulse[0].shape[2]:
                # contacts.touching[0] for the one lane, without stacking every animal's
                # (only the animals whose nodes were tested: the others' impulses are zero)
                tested = range(n) if contacts.near is None else contacts.near
                touched.update((i, int(o)) for i in tested for o in np.flatnonzero(
                    (contacts.impulse[i][0] != 0.0).any(axis=(0, 2))))  # fmt: skip
            if world.step_count % rec_steps == 0 or world.step_count == end:
                allpos = world.node_positions(0)
                pos = [allpos[o0:o1] for o0, o1 in zip(off[:-1], off[1:], strict=True)]
                record(pos)
                recorded = world.step_count
        t1 = world.time
        new = world.food_eaten[0] & ~before
        if new.any():
            fp = world.food_positions[0]
            for q in np.flatnonzero(new):  # the eater: the live head nearest at the period's start
                d = np.linalg.norm(nose - fp[q], axis=1)
                d[~alive] = np.inf
                i = int(np.argmin(d))
                brains[i].ate(t1)
                events.append((t1, fishes[i].name, "eat", f"food_{q}"))
        for i, j2 in zip(*np.nonzero(np.triu(fish_hit, 1)), strict=True):
            if t1 - fish_touch[i, j2] > APART:
                events.append((t1, fishes[i].name, "collision", fishes[j2].name))
            fish_touch[i, j2] = t1
        for i, o in sorted(touched):
            if o in static_obj and t1 - touching[i, o] > APART:
                events.append((t1, fishes[i].name, "collision", world.objects[o].name))
            touching[i, o] = t1
        # how deep any fish lies in a rock or another fish, once a period (allpos, pos: now)
        if recorded != world.step_count:
            allpos = world.node_positions(0)
            pos = [allpos[o0:o1] for o0, o1 in zip(off[:-1], off[1:], strict=True)]
            recorded = world.step_count
        if len(kind):
            deepest = max(deepest, float(-obstacle_distance(allpos, kind, center, size).min()))
        deepest_fish = max(deepest_fish, _fish_depth(fishes, pos, extent, masses))
        pos, com, fwd, vel, nose = _kinematics(world, weights, cw, heads_of, allpos)
        # catches and matings (fish-fish touches come from the world's contacts above)
        dcoms = np.linalg.norm(com[:, None] - com[None], axis=-1)
        for i, j2 in zip(*np.nonzero(dcoms < NEAR), strict=True):
            i, j2 = int(i), int(j2)
            f, g = fishes[i], fishes[j2]
            if j2 == i or not brains[i].alive or not brains[j2].alive:
                continue
            dcom = float(dcoms[i, j2])
            if g.species.name in f.species.prey and brains[i].thought.intention == "hunt":
                reach = np.linalg.norm(pos[j2] - nose[i], axis=1).min()
                if reach < f.species.motor.catch_radius:
                    brains[j2].alive = False
                    brains[i].ate(t1, 3.0)
                    events.append((t1, f.name, "catch", g.name))
                    continue
            if j2 < i:
                continue
            if (f.species.name == g.species.name and dcom < 1.5
                    and "mate" in (brains[i].thought.intention, brains[j2].thought.intention)
                    and brains[i].willing(t1) and brains[j2].willing(t1)):  # fmt: skip
                brains[i].mated(t1)
                brains[j2].mated(t1)
                events.append((t1, f.name, "mate", g.name))
                events.append((t1, g.name, "mate", f.name))
        if progress is not None:
            progress(t1)
    return Life(
        times=np.array(times) - times[0], positions=[np.stack(p) for p in positions],
        food=np.stack(foods), eaten=np.stack(eaten), brain_times=np.array(b_times),
        drives=np.array(drive_rec, float).reshape(-1, n, 3),
        intentions=np.array(intents, int).reshape(-1, n),
        alive=np.array(alive_rec, bool).reshape(-1, n),
        targets=np.array(target_rec, int).reshape(-1, n), events=events,
        wall_seconds=time.perf_counter() - t_start, deepest=deepest, deepest_fish=deepest_fish,
    )  # fmt: skip


def _fish_depth(fishes: list[Fish], pos: list[np.ndarray], extent: np.ndarray,
                masses: list[tuple[np.ndarray, float]] | None = None) -> float:
    """Return how deep (m) the deepest node of any fish lies inside another fish's closed
    surface (``physics.bodycontact.deepest``), over the pairs whose bounding spheres meet;
    masses: each fish's node masses and total (default from the bodies)."""
    if masses is None:
        masses = [(f.body.mass, f.body.total_mass) for f in fishes]
    com = np.array([m @ p / total for (m, total), p in zip(masses, pos, strict=True)])
    d = np.linalg.norm(com[:, None] - com[None], axis=-1)
    out = 0.0
    for i, j in zip(*np.nonzero(np.triu(d < extent[:, None] + extent[None], 1)), strict=True):
        out = max(out, deepest_into(pos[i], pos[j], fishes[j].body.faces),
                  deepest_into(pos[j], pos[i], fishes[i].body.faces))
    return out


def summarize(tank: Tank, life: Life) -> dict:
    """Return the run's figures: events by kind, food eaten, catches, survivors, timing."""
    kinds = ("eat", "catch", "escape", "mate", "collision")
    counts = {k: sum(1 for e in life.events if e[2] == k) for k in kinds}
    fish_names = {f.name for f in tank.fishes}
    obstacle_hits = sum(1 for e in life.events if e[2] == "collision" and e[3] not in fish_names)
    sim = float(life.times[-1]) if len(life.times) else 0.0
    share = {name: float(np.mean(life.intentions == k)) for k, name in enumerate(INTENTIONS)}
    return {
        "fishes": len(tank.fishes),
        "predators": sum(f.species.predator for f in tank.fishes),
        "food": len(tank.world.foods),
        "obstacles": len(tank.static_names) - 4,
        "seconds": sim,
        "seed": tank.config.seed,
        "perception": tank.config.perception,
        # per species: "learned" (the repertoire shipped for its body), "built-in" or a directory
        "motor_skills": {f.species.name: f.species.to_dict()["motor"]["skills"]
                         for f in tank.fishes},  # fmt: skip
        "tank_half_size_m": tank.config.size(),
        "events": counts,
        "collisions_with_obstacles": obstacle_hits,
        "food_eaten_fraction": float(life.eaten[-1].mean()) if life.eaten.size else 0.0,
        "survivors": int(life.alive[-1].sum()) if life.alive.size else len(tank.fishes),
        "deepest_into_obstacle_m": life.deepest,
        "collisions_between_fishes": counts["collision"] - obstacle_hits,
        "deepest_into_fish_m": life.deepest_fish,
        "intention_share": share,
        "wall_seconds": life.wall_seconds,
        "realtime_factor": sim / life.wall_seconds if life.wall_seconds > 0 else None,
    }


def events_csv(life: Life) -> str:
    """Return the events as CSV text: columns time, fish, event, detail."""
    import csv
    import io

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["time", "fish", "event", "detail"])
    for t, fish, event, detail in life.events:
        w.writerow([f"{t:.2f}", fish, event, detail])
    return buf.getvalue()


def frame_labels(life: Life, names: list[str]) -> list[list[str]]:
    """Return per record time one label per fish: its name and the intention it followed."""
    k = np.clip(np.searchsorted(life.brain_times, life.times + 1e-9, side="right") - 1, 0,
                max(len(life.brain_times) - 1, 0))  # fmt: skip
    return [[f"{nm}: {INTENTIONS[life.intentions[j, i]]}" if life.alive[j, i] else f"{nm}: caught"
             for i, nm in enumerate(names)] for j in k]  # fmt: skip
