"""Every fish of a tank deciding at once: the closed loop's ``decide`` for the aquarium.

Once a control period ``Shoal`` perceives the tank for every fish (the oracle, and animat
vision for the seeing predators' prey), probes ahead of each for obstacles, reads every fish's
situation and drives in one step over arrays, asks each brain for its motor demand with the
roll and bend its body has now (``FishBodies.posture``), and turns the demands into muscle
activations (fishes that share a motor in one batched call).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from zoetic.behavior.aquarium.bodystate import FishBodies
from zoetic.behavior.aquarium.brain import FishBrain, View, conceded, situations
from zoetic.behavior.aquarium.locomotion import Demand, LearnedLocomotion
from zoetic.behavior.aquarium.perception import Percepts, obstacle_distance, perceive
from zoetic.behavior.aquarium.routines import (
    CLEARANCE,
    Me,
    collision_ahead,
    fish_threats,
    probes_ahead_many,
)
from zoetic.behavior.aquarium.species import Species
from zoetic.behavior.mind import Drives, drives_many
from zoetic.control.policy import Period
from zoetic.physics.world import World

if TYPE_CHECKING:  # the eyes' renderer loads only for a tank with vision
    from zoetic.behavior.aquarium.vision import TankEyes


class Shoal:
    """The tank's fishes' brains over their bodies, asked for activations once a period.

    statics: the tank's obstacles (kind, center, size) as ``pack_statics`` returns them;
    eyes: animat vision for the seeing predators (None: every fish perceives by the oracle).
    """

    def __init__(
        self,
        species: list[Species],
        brains: list[FishBrain],
        bodies: FishBodies,
        statics: tuple[np.ndarray, ...],
        eyes: TankEyes | None = None,
    ) -> None:
        self.species, self.brains, self.bodies = species, brains, bodies
        self.statics, self.eyes = statics, eyes
        self.names = tuple(s.name for s in species)
        self.senses = [
            np.array([getattr(s.senses, k) for s in species])
            for k in ("view_angle", "view_range", "smell_range")
        ]
        # the collision sensitivity region: reach, half width (m), anticipation (s)
        self.region = [
            np.array([getattr(s.senses, k) for s in species], float)
            for k in ("collision_reach", "collision_half_width", "collision_anticipation")
        ]
        # each fish's kinds of fishes (rows: same species, hunters, prey), habits and constants
        kinds = [b.kinds(self.names) for b in brains]
        self.masks = tuple(np.array([k[x] for k in kinds]) for x in range(3))
        self.habits = (
            np.array([s.habits.personal_space for s in species], float),
            np.array([s.habits.crowd for s in species]),
        )
        self.cruise = np.array([b.cruise for b in brains], float)
        self.constants = [
            np.array([getattr(b.constants, k) for b in brains], float)
            for k in ("hunger_rate", "alpha", "libido_rate", "fear_distance")
        ]

    def __call__(self, world: World, period: Period) -> list[np.ndarray]:
        """Return every fish's activations (1, T, A) for the period: perceive, think, act."""
        alive = np.array([b.alive for b in self.brains])
        food = world.food_positions[0]
        pc, seen = self.perceive(world, alive, food)
        selves, meals = self._selves(pc)
        hits, aways, threats, fish_only = self._ahead(pc, selves, meals, alive)
        sits, predators = situations(
            pc.fish, pc.food, pc.obstacles, *self.masks, *self.habits, hits, fish_only
        )
        eating = alive & np.array([br.thought.intention == "eat" for br in self.brains])
        b = self.bodies
        sees = np.isfinite(pc.fish)
        given = conceded(b.nose, b.fwd, food, eating, sees, np.isfinite(pc.food))
        drives = self._drives(period.t0, predators)
        roll, rate, bend = (x.tolist() for x in self.bodies.posture(world, period.t0))
        b, obs = self.bodies, {"time": np.array([period.t0])}
        demands: list[Demand | None] = []
        for i, brain in enumerate(self.brains):
            view = View(
                me=selves[i],
                fish_distance=pc.fish[i],
                fish_com=seen.get(i, b.com),
                fish_forward=b.fwd,
                fish_velocity=b.vel,
                fish_species=self.names,
                food_distance=pc.food[i],
                food=food,
                obstacle_distance=pc.obstacles[i],
                collision=hits[i],
                away=aways[i],
                threat=threats[i],
                fish_only=fish_only[i],
                conceded=given[i],
            )
            d = brain.decide({**obs, "view": view}, period, sits[i], drives[i])
            # the demand with the body's posture (``Demand(...)``: ``replace`` is slow)
            demands.append(
                None if d is None else Demand(d.speed, d.turn, d.pitch, roll[i], rate[i], bend[i])
            )
        return activations(self.brains, demands, period)

    def perceive(
        self, world: World, alive: np.ndarray, food: np.ndarray
    ) -> tuple[Percepts, dict[int, np.ndarray]]:
        """Return every fish's percepts (the oracle's) and, for a fish with eyes, the fishes'
        centres as it sees them: its prey only where its eyes see them."""
        b, (kind, center, size) = self.bodies, self.statics
        left = ~world.food_eaten[0]
        pc = perceive(b.nose, b.fwd, b.com, alive, food, left, kind, center, size, *self.senses)
        seen: dict[int, np.ndarray] = {}
        if self.eyes is None:
            return pc, seen
        prey = {
            a: np.array(
                [j for j in range(len(alive)) if alive[j] and j != a and self.names[j] in hunted],
                int,
            )
            for a in self.eyes.animals
            if alive[a]
            for hunted in [self.species[a].prey]
        }
        for a, sight in self.eyes.see(world, prey).items():
            pc.fish[a, prey[a]] = np.inf  # prey only as the eyes see it
            seen[a] = b.com.copy()
            if sight is not None:
                pc.fish[a, sight.fish] = sight.distance
                seen[a][sight.fish] = sight.point
        return pc, seen

    def _selves(self, pc: Percepts) -> tuple[list[Me], list[float | None]]:
        """Return each fish as its routines see itself, and the distance to the food particle
        it is eating (None when not eating)."""
        b, selves, meals = self.bodies, [], []
        for i, brain in enumerate(self.brains):
            selves.append(
                Me(b.com[i], b.nose[i], b.fwd[i], b.vel[i], brain.cruise, brain.top, brain.radius)
            )
            th = brain.thought
            eating = th.intention == "eat" and th.target is not None
            meals.append(pc.food[i, th.target] if eating else None)
        return selves, meals

    def _ahead(
        self, pc: Percepts, selves: list[Me], meals: list[float | None], alive: np.ndarray
    ) -> tuple[list[bool], list[np.ndarray | None], list[float], list[bool]]:
        """Return for each fish whether an obstacle or fish lies ahead, the way out, how
        far (m) a threatening fish is (inf: none), and whether only a fish threatens (no
        obstacle ahead); an avoiding fish keeps the side it turned to. A hunting predator
        does not shy away from the prey it chases; a dead fish's body (``carcasses``) is
        avoided as a fish is."""
        kind, center, size = self.statics
        fb = self.bodies
        seen = np.isfinite(pc.fish) | carcasses(fb.nose, fb.com, alive, self.senses[1])
        probes = probes_ahead_many(fb.nose, fb.fwd, fb.vel, self.cruise, meals)
        ahead = obstacle_distance(probes, kind, center, size)  # all fishes at once
        for i, brain in enumerate(self.brains):
            th = brain.thought
            if th.intention == "hunt" and th.target is not None:
                seen[i, th.target] = False
        avoiding = [b.avoid_side if b.thought.intention == "avoid" else 0 for b in self.brains]
        threat, sides, near = fish_threats(
            fb.nose, fb.com, fb.fwd, fb.vel, seen, *self.region, np.array(avoiding)
        )
        on = right_of_way(threat, meals)
        sides[on], near[on] = 0, np.inf  # the other fish yields: this one swims on to its food
        # no obstacle within CLEARANCE of a probe and no fish threatening: nothing ahead
        # (``collision_ahead``'s answer, without asking it for every fish of a crowd)
        rocks = (ahead.min(axis=(1, 2)) < CLEARANCE).tolist() if len(kind) else [False] * len(sides)
        hits, aways, fish_only = [], [], []
        for i, brain in enumerate(self.brains):
            if not rocks[i] and not sides[i]:
                hits.append(False)
                aways.append(None)
                fish_only.append(False)
                continue
            prefer = brain.avoid_side if brain.thought.intention == "avoid" else 0
            hit, away = collision_ahead(
                selves[i], kind, center, size, int(sides[i]), prefer, meals[i], ahead[i]
            )
            if hit and away is not None:
                # the vertical component of fwd x away: which side the way out lies on
                fwd = fb.fwd[i]
                brain.avoid_side = 1 if fwd[2] * away[0] - fwd[0] * away[2] < 0 else -1
            hits.append(hit)
            aways.append(away)
            fish_only.append(bool(hit and sides[i] and not rocks[i]))
        return hits, aways, near.tolist(), fish_only

    def _drives(self, t: float, predators: np.ndarray) -> list[Drives]:
        """Return every fish's drives at time ``t`` s in one step over arrays."""
        minds = [b.mind for b in self.brains]
        meals = [m.eaten for m in minds], [m.meal_time for m in minds]
        arrays = drives_many(*meals, [m.mating_time for m in minds], t, *self.constants, predators)
        hunger, libido, fear = (x.tolist() for x in arrays)
        return [Drives(h, lib, f) for h, lib, f in zip(hunger, libido, fear, strict=True)]


def carcasses(
    nose: np.ndarray, com: np.ndarray, alive: np.ndarray, view_range: np.ndarray
) -> np.ndarray:
    """Return (n, n): the dead fishes' bodies (columns) that each live fish (rows) has in
    view range (m, its nose to the body's centre): a body left in the water (a catch) is
    perceived by no one as a fish, yet it is in the way, and fishes ran into it."""
    dead = ~np.asarray(alive, bool)
    out = np.zeros((len(nose), len(nose)), bool)
    if dead.any():
        d = np.linalg.norm(com[None, dead] - nose[:, None], axis=-1)
        out[:, dead] = d < view_range[:, None]
        out[dead] = False
    return out


def right_of_way(threat: np.ndarray, meals: list[float | None]) -> np.ndarray:
    """Return (n,) bools: the fishes that swim on to their food past a fish that yields.

    Of two fishes that threaten each other (``threat`` (n,): each one's threatening fish,
    ``fish_threats``; -1 none), a fish going for food (``meals``: the distance (m) to the
    particle it is eating, None when not eating) keeps its course and the other yields (it
    avoids this one, as it would anyway); of two going for food, the one nearer its particle
    keeps its course (the first on a tie). Braking for each other cost the eater its meal:
    two fishes stopped, and the particle went to another fish or was left. A fish that
    threatens one that does not see it coming (a flank struck from behind) has no right of
    way: only the fish that would strike can avoid the touch."""
    n = len(threat)
    meal = np.array([np.inf if m is None else m for m in meals], float)
    other = np.where(threat >= 0, threat, np.arange(n))
    mutual = (threat >= 0) & (threat[other] == np.arange(n))
    first = (meal < meal[other]) | ((meal == meal[other]) & (np.arange(n) < other))
    return mutual & np.isfinite(meal) & first


def activations(
    brains: list[FishBrain], demands: list[Demand | None], period: Period
) -> list[np.ndarray]:
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
