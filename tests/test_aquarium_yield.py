"""Foraging that avoidance does not cost: of two fishes on a collision course the one going
for food keeps its course and the other yields (``shoal.right_of_way``), turning off the
eater's way to the side it lies on (``shoal.yield_sides``); a particle near and well off the
heading is turned to on the spot (``routines.go_to``)."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import cruise_from
from zoetic.behavior.aquarium import tank as tk
from zoetic.behavior.aquarium.brain import tank_brains
from zoetic.behavior.aquarium.shoal import right_of_way
from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live
from zoetic.behavior.mind import INTENTIONS, initial_mind

SECONDS, FOOD = 6.0, (3.0, 0.0, 0.0)


def test_of_two_fishes_threatening_each_other_the_one_going_for_food_swims_on():
    # fishes 0 and 1 threaten each other, 2 and 3 too, 4 threatens 5 (which does not see it)
    threat = np.array([1, 0, 3, 2, 5, -1])
    # 0 eats, 1 does not: 0 swims on; 2 and 3 both eat: the nearer its particle (3) swims on;
    # 4 eats but 5 does not see it coming: 4 must avoid it itself
    meals = [2.0, None, 1.5, 0.8, 1.0, None]
    assert right_of_way(threat, meals).tolist() == [True, False, False, True, False, False]
    # neither going for food: both avoid, as before
    assert not right_of_way(np.array([1, 0]), [None, None]).any()
    # two at the same distance from their particles: the first swims on
    assert right_of_way(np.array([1, 0]), [1.0, 1.0]).tolist() == [True, False]


def test_an_eater_keeps_no_right_of_way_over_a_fish_too_slow_to_yield():
    # 0 eats and 1 does not, 2 eats and 3 does not: each pair threatens each other; fish 1
    # swims on (able to yield), fish 3 is nearly still (braked, or turning on the spot)
    threat, meals = np.array([1, 0, 3, 2]), [1.0, None, 1.0, None]
    able = np.array([True, True, True, False])
    # the eater passing fish 3 would strike it where it stays: it avoids it as fish 3 does
    assert right_of_way(threat, meals, able).tolist() == [True, False, False, False]
    # whether the eater itself is slow does not matter: its right of way is the other's yield
    able = np.array([False, True, True, True])
    assert right_of_way(threat, meals, able).tolist() == [True, False, True, False]


def _head_on_tank(monkeypatch, seconds: float):
    """Two minnows head on, 0.1 m aside, cruising: fish 0 hungry and swimming for a particle
    4.5 m ahead, fish 1 sated (hunger 0: it wanders)."""
    from zoetic.physics.objects import Food
    from zoetic.physics.world import World

    def brains(*args):
        out = tank_brains(*args)
        out[1].mind = initial_mind(0.0, out[1].species.mind.hunger_rate)
        return out

    monkeypatch.setattr(tk, "tank_brains", brains)
    cfg = TankConfig(
        fishes=2, predators=0, food=0, obstacles=0, seconds=seconds, seed=0, half_size=8.0
    )
    t = build_tank(cfg)
    world = World([*t.world.animals, *t.world.statics, Food(FOOD, 0.25)], medium="water")
    tank = tk.Tank(cfg, world, t.fishes, t.kind, t.center, t.size, t.static_names)
    poses = [((-2.0, 0.0, 0.0), 0.0), ((1.0, 0.0, 0.1), np.pi)]
    cruise_from(world, tank.fishes[0].body, poses, tank.fishes[0].species.motor.cruise_speed)
    return tank


def test_a_fish_going_for_food_swims_on_and_the_fish_coming_head_on_yields(monkeypatch):
    # a hungry minnow swims for a particle 4.5 m ahead; a sated one (hunger 0: it wanders)
    # comes at it head on, 0.1 m aside: the sated one avoids (brakes, turns away) first
    life = live(_head_on_tank(monkeypatch, SECONDS))
    avoid, eat = INTENTIONS.index("avoid"), INTENTIONS.index("eat")
    yields = np.flatnonzero(life.intentions[:, 1] == avoid)
    assert len(yields)  # the sated fish saw the eater coming and yielded
    # the eater swims on to its food through the first half second of the yield (without a
    # right of way both braked for each other, the eater within a period of the other); the
    # yielding fish then brakes across its way, and the eater avoids it in turn
    first = int(yields[0])
    assert (life.intentions[: first + 5, 0] == eat).all()
    assert not [e for e in life.events if e[2] == "collision"]


def test_go_to_turns_on_the_spot_to_a_particle_near_and_well_off_the_heading():
    from zoetic.behavior.aquarium.routines import BRAKE_BEARING, NEAR, Around, Me, go_to

    f = np.array([1.0, 0.0, 0.0])
    me = Me(np.zeros(3), 0.5 * f, f, 0.25 * f, 0.25, 0.43, radius=0.1)
    rng = np.random.default_rng(0)

    def demand(x: float, z: float, **kw):
        return go_to(me, Around(target=np.array([x, 0.0, z]), **kw), rng)

    # 1.2 m to the left, nearly square to the heading: the half turn, no forward speed
    beside = demand(0.5, 1.2)
    assert beside.speed == 0.0 and beside.turn == pytest.approx(np.pi)
    assert demand(0.0, -1.0).turn == pytest.approx(-np.pi)  # behind on the right
    # nearly ahead, or well off the heading but farther than NEAR: swim and steer to it
    ahead = demand(1.5, 0.3)
    assert ahead.speed > 0.0 and 0.0 < ahead.turn < BRAKE_BEARING
    far = demand(0.5, NEAR + 0.5)
    assert far.speed == pytest.approx(0.43) and far.turn == pytest.approx(np.pi / 2)
    # a moving target (a mate, a prey) is steered to as before
    moving = demand(0.5, 1.2, target_velocity=np.zeros(3))
    assert moving.speed > 0.0 and moving.turn == pytest.approx(np.pi / 2)


def test_a_minnow_eats_a_particle_beside_it_instead_of_circling_it():
    # a minnow cruising along x with a particle 1.2 m to the left of its centre: steering to
    # it at the approach speed circled it 1.3-2 m away for 30 s; turned to on the spot, it
    # eats it within 10 s
    from zoetic.physics.objects import Food
    from zoetic.physics.world import Animal, World

    cfg = TankConfig(
        fishes=1, predators=0, food=0, obstacles=0, seconds=10.0, seed=1, half_size=12.0
    )
    t = build_tank(cfg)
    body = t.fishes[0].body
    com0 = body.mass @ body.rest_pos / body.total_mass
    fish = Animal(body, tuple(-com0), 0.0, (0.25, 0.0, 0.0))
    world = World([fish, *t.world.statics, Food((0.0, 0.0, 1.2), 0.25)], medium="water")
    tank = tk.Tank(cfg, world, t.fishes, t.kind, t.center, t.size, t.static_names)
    life = live(tank)
    assert [e[2] for e in life.events if e[2] == "eat"] == ["eat"]


def test_a_yielding_fish_turns_off_the_eaters_line_to_the_side_it_lies_on():
    from zoetic.behavior.aquarium.shoal import yield_sides

    # fish 0 eats along +x (its way to its particle) with the right of way over fish 1, which
    # comes head on 0.1 m to 0's left (+z): 1 turns to 0's left, its own right (-1), whatever
    # the side it had
    f = np.array([1.0, 0.0, 0.0])
    com = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.1]])
    fwd = np.stack([f, -f])
    threat, on = np.array([1, 0]), np.array([True, False])
    for had in (1, -1):
        assert yield_sides(threat, on, com, fwd, np.array([0, had])).tolist() == [0, -1]
    # on 0's right (-z): its own left; swimming the same way as the eater on its left: left
    com[1, 2] = -0.1
    assert yield_sides(threat, on, com, fwd, np.array([0, -1])).tolist() == [0, 1]
    com[1, 2], fwd[1] = 0.1, f
    assert yield_sides(threat, on, com, fwd, np.array([0, -1])).tolist() == [0, 1]
    # crossing the eater's line square: its side is kept; no right of way: nothing changes
    fwd[1] = [0.0, 0.0, 1.0]
    assert yield_sides(threat, on, com, fwd, np.array([0, -1])).tolist() == [0, -1]
    fwd[1] = -f
    assert yield_sides(threat, np.zeros(2, bool), com, fwd, np.array([1, 1])).tolist() == [1, 1]
    # the eater's way is to its particle, not its heading: turning to a particle ahead on its
    # left (its way along x + z), the yielder 0.1 m to the left of its heading lies right of
    # that way: it turns to the eater's right, its own left (+1)
    ways = np.stack([np.array([1.0, 0.0, 1.0]), -f])
    assert yield_sides(threat, on, com, ways, np.array([0, -1])).tolist() == [0, 1]


def test_the_fish_that_yields_head_on_moves_off_the_eaters_line(monkeypatch):
    # the right of way's head-on pair (0.1 m aside): the yielder turns off the eater's line
    # to the side it lies on (a side taken from the foreseen closest approach sways with each
    # tail beat and can stop it on the line), so it is clear of the eater within 7 s
    tank = _head_on_tank(monkeypatch, 7.0)
    cfg = tank.config
    life = live(tank)
    avoid = INTENTIONS.index("avoid")
    # the yielder ends on the side of the eater's line (z = 0) it started on, a body width
    # and more off it; the eater avoided it for under 2 s of the 7
    assert life.positions[1].mean(axis=1)[-1, 2] > 0.3
    assert (life.intentions[:, 0] == avoid).sum() * cfg.control_period < 2.0
    assert not [e for e in life.events if e[2] == "collision"]
