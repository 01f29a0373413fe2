"""Avoiding other fishes by where they will be: the side turned to is away from each
threat's closest approach (``routines.closest_lateral``), weighed over every threatening
fish, the side taken kept when they lie on both sides; a dead fish's body is avoided as a
fish is (``shoal.carcasses``)."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import cruise_from
from zoetic.behavior.aquarium import tank as tk
from zoetic.behavior.aquarium.brain import tank_brains
from zoetic.behavior.aquarium.routines import closest_lateral, fish_threats
from zoetic.behavior.aquarium.shoal import carcasses
from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live
from zoetic.behavior.mind import INTENTIONS, initial_mind

REGION = (1.0, 0.4, 2.0)  # reach, half width (m), anticipation (s)
SEEN = ~np.eye(3, dtype=bool)


def test_a_fish_crossing_ahead_from_the_right_is_passed_behind():
    # fish 0 heads +x at 0.3 m/s; fish 1, 1.2 m ahead of its nose and 0.3 m to its right,
    # swims left across its way as fast: now it is on the right, but nearest (at the 2 s
    # horizon) it will be 0.3 m to the left: fish 0 turns right, behind it (turning left,
    # away from where it is now, took fish 0 into its path, alongside it)
    f, left = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    nose = np.array([[0.0, 0.0, 0.0], [1.2, 0.0, 0.2]])
    com = np.array([[-0.5, 0.0, 0.0], [1.2, 0.0, -0.3]])
    fwd = np.stack([f, left])
    vel = 0.3 * fwd
    region = [np.full(2, x) for x in REGION]
    j, side, _ = fish_threats(nose, com, fwd, vel, SEEN[:2, :2], *region)
    assert j[0] == 1 and side[0] == -1
    lateral = closest_lateral(
        com[[1]] - nose[[0]], vel[[1]] - vel[[0]], left[None], np.array([2.0])
    )
    assert lateral[0] == pytest.approx(0.3)
    # a fish coming head on, 0.3 m to the right, stays there: turned away from, left
    com[1], nose[1], fwd[1] = [1.7, 0.0, -0.3], [1.2, 0.0, -0.3], -f
    j, side, _ = fish_threats(nose, com, fwd, 0.3 * fwd, SEEN[:2, :2], *region)
    assert j[0] == 1 and side[0] == 1


def test_a_fish_between_two_threats_keeps_its_side():
    # fish 0 heads +x at 0.3 m/s; fish 1 and 2 come head on 0.25 m to its left and to its
    # right, mirror images: each alone is turned away from
    f = np.array([1.0, 0.0, 0.0])
    nose = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.25], [1.0, 0.0, -0.25]])
    fwd = np.stack([f, -f, -f])
    com, vel = nose - 0.5 * fwd, 0.3 * fwd
    region = [np.full(3, x) for x in REGION]
    for other, away in ((1, -1), (2, 1)):
        seen = SEEN.copy()
        seen[0, 3 - other] = False
        _, side, _ = fish_threats(nose, com, fwd, vel, seen, *region)
        assert side[0] == away
    # both: the side the avoidance already turns to is kept (turning from the threat it
    # picked to the other's side, period after period, the fish swam on between them)
    for keep in (1, -1):
        _, side, _ = fish_threats(nose, com, fwd, vel, SEEN, *region, np.array([keep, 0, 0]))
        assert side[0] == keep


def test_the_brake_weighs_the_nearest_contact_of_all_the_threatening_fishes():
    # fish 0 heads +x at 0.3 m/s; fish 1 lies still across its way 1.2 m ahead (the most
    # points in the region: its threat); fish 2 comes head on at 1 m/s from 2.3 m ahead,
    # 0.2 m to the left: it will touch first, and the brake weighs its contact
    f, left = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    nose = np.array([[0.0, 0.0, 0.0], [1.2, 0.0, -0.5], [2.3, 0.0, 0.2]])
    fwd = np.stack([f, -left, -f])
    com, vel = nose - 0.5 * fwd, np.stack([0.3 * f, 0.0 * f, -f])
    region = [np.full(3, x) for x in REGION]
    seen = SEEN.copy()
    seen[0, 1] = False
    _, _, near2 = fish_threats(nose, com, fwd, vel, seen, *region)
    j, _, near = fish_threats(nose, com, fwd, vel, SEEN, *region)
    assert j[0] == 1 and near[0] == near2[0] < 1.2


def test_carcasses_are_the_dead_bodies_in_view_of_the_live_fishes():
    nose = np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [9.0, 0.0, 0.0]])
    alive = np.array([True, False, True])
    seen = carcasses(nose, nose + [0.5, 0.0, 0.0], alive, np.full(3, 6.0))
    # fish 0 has the body of fish 1 3.5 m away in range; fish 2 (5.5 m) too; the dead
    # fish sees nothing
    assert seen.tolist() == [[False, True, False], [False, False, False], [False, True, False]]
    assert not carcasses(nose, nose, np.ones(3, bool), np.full(3, 6.0)).any()


def test_a_fish_going_for_food_swims_around_a_dead_fish_in_its_way(monkeypatch):
    # a hungry minnow swims for a particle 5 m ahead; a dead minnow lies across its way
    # halfway: no fish perceives a body, and without avoiding it the eater swam into it
    from zoetic.physics.objects import Food
    from zoetic.physics.world import World

    def brains(*args):
        out = tank_brains(*args)
        out[1].alive = False
        return out

    monkeypatch.setattr(tk, "tank_brains", brains)
    cfg = TankConfig(
        fishes=2, predators=0, food=0, obstacles=0, seconds=10.0, seed=0, half_size=8.0
    )
    t = build_tank(cfg)
    world = World([*t.world.animals, *t.world.statics, Food((3.0, 0.0, 0.0), 0.25)], medium="water")
    tank = tk.Tank(cfg, world, t.fishes, t.kind, t.center, t.size, t.static_names)
    body = tank.fishes[0].body
    poses = [((-2.0, 0.0, 0.0), 0.0), ((0.6, 0.0, 0.0), np.pi / 2)]
    cruise_from(world, body, poses, tank.fishes[0].species.motor.cruise_speed)
    life = live(tank)
    assert (life.intentions[:, 0] == INTENTIONS.index("avoid")).any()
    assert not [e for e in life.events if e[2] == "collision"]


def test_an_eater_passes_behind_a_fish_crossing_its_way_from_the_right(monkeypatch):
    # a hungry minnow swims +x for a particle; a sated one (it wanders) crosses its way
    # from the right, 3 m ahead: the eater turns right, behind it, and is on to its food
    # after 1.9 s of avoiding; turning left, away from where the crosser was, it swam
    # alongside it and avoided it for 5.6 s of the 8
    from dataclasses import replace

    from zoetic.physics.objects import Food
    from zoetic.physics.world import World

    def brains(*args):
        out = tank_brains(*args)
        out[1].mind = initial_mind(0.0, out[1].species.mind.hunger_rate)
        for b in out:  # no courting: the two only meet
            b.constants = replace(b.constants, libido_rate=0.0)
        return out

    monkeypatch.setattr(tk, "tank_brains", brains)
    cfg = TankConfig(fishes=2, predators=0, food=0, obstacles=0, seconds=8.0, seed=0, half_size=8.0)
    t = build_tank(cfg)
    world = World([*t.world.animals, *t.world.statics, Food((4.0, 0.0, 0.0), 0.25)], medium="water")
    tank = tk.Tank(cfg, world, t.fishes, t.kind, t.center, t.size, t.static_names)
    poses = [((-2.0, 0.0, 0.0), 0.0), ((1.0, 0.0, -1.5), np.pi / 2)]
    cruise_from(world, tank.fishes[0].body, poses, tank.fishes[0].species.motor.cruise_speed)
    life = live(tank)
    avoiding = life.intentions[:, 0] == INTENTIONS.index("avoid")
    assert 0 < avoiding.sum() * cfg.control_period < 3.0
    # the eater's centre went right (-z) of its line before the crosser crossed it
    eater = life.positions[0].mean(axis=1)
    crossed = int(np.argmax(life.positions[1].mean(axis=1)[:, 2] > 0.0))
    assert crossed > 0 and eater[:crossed, 2].min() < -0.02
    assert not [e for e in life.events if e[2] == "collision"]


def _head_on(monkeypatch, avoiding: bool):
    """Two sated minnows (no food, no courting) cruising head on, 4 m apart, 0.1 m aside, for
    10 s; ``avoiding`` False: no fish is ever a threat (``fish_threats`` answers none)."""
    from dataclasses import replace

    from zoetic.behavior.aquarium import shoal

    def brains(*args):
        out = tank_brains(*args)
        for b in out:  # no courting: the two only meet
            b.constants = replace(b.constants, libido_rate=0.0)
        return out

    def blind(nose, *args):
        n = len(nose)
        return np.full(n, -1), np.zeros(n, int), np.full(n, np.inf)

    with monkeypatch.context() as m:
        m.setattr(tk, "tank_brains", brains)
        if not avoiding:
            m.setattr(shoal, "fish_threats", blind)
        cfg = TankConfig(
            fishes=2, predators=0, food=0, obstacles=0, seconds=10.0, seed=0, half_size=8.0
        )
        tank = build_tank(cfg)
        poses = [((-2.0, 0.0, 0.0), 0.0), ((2.0, 0.0, 0.1), np.pi)]
        cruise = tank.fishes[0].species.motor.cruise_speed
        cruise_from(tank.world, tank.fishes[0].body, poses, cruise)
        return live(tank)


def test_two_minnows_head_on_swerve_apart_and_swim_on(monkeypatch):
    # without avoiding each other the two run into each other
    blind = _head_on(monkeypatch, avoiding=False)
    assert [e for e in blind.events if e[2] == "collision"]
    life = _head_on(monkeypatch, avoiding=True)
    assert not [e for e in life.events if e[2] == "collision"]
    a, b = (p.mean(axis=1) for p in life.positions)
    gap = np.linalg.norm(a - b, axis=1)
    k = int(gap.argmin())
    # they swerve apart: each off its line (the centre more than 0.15 m aside, each to its
    # own side), and they pass with the centres more than 0.4 m apart across the way (blind,
    # 0.3 m: the bodies, 0.24 m wide, touch)
    moved = a[k, 2] - a[0, 2], b[k, 2] - b[0, 2]
    assert min(map(abs, moved)) > 0.15 and moved[0] * moved[1] < 0.0
    assert abs(a[k, 2] - b[k, 2]) > 0.4
    # a swerve, not a freeze: each swam on through the meeting (at cruise 2.5 m in 10 s)
    for c in (a, b):
        assert np.linalg.norm(np.diff(c, axis=0), axis=1).sum() > 1.5


def test_a_minnow_brakes_for_a_fish_two_seconds_of_travel_ahead():
    # a minnow cruising (0.25 m/s) with another fish alone threatening 1.75 s of travel
    # ahead: the half turn with no forward speed (the turn's bursts stop it), not swimming on
    from zoetic.behavior.aquarium.routines import Around, Me, avoid

    f, left = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    me = Me(np.array([-0.5, 0.0, 0.0]), np.zeros(3), f, 0.25 * f, 0.25, 0.43)
    near = 1.75 * 0.25  # m
    braked = avoid(me, Around(away=left, obstacle=near, fish_only=True))
    assert braked.speed == 0.0 and braked.turn == pytest.approx(np.pi)
    # 2.5 s of travel away: a quarter turn, swimming on at top speed
    far = avoid(me, Around(away=left, obstacle=2.5 * 0.25, fish_only=True))
    assert far.speed == pytest.approx(0.43) and far.turn == pytest.approx(np.pi / 2)
    # a rock as near (no fish): a quarter turn at top speed, as before (rocks stay put)
    rock = avoid(me, Around(away=left, obstacle=near))
    assert rock.speed == pytest.approx(0.43) and rock.turn == pytest.approx(np.pi / 2)
