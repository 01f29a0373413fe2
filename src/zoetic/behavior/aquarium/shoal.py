"""Every fish of a tank deciding at once: the closed loop's ``decide`` for the aquarium.

Once a control period ``Shoal`` perceives the tank for every fish (the oracle, and animat
vision for the seeing predators' prey), probes ahead of each for obstacles, reads every fish's
situation and drives in one step over arrays, asks each brain for its motor demand with the
roll and bend its body has now (``FishBodies.posture``), and turns the demands into muscle
activations (fishes that share a motor in one batched call).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from zoetic.behavior.aquarium.bodystate import FishBodies
from zoetic.behavior.aquarium.brain import (
    GO_TO,
    FishBrain,
    View,
    conceded,
    focus_targets,
    situations,
)
from zoetic.behavior.aquarium.locomotion import Demand, LearnedLocomotion, learned_activations
from zoetic.behavior.aquarium.perception import Percepts, obstacle_distance, perceive
from zoetic.behavior.aquarium.routines import (
    CLEARANCE,
    Around,
    Me,
    collision_ahead,
    fish_threats,
    probe_reach,
    probes_ahead_many,
    side_rooms,
    wander,
)
from zoetic.behavior.aquarium.species import Species
from zoetic.behavior.aquarium.steering import avoid_many, flats, go_to_many, keep_depths
from zoetic.behavior.mind import MindState, Situations, Tempers, drives_many, think_many
from zoetic.control.policy import Period
from zoetic.physics.world import World

if TYPE_CHECKING:  # the eyes' renderer loads only for a tank with vision
    from zoetic.behavior.aquarium.vision import TankEyes


NOTHING = Around()  # what a wanderer reads of its surroundings: nothing


@dataclass(frozen=True)
class Moment:
    """What the fishes sense at a control period's start: the food (F, 3), the percepts and
    the fishes' centres as the fishes with eyes see them (``Shoal.perceive``), each fish as
    its routines see itself, what lies ahead of each (``Shoal._ahead``: hits, ways out,
    threats, fish only), the situations and the predators' distances (``situations``) and
    the food each leaves to another (``conceded``)."""

    food: np.ndarray
    pc: Percepts
    seen: dict[int, np.ndarray]
    selves: list[Me]
    ahead: tuple[list, list, list, list]
    sits: Situations
    predators: np.ndarray
    given: np.ndarray


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
        self.tempers = Tempers.of(
            [b.constants for b in brains],
            [s.habits for s in species],
            [s.predator for s in species],
        )
        self.radius = np.array([b.radius for b in brains], float)
        self.top = np.array([b.top for b in brains], float)
        self.constants = [
            np.array([getattr(b.constants, k) for b in brains], float)
            for k in ("hunger_rate", "alpha", "libido_rate", "fear_distance")
        ]

    def __call__(self, world: World, period: Period) -> list[np.ndarray]:
        """Return every fish's activations (1, T, A) for the period: perceive, think, act."""
        now = self._sense(world)
        t, b = period.t0, self.bodies
        hunger, libido, fear = self._drives(t, now.predators)
        roll, rate, bend = (x.tolist() for x in self.bodies.posture(world, t))
        living = [i for i, brain in enumerate(self.brains) if brain.alive]
        # every mind thinks at once (the dead ones' thoughts are dropped)
        thinking = [brain.mind for brain in self.brains]
        thinking = think_many(thinking, t, self.tempers, now.sits, hunger, libido, fear)
        minds: list[MindState | None] = [None] * len(self.brains)
        for i in living:
            self.brains[i].mind = minds[i] = thinking[i]
        targets = focus_targets(
            ["" if m is None else m.intention for m in minds],
            [None if m is None else m.target for m in minds],
            b.nose,
            b.fwd,
            self.radius,
            now.food,
            now.pc.food,
            now.given,
            now.pc.fish,
            self.masks[0],
            self.masks[2],
        )
        moves, heights = self._respond(living, minds, targets, now)
        felt = list(zip(hunger.tolist(), libido.tolist(), fear.tolist(), strict=True))
        for i in living:
            self.brains[i].remember(felt[i], targets[i])
        pitch = keep_depths(b.com[living, 1], b.fwd[living, 1], [heights[i] for i in living])
        demands: list[Demand | None] = [None] * len(self.brains)
        for i, p in zip(living, pitch.tolist(), strict=True):
            # the demand with the body's posture (``Demand(...)``: ``replace`` is slow)
            demands[i] = Demand(*moves[i], p, roll[i], rate[i], bend[i])
        return activations(self.brains, demands, period)

    def _sense(self, world: World) -> Moment:
        """Return what the fishes perceive now, what lies ahead of each, their situations
        and the food each leaves to another (``Moment``)."""
        alive = np.array([b.alive for b in self.brains])
        food = world.food_positions[0]
        pc, seen = self.perceive(world, alive, food)
        selves, meals = self._selves(pc)
        hits, aways, threats, fish_only = self._ahead(pc, selves, meals, alive, food)
        sits, predators = situations(
            pc.fish, pc.food, pc.obstacles, *self.masks, *self.habits, hits, fish_only
        )
        eating = alive & np.array([br.thought.intention == "eat" for br in self.brains])
        b = self.bodies
        sees = np.isfinite(pc.fish)
        given = conceded(b.nose, b.fwd, food, eating, sees, np.isfinite(pc.food))
        ahead = (hits, aways, threats, fish_only)
        return Moment(food, pc, seen, selves, ahead, sits, predators, given)

    def _respond(
        self, living: list[int], minds: list, targets: list[int | None], now: Moment
    ) -> tuple[dict[int, tuple[float, float]], dict[int, float]]:
        """Return each living fish's speed and turn, and the height (m) it keeps, from the
        routine that serves its intention: the fishes going to a target and the avoiding
        ones all at once, the wanderers each with its own random turn, the others (escape,
        school, leave: they read the crowd they see) one by one."""
        b, selves = self.bodies, now.selves
        go = [i for i in living if minds[i].intention in GO_TO and targets[i] is not None]
        speed, turn, wanted = self._go_to(go, targets, now.food, now.seen)
        moves = {i: (s, t) for i, s, t in zip(go, speed.tolist(), turn.tolist(), strict=True)}
        heights = dict(zip(go, wanted.tolist(), strict=True))
        ducks = [i for i in living if minds[i].intention == "avoid"]
        speed, turn = self._avoid(ducks, now)
        moves |= {i: (s, t) for i, s, t in zip(ducks, speed.tolist(), turn.tolist(), strict=True)}
        hits, aways, threats, fish_only = now.ahead
        for i in living:
            if i in moves:
                continue
            if minds[i].intention in GO_TO or minds[i].intention == "wander":
                d = wander(selves[i], NOTHING, self.brains[i].rng)  # (no target: it searches)
                moves[i] = (d.speed, d.turn)
                continue
            view = View(
                me=selves[i],
                fish_distance=now.pc.fish[i],
                fish_com=now.seen.get(i, b.com),
                fish_forward=b.fwd,
                fish_velocity=b.vel,
                fish_species=self.names,
                food_distance=now.pc.food[i],
                food=now.food,
                obstacle_distance=now.pc.obstacles[i],
                collision=hits[i],
                away=aways[i],
                threat=threats[i],
                fish_only=fish_only[i],
                conceded=now.given[i],
            )
            d, height = self.brains[i].routine(view, targets[i])
            moves[i] = (d.speed, d.turn)
            if height is not None:
                heights[i] = height
        # the others keep their layers
        return moves, {i: heights.get(i, selves[i].layer) for i in living}

    def _go_to(
        self, go: list[int], targets: list[int | None], food: np.ndarray, seen: dict
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return the speeds and turns (``go_to_many``) of the fishes ``go`` to their
        targets (food particles, or fishes as each perceives them: ``seen``), and the
        targets' heights (m)."""
        b, rows = self.bodies, np.array(go, int)
        aim, velocity = np.empty((len(go), 3)), np.full((len(go), 3), np.nan)
        lead, beside = np.zeros(len(go)), np.zeros(len(go))
        for k, i in enumerate(go):
            intention, t = self.brains[i].mind.intention, targets[i]
            lead[k] = GO_TO[intention].get("lead", 0.0)
            beside[k] = GO_TO[intention].get("beside", 0.0)
            if intention == "eat":
                aim[k] = food[t]
            else:
                aim[k], velocity[k] = seen.get(i, b.com)[t], b.vel[t]
        speed, turn = go_to_many(
            b.nose[rows], b.com[rows], b.fwd[rows], self.cruise[rows], self.top[rows],
            aim, velocity, lead, beside,
        )  # fmt: skip
        return speed, turn, aim[:, 1]

    def _avoid(self, ducks: list[int], now: Moment) -> tuple[np.ndarray, np.ndarray]:
        """Return the speeds and turns (``avoid_many``) of the avoiding fishes ``ducks``: each
        turning to its way out, as urgently as the nearest obstacle or the threatening fish
        is near."""
        b, rows = self.bodies, np.array(ducks, int)
        _, aways, threats, fish_only = now.ahead
        away = np.array([np.full(3, np.nan) if aways[i] is None else aways[i] for i in ducks])
        obstacles = now.pc.obstacles
        near = obstacles[rows].min(axis=1) if obstacles.shape[1] else np.inf
        obstacle = np.minimum(near, np.array([threats[i] for i in ducks], float))
        only = np.array([fish_only[i] for i in ducks], bool)
        cruise, top, away = self.cruise[rows], self.top[rows], away.reshape(-1, 3)
        return avoid_many(b.fwd[rows], b.vel[rows], cruise, top, away, obstacle, only)

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
        self,
        pc: Percepts,
        selves: list[Me],
        meals: list[float | None],
        alive: np.ndarray,
        food: np.ndarray,
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
        pace = np.sqrt(fb.vel[:, 0] ** 2 + fb.vel[:, 2] ** 2)  # m/s in the horizontal plane
        on = right_of_way(threat, meals, pace >= YIELD_PACE * self.cruise)
        sides[on], near[on] = 0, np.inf  # the other fish yields: this one swims on to its food
        sides = yield_sides(threat, on, fb.com, self._ways(on, food), sides)
        # no obstacle within CLEARANCE of a probe and no fish threatening: nothing ahead
        # (``collision_ahead``'s answer, without asking it for every fish of a crowd)
        rocks = (ahead.min(axis=(1, 2)) < CLEARANCE).tolist() if len(kind) else [False] * len(sides)
        hits, aways, fish_only = [], [], []
        # the room to either side of every fish something lies ahead of, all at once
        asked = [i for i in range(len(sides)) if rocks[i] or sides[i]]
        rooms = {}
        if asked and len(kind):
            reach = np.array([probe_reach(selves[i], meals[i]) for i in asked])
            room = side_rooms(fb.nose[asked], fb.fwd[asked], reach, kind, center, size)
            rooms = dict(zip(asked, map(tuple, room.tolist()), strict=True))
        for i, brain in enumerate(self.brains):
            if not rocks[i] and not sides[i]:
                hits.append(False)
                aways.append(None)
                fish_only.append(False)
                continue
            prefer = brain.avoid_side if brain.thought.intention == "avoid" else 0
            hit, away = collision_ahead(
                selves[i],
                kind,
                center,
                size,
                int(sides[i]),
                prefer,
                meals[i],
                ahead[i],
                rooms.get(i),
            )
            if hit and away is not None:
                # the vertical component of fwd x away: which side the way out lies on
                fwd = fb.fwd[i]
                brain.avoid_side = 1 if fwd[2] * away[0] - fwd[0] * away[2] < 0 else -1
            hits.append(hit)
            aways.append(away)
            fish_only.append(bool(hit and sides[i] and not rocks[i]))
        return hits, aways, near.tolist(), fish_only

    def _ways(self, on: np.ndarray, food: np.ndarray) -> np.ndarray:
        """Return (n, 3) the way each fish swims: its heading, or for the fishes with the right
        of way (``on`` (n,) bools: eaters) from the nose to their food particles."""
        b = self.bodies
        ways = np.array(b.fwd, float)
        eaters = np.flatnonzero(on)
        if len(eaters):
            aim = [self.brains[k].thought.target for k in eaters.tolist()]
            ways[eaters] = food[aim] - b.nose[eaters]
        return ways

    def _drives(self, t: float, predators: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return every fish's hunger, libido and fear (n,) at time ``t`` s at once."""
        minds = [b.mind for b in self.brains]
        meals = [m.eaten for m in minds], [m.meal_time for m in minds]
        return drives_many(*meals, [m.mating_time for m in minds], t, *self.constants, predators)


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


# of its cruise speed: a fish slower than this cannot get out of an eater's way in time
YIELD_PACE = 0.5


def right_of_way(
    threat: np.ndarray, meals: list[float | None], able: np.ndarray | None = None
) -> np.ndarray:
    """Return (n,) bools: the fishes that swim on to their food past a fish that yields.

    Of two fishes that threaten each other (``threat`` (n,): each one's threatening fish,
    ``fish_threats``; -1 none), a fish going for food (``meals``: the distance (m) to the
    particle it is eating, None when not eating) keeps its course and the other yields (it
    avoids this one, as it would anyway); of two going for food, the one nearer its particle
    keeps its course (the first on a tie). Braking for each other cost the eater its meal:
    two fishes stopped, and the particle went to another fish or was left. A fish that
    threatens one that does not see it coming (a flank struck from behind) has no right of
    way: only the fish that would strike can avoid the touch. Nor has a fish that threatens
    one unable to yield (``able`` (n,) bools, default all able): a fish nearly still, braked
    or turning on the spot, stays in the way, and an eater swimming on struck it."""
    n = len(threat)
    meal = np.array([np.inf if m is None else m for m in meals], float)
    other = np.where(threat >= 0, threat, np.arange(n))
    mutual = (threat >= 0) & (threat[other] == np.arange(n))
    first = (meal < meal[other]) | ((meal == meal[other]) & (np.arange(n) < other))
    on = mutual & np.isfinite(meal) & first
    return on if able is None else on & np.asarray(able, bool)[other]


# |cos| between a yielding fish's heading and the eater's over which it turns off the eater's
# line (nearly along it or against it); across it, turning does not take it off the line
ALONG_COS = 0.5


def yield_sides(
    threat: np.ndarray, on: np.ndarray, com: np.ndarray, ways: np.ndarray, sides: np.ndarray
) -> np.ndarray:
    """Return the sides (n,) to turn to (+1 left, -1 right) with each yielding fish's side
    off the way of the eater it yields to (``right_of_way``): to the side of the eater's
    line (its centre along its way) that the yielder's centre lies on, so that it moves out
    of the eater's way.

    The closest approach foreseen from the velocities sways with each tail beat, so a side
    taken from it turns a yielder head on one way and the other and leaves it on the eater's
    line; the eater's line does not sway. A yielder swimming across the eater's line
    (headings more than 60 degrees apart), or on it, keeps ``sides``. threat (n,): each
    fish's threat (-1 none); on (n,) bools: the fishes with the right of way; com (n, 3);
    ways (n, 3): the yielders' headings, the eaters' ways (from the nose to the particle,
    ``Shoal._ways``)."""
    k = np.where(threat >= 0, threat, 0)
    yields = (threat >= 0) & on[k] & ~on
    if not yields.any():
        return sides
    f = flats(ways)
    f /= np.maximum(np.linalg.norm(f, axis=1, keepdims=True), 1e-9)
    left = np.stack([-f[:, 2], np.zeros(len(f)), f[:, 0]], axis=1)
    offset = np.einsum("nc,nc->n", com - com[k], left[k])  # m left of the eater's line
    along = np.einsum("nc,nc->n", left, left[k])  # the eater's left seen from the yielder
    off = yields & (np.abs(along) > ALONG_COS) & (np.abs(offset) > 1e-3)
    out = np.array(sides)
    out[off] = (np.sign(offset) * np.sign(along))[off].astype(out.dtype)
    return out


def activations(
    brains: list[FishBrain], demands: list[Demand | None], period: Period
) -> list[np.ndarray]:
    """Return each fish's activations (1, T, A) for its demand (zeros when dead): fishes that
    share a motor (body and wave frequency, or body and learned repertoire) in one batched
    call (each learned fish with its own turn under way)."""
    rows: list[np.ndarray] = [np.empty(0)] * len(brains)
    groups: dict[int, list[int]] = {}
    times = period.times
    for i, (b, d) in enumerate(zip(brains, demands, strict=True)):
        if d is None:
            rows[i] = np.zeros((1, period.steps, b.body.n_actuators))
        else:
            groups.setdefault(id(b.locomotion.motor), []).append(i)
    for idx in groups.values():
        first = brains[idx[0]].locomotion
        if isinstance(first, LearnedLocomotion):
            fishes = [brains[i].locomotion for i in idx]
            acts = learned_activations(fishes, [demands[i] for i in idx], times)
        else:
            acts = first.activations_many([demands[i] for i in idx], times)
        for k, i in enumerate(idx):
            rows[i] = acts[k : k + 1]
    return rows
