"""A predator's touch of the prey it hunts is its catch, not a fish-fish collision: the
hunted prey is kept while an avoidance interrupts the hunt (``FishBrain.prey``), and the
tank's events count neither that touch nor the touch of the body just caught."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import numpy as np

from zoetic.behavior.aquarium.brain import tank_brains
from zoetic.behavior.aquarium.events import APART, Events
from zoetic.behavior.aquarium.tank import TankConfig, build_tank


def test_a_predator_keeps_its_prey_through_an_avoidance_and_drops_it_after_the_hunt():
    tank = build_tank(TankConfig(fishes=3, food=1, obstacles=0, seconds=1.0, seed=0))
    fishes = tank.fishes
    brains = tank_brains([f.species for f in fishes], [f.body for f in fishes], True, 0)
    shark = next(b for b in brains if b.species.predator)
    drives = (0.0, 0.0, 0.0)
    for intention, target, prey in (("hunt", 2, 2), ("avoid", None, 2), ("wander", None, None)):
        shark.mind = replace(shark.mind, intention=intention)
        shark.remember(drives, target)
        assert shark.prey == prey


def test_a_predators_touch_of_its_prey_or_of_the_body_it_just_caught_is_no_collision():
    events = Events.__new__(Events)  # only the brains and the catches are read
    events.brains = [SimpleNamespace(prey=1, alive=True)] + [
        SimpleNamespace(prey=None, alive=True) for _ in range(2)
    ]
    events.caught = np.full((3, 3), -np.inf)
    assert events._bites(0, 1, 5.0) and events._bites(1, 0, 5.0)  # the hunt's touch
    assert not events._bites(0, 2, 5.0) and not events._bites(1, 2, 5.0)  # any other
    events.brains[0].prey, events.brains[1].alive = None, False
    events.caught[0, 1] = 5.0  # caught at 5 s: its nose is at the body
    assert events._bites(0, 1, 5.0 + APART)
    # later the body is in the water as any other, and touching it is a collision
    assert not events._bites(0, 1, 5.0 + APART + 0.1)
