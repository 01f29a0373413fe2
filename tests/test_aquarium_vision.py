"""``--perception vision``: a predator of the tank perceives its prey through rendered images
(animat vision eyes, colour recognition, gaze), the other fishes stay on the oracle."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.behavior.aquarium import tank as tk
from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live, summarize
from zoetic.errors import SimulationError
from zoetic.physics.world import Animal, World


def _two_fish_tank(prey_at, seconds=1.0):
    """A predator at the origin heading +x and one prey at ``prey_at``, in an empty tank."""
    cfg = TankConfig(
        fishes=2,
        predators=1,
        food=0,
        obstacles=0,
        seconds=seconds,
        seed=2,
        half_size=10.0,
        perception="vision",
    )
    t = build_tank(cfg)
    animals = []
    for f, p in zip(t.fishes, [np.zeros(3), np.asarray(prey_at, float)], strict=True):
        com0 = f.body.mass @ f.body.rest_pos / f.body.total_mass
        animals.append(Animal(f.body, tuple(p - com0), 0.0, (0.2, 0.0, 0.0)))
    world = World([*animals, *t.world.statics], medium="water")
    return tk.Tank(cfg, world, t.fishes, t.kind, t.center, t.size, t.static_names)


def test_the_predators_eyes_find_the_prey_ahead_and_range_it():
    tank = _two_fish_tank((2.5, 0.0, 0.6))
    eyes = tk._eyes(tank).eyes[0]  # one seeing predator by default
    assert eyes.animal == 0
    sights = [eyes.see(tank.world, np.array([1])) for _ in range(4)]
    seen = [s for s in sights if s is not None]
    assert seen and all(s.fish == 1 for s in seen)
    true = np.linalg.norm(tank.world.positions(1)[0].mean(0) - tank.world.positions(0)[0][0])
    assert seen[-1].distance == pytest.approx(true, rel=0.35)
    # nothing of the prey's colour in view: nothing seen
    empty = _two_fish_tank((-6.0, 0.0, 0.0))  # straight behind, out of the eyes' field
    eyes = tk._eyes(empty).eyes[0]
    assert all(eyes.see(empty.world, np.array([1])) is None for _ in range(2))


def test_a_vision_tank_lives_and_the_predator_hunts_what_it_sees():
    tank = _two_fish_tank((2.5, 0.0, 0.6), seconds=1.5)
    life = live(tank)
    s = summarize(tank, life)
    assert s["perception"] == "vision" and s["seconds"] == pytest.approx(1.5)
    hunting = life.intentions[:, 0] == tk.INTENTIONS.index("hunt")
    assert hunting[-5:].all() and (life.targets[-5:, 0] == 1).all()  # the prey its eyes hold
    # the same prey straight behind, out of the eyes' field: hungry, but no target
    tank = _two_fish_tank((-6.0, 0.0, 0.0), seconds=0.5)
    assert (live(tank).targets[:, 0] == -1).all()


def test_vision_needs_a_predator_and_a_known_perception():
    with pytest.raises(SimulationError, match="predators"):
        build_tank(TankConfig(fishes=2, predators=0, perception="vision"))
    with pytest.raises(SimulationError, match="oracle, vision"):
        build_tank(TankConfig(perception="sonar"))
