"""The follow point of Fig. 10: its path, its turns, and the pursuit experiment's splines."""

from __future__ import annotations

import dataclasses
import importlib.util
import math

import numpy as np
import pytest

from zoetic.reproduce.provenance import REPO
from zoetic.san import World, load_creature
from zoetic.san.follow import FollowPath


def _pursuit_experiment():
    spec = importlib.util.spec_from_file_location(
        "san_pursuit", REPO / "experiments/san_pursuit.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_a_straight_path_never_turns():
    path = FollowPath(np.zeros(2), 0.4, 0.1, 5.0, seed=3, lateral=False)
    assert path.turns(0.3, 4.0) == (0.0, 0.0)


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_turns_on_a_circle_are_arc_over_radius_on_its_side(side):
    # a point going round a circle of radius r turns its heading by s / r over s metres of
    # arc: to the left (+z) on an anticlockwise circle, to the right on a clockwise one
    r, window = 0.5, 0.3
    path = FollowPath(np.zeros(2), 0.4, 0.1, 5.0, seed=0, lateral=False)
    a = np.linspace(0.0, math.pi, 2000)
    path.points = np.stack([r * np.sin(a), side * r * (1.0 - np.cos(a))], axis=1)
    seg = np.linalg.norm(np.diff(path.points, axis=0), axis=1)
    path.arc = np.concatenate([[0.0], np.cumsum(seg)])
    left, right = path.turns(window, 1.5)
    turned, other = (left, right) if side > 0 else (right, left)
    assert turned == pytest.approx(window / r, rel=0.02)
    assert other == pytest.approx(0.0, abs=1e-6)


class _Policy:
    """Zero commands, or full square waves of ``period`` s in phase on every actuator."""

    def __init__(self, n: int, period: float | None = None):
        self.n, self.period = n, period

    def reset(self):
        self.t = 0.0

    def step(self, sensors, dt):
        self.t += dt
        if self.period is None:
            return np.zeros(self.n)
        return np.full(self.n, 2.0 if (self.t / self.period) % 1.0 < 0.5 else -2.0)


def test_a_fish_world_chases_the_path_its_creature_defines():
    fish = load_creature("fish")
    r = World(fish, seed=5).run(_Policy(fish.n_actuators), seconds=4.0, record_every=40)
    start = r.follow[0] - np.array([fish.follow_lead, 0.0])  # the point starts lead ahead
    path = FollowPath.for_creature(fish, start, 5, 4.0, lateral=True)
    assert np.allclose(r.follow, [path.at(t) for t in r.times])
    assert np.linalg.norm(r.follow[-1] - r.follow[0]) > 0.9 * fish.follow_speed * 4.0


def test_pursuit_trains_on_a_sharp_turn_and_tests_on_unseen_splines():
    exp = _pursuit_experiment()
    fish = load_creature("fish")
    fish = dataclasses.replace(fish, follow_speed=exp.POINT_SPEED["fish"])
    turns = np.array([exp.sharpest_turns_deg(fish, s) for s in exp.TRAIN])
    assert turns.max() >= 45  # a turn the SAN must make hard
    unseen = set(exp.UNSEEN) | set(exp.SEEDS[1:])
    assert exp.SEEDS[0] in exp.TRAIN and not unseen & set(exp.TRAIN)


def test_the_fish_point_is_slower_than_a_straight_fish_swim_with_room_for_turns():
    # Fig. 10's point speed is not in the paper: a point as fast as the fish's straight
    # swim leaves it nothing for the turns, and the gap grows whatever it steers
    exp = _pursuit_experiment()
    fish = load_creature("fish")
    r = World(fish, follow=False).run(_Policy(fish.n_actuators, fish.expected_cycle), seconds=10.0)
    straight_m_s = r.distance / r.seconds
    assert 0.0 < exp.POINT_SPEED["fish"] <= 0.7 * straight_m_s, straight_m_s
