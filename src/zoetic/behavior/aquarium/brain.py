"""A fish's brain as a Policy: its percept in, its motor demand and activations out.

Every control period the brain's mind (drives, intention generator) thinks over the fish's
situation, the focuser picks a target, a behaviour routine turns intention and target into a
motor demand (speed, turn, pitch) and the motor layer (``locomotion``) into muscle activations.
``situations`` reads every fish's situation from all the percepts at once.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from functools import cached_property, lru_cache

import numpy as np

from zoetic.behavior.aquarium.locomotion import (
    Demand,
    LearnedLocomotion,
    MotorLocomotion,
    learned_motor,
)
from zoetic.behavior.aquarium.reach import reach_pairs
from zoetic.behavior.aquarium.routines import (
    Around,
    Me,
    avoid,
    escape,
    go_to,
    keep_depth,
    leave,
    school,
    wander,
)
from zoetic.behavior.aquarium.species import BUILT_IN, Species
from zoetic.behavior.mind import (
    MindState,
    Situations,
    Tempers,
    ate,
    drives,
    drives_many,
    focus_many,
    focus_pairs,
    initial_mind,
    think_many,
)
from zoetic.behavior.mind import mated as mind_mated
from zoetic.bodies import Body
from zoetic.control.policy import Period

# how ``go_to`` approaches each intention's target: eat it, court beside a mate (0.6 m), aim
# 0.5 s ahead of a prey
GO_TO: dict[str, dict[str, float]] = {"eat": {}, "mate": {"beside": 0.6}, "hunt": {"lead": 0.5}}
# the routines that read the perceived fishes (``Around.fish``, ``same``, ``predators``):
# for the others ``_around`` leaves them empty (a crowd's fishes masked for nothing)
CROWD_ROUTINES = frozenset(("escape", "school", "leave"))


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
    threat: float = np.inf  # m from the nose to a fish that threatens a collision (inf: none)
    fish_only: bool = False  # the collision threatens from another fish only, no obstacle
    # (F,) particles another fish nearer to them is heading for (``conceded``; None: none)
    conceded: np.ndarray | None = None


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

    def __init__(
        self, species: Species, body: Body, hunted_by: frozenset[str], righting: bool = True
    ) -> None:
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

    @cached_property
    def tempers(self) -> Tempers:
        """Return the mind's tempers for ``decide`` (one fish; a tank's ``Shoal`` keeps all
        its fishes' at once, so a crowd's brains never work out their own)."""
        return Tempers.of([self.constants], [self.species.habits], [self.species.predator])

    def reset(self, seed: int | None = None) -> None:
        """Start a life: a fresh mind with the species' initial hunger, a reseeded wander."""
        self.rng = np.random.default_rng(seed)
        self.mind: MindState = initial_mind(
            self.species.mind.initial_hunger, self.species.mind.hunger_rate
        )
        self.alive = True
        self.thought = Thought(0.0, 0.0, 0.0, self.mind.intention, None)
        # the fish a predator hunts, kept while an avoidance interrupts the hunt (None: none):
        # its touch of that fish is the hunt's, not a collision (``events.Events``)
        self.prey: int | None = None
        if isinstance(self.locomotion, LearnedLocomotion):
            self.locomotion.turning, self.locomotion.last = None, (0, -np.inf)

    def willing(self, t: float) -> bool:
        """Return True when the fish would mate at time t: its libido (which a mating resets)
        above the desire threshold, and it is not fleeing or avoiding."""
        lib = drives(self.mind, t, self.constants).libido
        busy = self.thought.intention in ("escape", "school", "avoid")
        return lib > self.species.mind.desire_threshold and not busy

    def ate(self, t: float, particles: float = 1.0) -> None:
        """Record a meal at time t."""
        self.mind = ate(self.mind, t, particles)

    def mated(self, t: float) -> None:
        """Record a mating at time t."""
        self.mind = mind_mated(self.mind, t)

    def kinds(self, names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return (same species, hunters, prey) masks over the tank's fishes (cached)."""
        known = getattr(self, "_names", None)
        if known is not names and known != names:  # the tank's own tuple: no compare
            self._names = names
            prey = tuple(self.species.prey)
            self._masks = kind_masks(names, self.species.name, self.hunted_by, prey)
        return self._masks

    def _situation(self, v: View) -> tuple[Situations, np.ndarray]:
        """The fish's situation from its own view (``situations`` for one fish)."""
        same, hunters, prey = self.kinds(v.fish_species)
        h = self.species.habits
        return situations(
            v.fish_distance[None],
            v.food_distance[None],
            v.obstacle_distance[None],
            same[None],
            hunters[None],
            prey[None],
            np.array([h.personal_space]),
            np.array([h.crowd]),
            [v.collision],
            [v.fish_only],
        )

    def act(self, observation: Mapping, period: Period) -> np.ndarray:
        """Return activations (1, T, A) for the period from the fish's percept (the percept
        holds no roll, so the righting reflex rests here: the tank measures the rolls)."""
        demand = self.decide(observation, period)
        if demand is None:
            return np.zeros((1, period.steps, self.body.n_actuators))
        return self.locomotion.activations(demand, period.times)[None]

    def decide(self, observation: Mapping, period: Period) -> Demand | None:
        """Return the motor demand for the period from the fish's percept (None: dead). A
        tank's ``Shoal`` takes the same steps for all its fishes at once: ``situations``,
        ``drives_many``, ``think_many``, ``focus_targets``, ``respond``."""
        if not self.alive:
            return None
        v: View = observation["view"]
        sit, predators = self._situation(v)
        m, c = self.mind, self.constants
        drives = drives_many(
            [m.eaten], [m.meal_time], [m.mating_time], period.t0,
            c.hunger_rate, c.alpha, c.libido_rate, c.fear_distance, predators,
        )  # fmt: skip
        (self.mind,) = think_many([m], period.t0, self.tempers, sit, *drives)
        me, masks = v.me, self.kinds(v.fish_species)
        (target,) = focus_targets(
            [self.mind.intention],
            [self.mind.target],
            me.nose[None],
            me.forward[None],
            np.array([me.radius]),
            v.food,
            v.food_distance[None],
            None if v.conceded is None else v.conceded[None],
            v.fish_distance[None],
            masks[0][None],
            masks[2][None],
        )
        return self.respond(v, target, tuple(float(x[0]) for x in drives))

    def respond(self, v: View, target: int | None, drives: tuple[float, ...]) -> Demand:
        """Return the motor demand of the routine that serves the mind's intention, for the
        target the focuser picked (kept in the mind), and keep the thought."""
        demand, height = self.routine(v, target)
        self.remember(drives, target)
        return keep_depth(v.me, demand, height)

    def routine(self, v: View, target: int | None) -> tuple[Demand, float | None]:
        """Return the demand of the routine that serves the mind's intention for the target
        (before ``keep_depth``), and the height (m) to keep: the target's (None: its layer)."""
        intention = self.mind.intention
        around = self._around(v, intention, target, self.kinds(v.fish_species))
        demand = self._routine(intention, v.me, around)
        return demand, None if around.target is None else float(around.target[1])

    def remember(self, drives: tuple[float, ...], target: int | None) -> None:
        """Keep the focused target in the mind and the period's thought (drives: hunger,
        libido, fear)."""
        if target != self.mind.target:
            self.mind = replace(self.mind, target=target)
        hunger, libido, fear = drives
        self.thought = Thought(hunger, libido, fear, self.mind.intention, target)
        if self.mind.intention == "hunt":
            self.prey = target
        elif self.mind.intention != "avoid":
            self.prey = None

    def _around(
        self, v: View, intention: str, target: int | None, masks: tuple[np.ndarray, ...]
    ) -> Around:
        """Return what the routines read of the fish's surroundings: the fishes it sees and
        the predators among them (for the routines that read them: ``CROWD_ROUTINES``), its
        target (and the target fish's velocity), the way out of a collision and the nearest
        obstacle's (or threatening fish's) distance; masks: the fishes' ``kinds``."""
        food = intention == "eat"
        crowd = {}
        if intention in CROWD_ROUTINES:
            same, hunters, _ = masks
            seen = np.isfinite(v.fish_distance)
            crowd = dict(
                fish=v.fish_com[seen],
                fish_forward=v.fish_forward[seen],
                same=same[seen],
                predators=v.fish_com[seen & hunters],
            )
        return Around(
            **crowd,
            target=None if target is None else (v.food if food else v.fish_com)[target],
            target_velocity=None if target is None or food else v.fish_velocity[target],
            away=v.away,
            obstacle=min(
                float(v.obstacle_distance.min()) if len(v.obstacle_distance) else np.inf,
                v.threat,
            ),
            fish_only=v.fish_only,
        )

    def _routine(self, intention: str, me: Me, around: Around) -> Demand:
        """Return the motor demand of the behaviour routine that serves the intention."""
        if intention in GO_TO:
            return go_to(me, around, self.rng, **GO_TO[intention])
        if intention == "avoid":
            return avoid(me, around)
        if intention == "escape":
            return escape(me, around)
        if intention == "school":
            return school(me, around)
        if intention == "leave":
            return leave(me, around)
        return wander(me, around, self.rng)


def focus_targets(
    intentions: list[str],
    previous: list[int | None],
    nose: np.ndarray,
    forward: np.ndarray,
    radius: np.ndarray,
    food: np.ndarray,
    food_distance: np.ndarray,
    given: np.ndarray | None,
    fish_distance: np.ndarray,
    same: np.ndarray,
    prey: np.ndarray,
) -> list[int | None]:
    """Return the target each of n focusers picks for its mind's intention (a food particle,
    a mate or a prey: its index; None for an intention without one, or none perceived), all
    at once over arrays (``mind.focus_many``); previous: each mind's target.

    Eat: the particles by the way to them (``reach_pairs``), not those left to another
    (``given`` (n, F), ``conceded``; all conceded: it races for one); mate and hunt: the
    nearest fish of its species, or of its prey (``same``, ``prey`` (n, M) masks over the
    perceived fishes' distances ``fish_distance`` (n, M)). nose, forward (n, 3); radius (n,):
    the fishes' sharpest turns (m); food (F, 3), food_distance (n, F) as perceived."""
    out: list[int | None] = [None] * len(intentions)
    prev = np.array([-1 if p is None else p for p in previous], int)
    for intention in ("eat", "mate", "hunt"):
        rows = np.array([k for k, x in enumerate(intentions) if x == intention], int)
        if not len(rows):
            continue
        if intention == "eat":  # the pairs of a fish and a particle it perceives
            ii, pp = np.nonzero(food_distance[rows] < np.inf)
            if given is not None:
                left = given[rows[ii], pp]
                free = np.bincount(ii[~left], minlength=len(rows)) > 0
                keep = ~left | ~free[ii]  # all conceded: it races for one
                ii, pp = ii[keep], pp[keep]
            cost = reach_pairs(nose, forward, radius, food, rows[ii], pp)
            picked = focus_pairs(len(rows), ii, pp, cost, prev[rows])
        else:
            mask = (same if intention == "mate" else prey)[rows]
            picked = focus_many(np.where(mask, fish_distance[rows], np.inf), prev[rows])
        for k, t in zip(rows.tolist(), picked.tolist(), strict=True):
            out[k] = None if t < 0 else t
    return out


def situations(
    fish: np.ndarray,
    food: np.ndarray,
    obstacles: np.ndarray,
    same: np.ndarray,
    hunters: np.ndarray,
    prey: np.ndarray,
    personal_space: np.ndarray,
    crowd: np.ndarray,
    collision,
    fish_only=None,
) -> tuple[Situations, np.ndarray]:
    """Return every fish's situation from all the percepts at once (``Situations``), and
    (n, n) the distances of the predators each perceives (inf elsewhere, for
    ``mind.drives_many``).

    fish (n, M), food (n, F), obstacles (n, S): the distances perceived by each of n fishes
    (inf: not perceived, ``Percepts``; M = n in the tank, one row for ``FishBrain._situation``);
    same, hunters, prey (n, M): row i the masks of ``FishBrain.kinds`` of fish i;
    personal_space, crowd (n,): the habits; collision (n,) bools; fish_only (n,) bools: the
    collision threatens from another fish only (default none)."""
    n = len(fish)
    inf = np.full(n, np.inf)
    predators = np.where(hunters, fish, np.inf)
    near_obstacle = (
        obstacles.min(axis=1) < personal_space if obstacles.shape[1] else np.zeros(n, bool)
    )
    sits = Situations(
        collision=np.array(collision, bool),
        food_distance=food.min(axis=1) if food.shape[1] else inf,
        mate_distance=np.where(same, fish, np.inf).min(axis=1) if n else inf,
        prey_distance=np.where(prey, fish, np.inf).min(axis=1) if n else inf,
        crowded=(fish < personal_space[:, None]).sum(axis=1) > crowd,
        alone=~np.isfinite(fish).any(axis=1),
        near_obstacle=near_obstacle,
        fish_only=np.zeros(n, bool) if fish_only is None else np.array(fish_only, bool),
    )
    return sits, predators


CONCEDE_COS = 0.7  # a fish heads for a particle within about 45 degrees of its heading


def conceded(
    nose: np.ndarray,
    forward: np.ndarray,
    food: np.ndarray,
    eating: np.ndarray,
    seen: np.ndarray,
    wanted: np.ndarray | None = None,
) -> np.ndarray:
    """Return (n, F): the food particles each of n fishes leaves to another, for its focuser
    (only where ``wanted`` (n, F), default everywhere: the particles each fish perceives).

    Fish i concedes particle p when a fish it perceives (``seen`` (n, n)) that is eating
    (``eating`` (n,)) is nearer to p than i (horizontally, nose to particle) and heads for it
    (p within about 45 degrees of its heading): racing it there would end in a collision or
    a lost meal, while another particle is free. Our addition to Tu's focuser (which takes
    the nearest food): with ten fishes after fifteen particles the minnows otherwise
    converged on the same particles and collided there. nose, forward (n, 3); food (F, 3)."""
    eating = np.asarray(eating, bool)
    n = len(nose)
    # the pairs (i, k) of a fish i and an eating fish k it perceives, and for each pair the
    # particles i wants (a crowd's fishes see a few particles each, a few fishes each)
    ii, kk = np.nonzero(np.asarray(seen, bool))
    ii, kk = ii[eating[kk]], kk[eating[kk]]
    want = np.ones((n, len(food)), bool) if wanted is None else np.asarray(wanted, bool)
    rows, cols = np.nonzero(want)
    start = np.searchsorted(rows, np.arange(n + 1))
    count = (start[1:] - start[:-1])[ii]
    pair = np.repeat(np.arange(len(ii)), count)
    at = np.arange(len(pair)) - np.repeat(np.cumsum(count) - count, count)
    q = start[ii][pair] + at  # the (i, p) pair of each triple
    i, k, p = ii[pair], kk[pair], cols[q]
    out = np.zeros(want.shape, bool)
    if len(p) == 0:
        return out
    # nose to particle, horizontally, of each fish i to each particle it wants (once a pair)
    # and of the eating fish k, for these triples only (every fish to every particle is
    # n F vectors: 36 MB at 1000 fishes)
    d_i = _horizontal(food[cols] - nose[rows])[0][q]
    d_k, to_k = _horizontal(food[p] - nose[k])
    cos = np.einsum("mc,mc->m", to_k, forward[k]) / np.maximum(d_k, 1e-9)
    given = (cos > CONCEDE_COS) & (d_k < d_i)  # k is nearer to p than i, heading there
    out[i[given], p[given]] = True
    return out


def _horizontal(to: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the lengths (m) of the vectors ``to`` (m, 3) taken horizontally, and the
    horizontal vectors (``to``'s height zeroed in place)."""
    to[:, 1] = 0.0
    return np.linalg.norm(to, axis=-1), to


@lru_cache(maxsize=16)
def kind_masks(
    names: tuple[str, ...], name: str, hunted_by: frozenset[str], prey: tuple[str, ...]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return (same species, hunters, prey) masks (read-only) over the fishes' species
    ``names`` for a fish of species ``name``: worked out once for all the fishes of a
    species (a crowd's thousand fishes of two species ask twice)."""
    same = np.array([x == name for x in names], bool)
    hunters = np.array([x in hunted_by for x in names], bool)
    hunted = np.array([x in prey for x in names], bool)
    for mask in (same, hunters, hunted):
        mask.setflags(write=False)
    return same, hunters, hunted


def tank_brains(
    species: list[Species], bodies: list[Body], righting: bool, seed: int
) -> list[FishBrain]:
    """Return a brain for each fish of a tank (its species and body), each knowing which of
    the tank's species hunt it, reset for a life from the tank's seed (fish i: seed * 1000 + i)."""
    kinds = {s.name: s for s in species}.values()
    hunted_by = {s.name: frozenset(h.name for h in species if s.name in h.prey) for s in kinds}
    brains = [
        FishBrain(s, b, hunted_by[s.name], righting) for s, b in zip(species, bodies, strict=True)
    ]
    for i, brain in enumerate(brains):
        brain.reset(seed * 1000 + i)
    return brains
