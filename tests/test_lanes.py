"""Animals that share a model step as lanes of one kernel call (``physics.lanes``): the same
world, and the same tank, bit for bit, as stepping each animal alone."""

from __future__ import annotations

import itertools

import numpy as np

from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live
from zoetic.bodies import load_animal
from zoetic.physics import stepping
from zoetic.physics.objects import Box
from zoetic.physics.world import Animal, World


def _one_at_a_time(monkeypatch) -> None:
    """Make every animal a group of its own: each steps alone, by its own stepper."""
    count = itertools.count()
    monkeypatch.setattr(stepping, "fingerprint", lambda model: next(count))


def _crowd() -> World:
    shark = load_animal("shark")
    # four sharks swimming at each other and at a rock: pairs, shape contacts and free lanes
    animals = [
        Animal(shark, (-1.2, 0.0, 0.0), 0.0, (0.8, 0.0, 0.0)),
        Animal(load_animal("shark"), (1.2, 0.0, 0.1), np.pi, (-0.8, 0.0, 0.0)),
        Animal(load_animal("shark"), (0.0, 0.0, 3.0), 0.0, (0.5, 0.0, 0.0)),
        Animal(load_animal("shark"), (-6.0, 0.0, -4.0), 0.3, (0.3, 0.0, 0.0)),
    ]
    return World([*animals, Box((2.6, 0.0, 3.0), (0.3, 1.0, 0.3))], medium="water")


def _run(world: World) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(3)
    between = []
    for _ in range(40):
        acts = [rng.uniform(0, 1, (1, b.n_actuators)) for b in world.bodies]
        c = world.step(0.05, acts)
        between.append(np.zeros((1, 4, 4)) if c.between is None else c.between)
    return world.node_positions(0), np.concatenate(between)


def test_a_world_steps_its_animals_as_lanes_as_one_at_a_time(monkeypatch):
    lanes = _crowd()
    assert [g.members for g in lanes._drive.groups] == [[0, 1, 2, 3]]
    pos, between = _run(lanes)
    _one_at_a_time(monkeypatch)
    alone = _crowd()
    assert all(len(g.members) == 1 for g in alone._drive.groups)
    pos_alone, between_alone = _run(alone)
    assert between_alone.any()  # the first two touched: the pairs' path ran
    assert np.array_equal(pos, pos_alone)
    assert np.array_equal(between, between_alone)


def test_a_crowded_tank_lives_as_lanes_as_one_fish_at_a_time(monkeypatch):
    touched = []
    pairs = stepping.ContactSlices.pairs

    def counted(self, rows, between):
        touched.extend(map(tuple, rows.tolist()))
        pairs(self, rows, between)

    monkeypatch.setattr(stepping.ContactSlices, "pairs", counted)
    cfg = TankConfig(fishes=14, predators=1, seconds=4.0, seed=4, half_size=7.0)
    lanes = live(build_tank(cfg))
    assert touched  # fishes came within reach of each other: the pairs' path ran
    _one_at_a_time(monkeypatch)
    alone = live(build_tank(cfg))
    for p, q in zip(lanes.positions, alone.positions, strict=True):
        assert np.array_equal(p, q)
    assert lanes.events == alone.events
    assert np.array_equal(lanes.eaten, alone.eaten)
    assert np.array_equal(lanes.intentions, alone.intentions)
    assert (lanes.deepest, lanes.deepest_fish) == (alone.deepest, alone.deepest_fish)
