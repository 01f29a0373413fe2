"""What happens in a tank, as events: meals, collisions, catches, matings and escapes.

``Events`` observes the closed loop (``control.loop``): each stepped slice's contacts tell which
fishes touched an obstacle or each other; at each control period's end it finds the food
eaten, the touches that start a collision, the catches and matings among fishes near each
other, and the fear episodes that ended with the fish alive. Catches and matings act on the
fishes' brains (a caught fish dies; a meal or a mating resets the drive).
"""

from __future__ import annotations

import numpy as np

from zoetic.behavior.aquarium.bodystate import FishBodies, near_pairs
from zoetic.behavior.aquarium.brain import FishBrain
from zoetic.behavior.aquarium.species import Species
from zoetic.control.loop import Observer
from zoetic.control.policy import Period
from zoetic.physics.objects import Box, Cylinder
from zoetic.physics.world import World

NEAR = 2.5  # m between centres within which fishes may catch or mate (1 m bodies)
MATE_NEAR = 1.5  # m between centres within which two willing fishes mate
APART = 1.0  # s: a touch counts as a new collision after this long apart
FEAR = ("escape", "school")  # the intentions of a fear episode

Event = tuple[float, str, str, str]  # time s, fish, what, detail (food, fish or obstacle)


class Events(Observer):
    """The tank's events in order (``log``), found from the world's contacts and the
    fishes' bodies (``FishBodies``, observed before this) and brains."""

    def __init__(
        self,
        world: World,
        names: list[str],
        species: list[Species],
        brains: list[FishBrain],
        bodies: FishBodies,
    ) -> None:
        n = len(brains)
        self.names, self.species, self.brains, self.bodies = names, species, brains, bodies
        self.log: list[Event] = []
        self.obstacles = [i for i, o in enumerate(world.objects) if isinstance(o, Box | Cylinder)]
        self.object_touch = np.full((n, len(world.objects)), -np.inf)  # when last touched
        self.fish_touch = np.full((n, n), -np.inf)
        self.caught = np.full((n, n), -np.inf)  # s: when fish (row) caught fish (column)
        self.in_fear = np.zeros(n, bool)
        self._start(world)

    def _start(self, world: World) -> None:
        """Begin a period: what was eaten before it, the noses at its start, no touches yet."""
        self.eaten = world.food_eaten[0]
        self.nose = self.bodies.nose
        self.touched: set[tuple[int, int]] = set()
        self.fish_hit = np.zeros((len(self.brains),) * 2, bool)

    def slice(self, world: World, contacts) -> None:
        """Note which fishes touched each other and which objects they touched."""
        if contacts.between is not None:  # fish against fish (the world's skin contact)
            self.fish_hit |= (contacts.between[0] + contacts.between[0].T) > 0.0
        if contacts.impulse and contacts.impulse[0].shape[2]:
            # contacts.touching[0] for the one lane, without stacking every animal's (only
            # the animals whose nodes were tested: the others' impulses are zero)
            tested = range(len(self.brains)) if contacts.near is None else contacts.near
            for i in tested:
                hit = (contacts.impulse[i][0] != 0.0).any(axis=(0, 2))
                self.touched.update((i, int(o)) for o in np.flatnonzero(hit))

    def period(self, world: World, period: Period) -> None:
        """Log the period's escapes, meals, collisions, catches and matings."""
        alive = np.array([b.alive for b in self.brains])
        self._escapes(period.t0, alive)
        t1 = world.time
        self._meals(world, t1, alive)
        self._collisions(world, t1)
        self._encounters(t1)
        self._start(world)

    def _escapes(self, t: float, alive: np.ndarray) -> None:
        """A fear episode (escape or school) that ends with the fish alive is an escape (an
        avoidance in between neither ends nor starts one)."""
        for i, b in enumerate(self.brains):
            x = b.thought
            afraid = alive[i] and x.intention in FEAR
            if self.in_fear[i] and not afraid and alive[i] and x.intention != "avoid":
                self.log.append((t, self.names[i], "escape", f"fear {x.fear:.2f}"))
            if x.intention != "avoid":
                self.in_fear[i] = afraid

    def _meals(self, world: World, t: float, alive: np.ndarray) -> None:
        """Each particle eaten this period: its eater is the live head nearest to it at the
        period's start."""
        new = world.food_eaten[0] & ~self.eaten
        if not new.any():
            return
        fp = world.food_positions[0]
        for q in np.flatnonzero(new):
            d = np.linalg.norm(self.nose - fp[q], axis=1)
            d[~alive] = np.inf
            i = int(np.argmin(d))
            self.brains[i].ate(t)
            self.log.append((t, self.names[i], "eat", f"food_{q}"))

    def _collisions(self, world: World, t: float) -> None:
        """A touch of another fish or an obstacle after ``APART`` s apart is a collision; a
        predator's touch of the prey it hunts, or of its body within ``APART`` s of the
        catch, is the catch (``_bites``), not a collision."""
        for i, j in zip(*np.nonzero(np.triu(self.fish_hit, 1)), strict=True):
            if t - self.fish_touch[i, j] > APART and not self._bites(i, j, t):
                self.log.append((t, self.names[i], "collision", self.names[j]))
            self.fish_touch[i, j] = t
        for i, o in sorted(self.touched):
            if o in self.obstacles and t - self.object_touch[i, o] > APART:
                self.log.append((t, self.names[i], "collision", world.objects[o].name))
            self.object_touch[i, o] = t

    def _bites(self, i: int, j: int, t: float) -> bool:
        """Whether the touch of fishes i and j at time t s is a predator's catch: one hunts
        the other (``FishBrain.prey``: the touch it swims for), or caught it within ``APART``
        s (its nose is at the body it caught)."""
        for a, b in ((i, j), (j, i)):
            if self.brains[a].prey == b and self.brains[b].alive:
                return True
            if t - self.caught[a, b] <= APART:
                return True
        return False

    def _encounters(self, t: float) -> None:
        """Catches (a hunting predator's nose within its catch radius of a prey's body) and
        matings (two willing fishes of a species, one of them courting, close together),
        from the bodies at the period's end."""
        com, pos, nose, brains = self.bodies.com, self.bodies.pos, self.bodies.nose, self.brains
        near = near_pairs(com, np.full(len(com), NEAR / 2))  # i < j, nearer than NEAR
        # the pairs surely too far apart to mate (their centres' distance, all at once, over
        # MATE_NEAR by more than its rounding): the others' distance is taken one by one
        gap = np.sqrt(((com[near[:, 0]] - com[near[:, 1]]) ** 2).sum(axis=1))
        far = set(map(tuple, near[gap > MATE_NEAR * (1.0 + 1e-9)].tolist()))
        both = np.concatenate([near, near[:, ::-1]])
        for i, j in both[np.lexsort((both[:, 1], both[:, 0]))].tolist():
            f, g = self.species[i], self.species[j]
            if not brains[i].alive or not brains[j].alive:
                continue
            if g.name in f.prey and brains[i].thought.intention == "hunt":
                if np.linalg.norm(pos[j] - nose[i], axis=1).min() < f.motor.catch_radius:
                    brains[j].alive = False
                    brains[i].ate(t, 3.0)
                    self.caught[i, j] = t
                    self.log.append((t, self.names[i], "catch", self.names[j]))
                    continue
            if j < i or f.name != g.name or (i, j) in far:
                continue
            if float(np.linalg.norm(com[i] - com[j])) >= MATE_NEAR:
                continue
            courting = "mate" in (brains[i].thought.intention, brains[j].thought.intention)
            if courting and brains[i].willing(t) and brains[j].willing(t):
                brains[i].mated(t)
                brains[j].mated(t)
                self.log.append((t, self.names[i], "mate", self.names[j]))
                self.log.append((t, self.names[j], "mate", self.names[i]))


def events_csv(events: list[Event]) -> str:
    """Return the events as CSV text: columns time, fish, event, detail."""
    import csv
    import io

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["time", "fish", "event", "detail"])
    for t, fish, event, detail in events:
        w.writerow([f"{t:.2f}", fish, event, detail])
    return buf.getvalue()
