"""A tank of artificial fishes living together: each a brain (a Policy) over one World.

``build_tank(TankConfig(...))`` places prey fishes and predators, rocks and seaweed, food and
four walls in water; ``live(tank)`` runs it through the one closed-loop driver
(``control.loop.drive``): every control period the fishes perceive, their brains decide and
their motor layers drive the muscles (``shoal.Shoal``), and the world steps them all in
lockstep; observers record positions and food (``Recorder``), the fishes' body states and how
deep they went into rocks and each other (``bodystate.FishBodies``) and the events: eat,
catch, escape, mate, collision (``events.Events``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from zoetic.behavior.aquarium.bodystate import FishBodies
from zoetic.behavior.aquarium.brain import FishBrain, tank_brains
from zoetic.behavior.aquarium.events import Event, Events
from zoetic.behavior.aquarium.perception import obstacle_distance
from zoetic.behavior.aquarium.plants import PLANTS, PlantSteps, is_weed, tank_plants
from zoetic.behavior.aquarium.shoal import Shoal
from zoetic.behavior.aquarium.species import Species, SpeciesError, load_species, with_skills
from zoetic.behavior.mind import INTENTIONS
from zoetic.bodies import Body, load_animal
from zoetic.control.loop import Observer, Schedule, drive
from zoetic.control.policy import Period
from zoetic.errors import SimulationError
from zoetic.physics.objects import Box, Cylinder, Food, pack_statics
from zoetic.physics.plants import Plants
from zoetic.physics.world import Animal, World

WALL = 0.25  # m: half thickness of the tank's walls
PERCEPTIONS = ("oracle", "vision")
MAX_FISHES, MAX_FOOD, MAX_OBSTACLES = 2000, 3000, 200  # the most a tank holds
HEIGHT = 2.0  # m: half height of the walls, rocks and seaweed (all span the fishes' layer)


@dataclass(frozen=True)
class TankConfig:
    """A tank: how many fishes (predators among them), food particles and obstacles, for how
    long, from which seed (food and obstacles default to grow with the fishes: 1.5 food
    particles a fish, 5 obstacles for 10 fishes times the square root of the fishes over 10,
    as the tank's side grows); ``half_size`` (m, default grows with the crowd), the water
    current (m/s) that carries the food, the brains' control period and the record period
    (s; how often positions are kept: the run is the same whatever it is)."""

    fishes: int = 10
    predators: int = 1
    food: int | None = None  # None: 1.5 a fish (15 for 10 fishes)
    obstacles: int | None = None  # None: 5 sqrt(fishes / 10) (5 for 10 fishes)
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
    perception: str = "oracle"  # or "vision": the first ``seeing`` predators see with animat vision
    seeing: int = 1
    predator_skills: str | None = None  # a learned repertoire's directory for the predator
    # every species' motor skills ("built-in", "learned" or a repertoire's directory) instead
    # of what the species files say (``predator_skills`` then still names the predator's)
    skills: str | None = None
    fish_contact: bool = True  # fishes push each other apart (``physics.bodycontact``)
    # the motor layer's righting reflex: the fins lean against each fish's roll
    # (``behavior.motor.righting``)
    righting: bool = True
    # seaweed as fixed cylinders ("static") or as light spring-mass strands that sway and
    # part around the fishes ("dynamic", ``behavior.aquarium.plants``; about a fifth more CPU
    # time, docs/aquarium.md)
    plants: str = "static"

    def __post_init__(self) -> None:
        crowd = max(int(self.fishes), 1)
        if self.food is None:
            object.__setattr__(self, "food", min(round(1.5 * crowd), MAX_FOOD))
        if self.obstacles is None:
            object.__setattr__(
                self, "obstacles", min(round(5 * math.sqrt(crowd / 10)), MAX_OBSTACLES)
            )

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
    plants: Plants | None = None  # the seaweed's strands (dynamic plants)


def _check(cfg: TankConfig) -> None:
    if cfg.fishes < 1 or cfg.predators < 0 or cfg.predators > cfg.fishes:
        raise SimulationError(
            f"a tank needs at least one fish and at most as many predators as fishes "
            f"(got {cfg.fishes} fishes, {cfg.predators} predators)"
        )
    if cfg.food < 0 or cfg.obstacles < 0:
        raise SimulationError("--food and --obstacles must be at least 0")
    if cfg.fishes > MAX_FISHES or cfg.food > MAX_FOOD or cfg.obstacles > MAX_OBSTACLES:
        raise SimulationError(
            f"at most {MAX_FISHES} fishes, {MAX_FOOD} food particles and {MAX_OBSTACLES} "
            f"obstacles (got {cfg.fishes}, {cfg.food}, {cfg.obstacles})"
        )
    if not 0 < cfg.seconds <= 3600:
        raise SimulationError(f"--seconds must be in (0, 3600], got {cfg.seconds:g}")
    if cfg.perception not in PERCEPTIONS:
        raise SimulationError(
            f"perception must be one of {', '.join(PERCEPTIONS)}, got {cfg.perception!r}"
        )
    if cfg.perception == "vision" and cfg.predators < 1:
        raise SimulationError("--perception vision gives a predator eyes: need --predators >= 1")
    if cfg.perception == "vision" and not 1 <= cfg.seeing <= cfg.predators:
        raise SimulationError(
            f"--seeing must be from 1 to the {cfg.predators} predator(s), got {cfg.seeing}"
        )
    if cfg.plants not in PLANTS:
        raise SimulationError(f"plants must be one of {', '.join(PLANTS)}, got {cfg.plants!r}")
    if not 0 < cfg.control_period <= 1.0 or not 0 < cfg.record_period <= cfg.control_period:
        raise SimulationError("need 0 < record period <= control period <= 1 s")


def _place(rng, half: float, ok: Callable[[np.ndarray], bool], margin: float) -> np.ndarray:
    for _ in range(2000):
        p = np.array(
            [
                rng.uniform(-half + margin, half - margin),
                0.0,
                rng.uniform(-half + margin, half - margin),
            ]
        )
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
    prey, pred = _tank_species(cfg)
    statics = _statics(rng, half, cfg.obstacles)
    kind, center, size = pack_statics(statics)

    def free(p: np.ndarray, gap: float) -> bool:
        return len(kind) == 0 or obstacle_distance(p, kind, center, size).min() > gap

    fishes, animals = _fishes(rng, half, cfg, prey, pred, free)
    foods = [
        Food(tuple(_place(rng, half, lambda p: free(p, 0.6), cfg.food_margin)), cfg.food_radius)
        for _ in range(cfg.food)
    ]
    dynamic = cfg.plants == "dynamic"
    # dynamic seaweed is no solid for the fishes' bodies: they part its strands
    solid = [s for s in statics if not (dynamic and is_weed(s))]
    world = World(
        [*animals, *solid, *foods],
        medium="water",
        current=cfg.current,
        animal_contact=cfg.fish_contact,
    )
    names = [s.name for s in statics]
    plants = (
        tank_plants(statics, cfg.seed, world.medium, cfg.current, world.dt) if dynamic else None
    )
    return Tank(cfg, world, fishes, kind, center, size, names, plants)


def _tank_species(cfg: TankConfig) -> tuple[Species, Species]:
    """Return the prey and predator species, with the motor skills the config asks for."""
    prey, pred = load_species(cfg.prey_species), load_species(cfg.predator_species)
    if not pred.predator:
        raise SpeciesError(f"{pred.source}: species {pred.name!r} is not a predator")
    if cfg.skills is not None:
        where = f"--skills {str(cfg.skills)!r}"
        prey, pred = with_skills(prey, cfg.skills, where), with_skills(pred, cfg.skills, where)
    if cfg.predator_skills is not None:
        where = f"--predator-skills {str(cfg.predator_skills)!r}"
        pred = with_skills(pred, cfg.predator_skills, where)
    return prey, pred


def _statics(rng: np.random.Generator, half: float, obstacles: int) -> list[Box | Cylinder]:
    """Return the four walls and the obstacles (rocks and seaweed by turns, 3 m apart)."""
    statics: list[Box | Cylinder] = []
    for sx, sz in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        c = (sx * (half + WALL), 0.0, sz * (half + WALL))
        hs = (WALL if sx else half + 2 * WALL, HEIGHT, WALL if sz else half + 2 * WALL)
        statics.append(Box(c, hs, name="wall"))
    rocks: list[np.ndarray] = []

    def clear_of_rocks(p: np.ndarray) -> bool:
        return all(np.hypot(*(p - r)[[0, 2]]) > 3.0 for r in rocks)

    for k in range(obstacles):
        p = _place(rng, half, clear_of_rocks, 1.5)
        rocks.append(p)
        r = float(rng.uniform(0.35, 0.7))
        if k % 2 == 0:
            statics.append(Box(tuple(p), (r, HEIGHT, float(rng.uniform(0.35, 0.7))), name="rock"))
        else:
            statics.append(Cylinder(tuple(p), r, 2 * HEIGHT, "y", name="seaweed"))
    return statics


def _fishes(
    rng: np.random.Generator,
    half: float,
    cfg: TankConfig,
    prey: Species,
    pred: Species,
    free: Callable[[np.ndarray, float], bool],
) -> tuple[list[Fish], list[Animal]]:
    """Return the fishes (the predators first) and their animals, each placed clear of the
    obstacles (``free``) and 2 m from the others, at a random heading, swimming at cruise."""
    placed: list[np.ndarray] = []
    fishes, animals = [], []
    spots = np.empty((cfg.fishes, 3))  # the placed fishes' points, row by row

    def apart(p: np.ndarray) -> bool:
        if not free(p, 1.5):
            return False
        # all at once, then one by one only where the squared distance is too close to call
        d2 = ((spots[: len(placed)] - p) ** 2).sum(axis=1)
        if (d2 > 4.0 * (1 + 1e-9)).all():
            return True
        return not (d2 < 4.0 * (1 - 1e-9)).any() and all(
            np.linalg.norm(p - q) > 2.0 for q in placed
        )

    for i in range(cfg.fishes):
        spec = pred if i < cfg.predators else prey
        body = load_animal(spec.body)
        if body.medium not in ("water", "sea"):
            raise SpeciesError(f"{spec.source}: body {spec.body!r} does not live in water")
        p = _place(rng, half, apart, 1.0)
        spots[len(placed)] = p
        placed.append(p)
        yaw = float(rng.uniform(-np.pi, np.pi))
        # the offset places the rest pose; shift it so that the body's centre lands on p
        com0 = body.mass @ body.rest_pos / body.total_mass
        v0 = spec.motor.cruise_speed * np.array([np.cos(yaw), 0.0, np.sin(yaw)])
        animals.append(Animal(body, tuple(p - com0), yaw, tuple(v0)))
        fishes.append(Fish(f"{spec.name}_{i}", spec, body))
    return fishes, animals


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
    events: list[Event] = field(default_factory=list)
    wall_seconds: float = 0.0
    deepest: float = 0.0  # m: the deepest any node went into an obstacle (0 if none)
    deepest_fish: float = 0.0  # m: the deepest any node went inside another fish (0 if none)
    plants: np.ndarray | None = None  # (R, S, M + 1, 3) m: the strands' nodes (dynamic plants)


class Recorder(Observer):
    """What ``Life`` keeps: at each record, the time, every fish's node positions and the food
    (where, and which is eaten); at each control period's start, every fish's drives,
    intention, target and whether it lives."""

    def __init__(self, brains: list[FishBrain], bodies: FishBodies) -> None:
        self.brains, self.bodies = brains, bodies
        self.times: list[float] = []
        self.positions: list[list[np.ndarray]] = [[] for _ in brains]
        self.food: list[np.ndarray] = []
        self.eaten: list[np.ndarray] = []
        self.brain_times: list[float] = []
        self.drives: list[list[tuple[float, float, float]]] = []  # hunger, libido, fear
        self.intentions: list[list[int]] = []
        self.alive: list[np.ndarray] = []
        self.targets: list[list[int]] = []

    def record(self, world: World) -> None:
        """Keep the time, the fishes' node positions and the food now."""
        self.times.append(world.time)
        for p, nodes in zip(
            self.positions, self.bodies.split(self.bodies.nodes(world)), strict=True
        ):
            p.append(nodes)
        self.food.append(world.food_positions[0])
        self.eaten.append(world.food_eaten[0])

    def period(self, world: World, period: Period) -> None:
        """Keep what each brain thought for the period (observed before any catch ends it)."""
        thoughts = [b.thought for b in self.brains]
        self.brain_times.append(period.t0)
        self.drives.append([(x.hunger, x.libido, x.fear) for x in thoughts])
        self.intentions.append([INTENTIONS.index(x.intention) for x in thoughts])
        self.alive.append(np.array([b.alive for b in self.brains]))
        self.targets.append([-1 if x.target is None else x.target for x in thoughts])

    def life(self, events: list[Event], bodies: FishBodies, wall_seconds: float) -> Life:
        """Return the run's record, with its events, deepest intrusions and wall time (s)."""
        n = len(self.brains)
        return Life(
            times=np.array(self.times) - self.times[0],
            positions=[np.stack(p) for p in self.positions],
            food=np.stack(self.food),
            eaten=np.stack(self.eaten),
            brain_times=np.array(self.brain_times),
            drives=np.array(self.drives, float).reshape(-1, n, 3),
            intentions=np.array(self.intentions, int).reshape(-1, n),
            alive=np.array(self.alive, bool).reshape(-1, n),
            targets=np.array(self.targets, int).reshape(-1, n),
            events=events,
            wall_seconds=wall_seconds,
            deepest=bodies.deepest,
            deepest_fish=bodies.deepest_fish,
        )


class _Progress(Observer):
    """Tells a caller the tank's time at each control period's end."""

    def __init__(self, progress: Callable[[float], None]) -> None:
        self.progress = progress

    def period(self, world: World, period: Period) -> None:
        """Tell the time now."""
        self.progress(world.time)


def _eyes(tank: Tank):
    """Return animat-vision eyes for the tank's first ``seeing`` predators
    (``aquarium.vision``)."""
    from zoetic.behavior.aquarium.vision import FishEyes, TankEyes

    hunters = [i for i, f in enumerate(tank.fishes) if f.species.predator]
    colors = [np.array(f.species.color) / 255.0 for f in tank.fishes]
    eyes = []
    for a in hunters[: tank.config.seeing]:
        me = tank.fishes[a]
        prey = next((f for f in tank.fishes if f.species.name in me.species.prey), None)
        prey_body, prey_color = (
            (prey.body, prey.species.color) if prey else (me.body, me.species.color)
        )
        rng, extent = me.species.senses.view_range, 2 * tank.config.size()
        eyes.append(
            FishEyes.build(
                a, me.body, colors, prey_body, np.array(prey_color) / 255.0, rng, -HEIGHT, extent
            )
        )
    return TankEyes(eyes, eyes[0].scenery)


def live(
    tank: Tank, seconds: float | None = None, progress: Callable[[float], None] | None = None
) -> Life:
    """Run the tank for ``seconds`` (default the config's) and return what happened;
    ``progress`` is told the tank's time after each control period."""
    cfg, world = tank.config, tank.world
    species, bodies = [f.species for f in tank.fishes], [f.body for f in tank.fishes]
    statics = (tank.kind, tank.center, tank.size)
    brains = tank_brains(species, bodies, cfg.righting, cfg.seed)
    # how deep the fishes go into the solids (not into dynamic seaweed, which they part)
    state = FishBodies(world, bodies, pack_statics(world.statics))
    eyes = _eyes(tank) if cfg.perception == "vision" else None
    shoal = Shoal(species, brains, state, statics, eyes)
    recorder = Recorder(brains, state)
    events = Events(world, [f.name for f in tank.fishes], species, brains, state)
    # the recorder sees the brains before the events end a caught fish's life; the events read
    # the bodies the state observer has measured at the period's end
    observers: list[Observer] = [recorder, state, events]
    grow = None if tank.plants is None else PlantSteps(tank.plants, world, bodies)
    if grow is not None:
        observers.append(grow)
    if progress is not None:
        observers.append(_Progress(progress))
    # records on the grid every record period from the run's start (step 0 for a new tank)
    every = max(1, int(round(cfg.record_period / world.dt)))
    schedule = Schedule(cfg.control_period, fixed=True, record_every=every, record_end=True)
    t_start = time.perf_counter()
    drive(world, shoal, cfg.seconds if seconds is None else seconds, schedule, observers)
    life = recorder.life(events.log, state, time.perf_counter() - t_start)
    if grow is not None:
        life.plants = grow.positions()
    return life


@dataclass(frozen=True)
class Aquarium:
    """A tank's run: the tank as built, what it recorded and its figures (``summarize``)."""

    tank: Tank
    life: Life
    summary: dict


def aquarium(progress: Callable[[float], None] | None = None, **options) -> Aquarium:
    """Build a tank and let it live; return the tank, its ``Life`` and its summary.

    options: ``TankConfig`` fields (fishes, predators, food, obstacles, seconds, seed,
    perception, skills, ...); progress: told the tank's time after each control period.
    """
    unknown = sorted(set(options) - set(TankConfig.__dataclass_fields__))
    if unknown:
        raise SimulationError(f"unknown aquarium option(s) {unknown}")
    tank = build_tank(TankConfig(**options))
    life = live(tank, progress=progress)
    return Aquarium(tank, life, summarize(tank, life))


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
        "motor_skills": {
            f.species.name: f.species.to_dict()["motor"]["skills"] for f in tank.fishes
        },
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


def frame_labels(life: Life, names: list[str]) -> list[list[str]]:
    """Return per record time one label per fish: its name and the intention it followed."""
    k = np.clip(
        np.searchsorted(life.brain_times, life.times + 1e-9, side="right") - 1,
        0,
        max(len(life.brain_times) - 1, 0),
    )
    return [
        [
            f"{nm}: {INTENTIONS[life.intentions[j, i]]}" if life.alive[j, i] else f"{nm}: caught"
            for i, nm in enumerate(names)
        ]
        for j in k
    ]
