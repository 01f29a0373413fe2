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
    # the search scores its random SANs on its seed's spline: never one the claim tests on
    assert not unseen & set(exp.SEARCH_SEED.values())


def test_the_fish_point_is_slower_than_a_straight_fish_swim_with_room_for_turns():
    # Fig. 10's point speed is not in the paper: a point as fast as the fish's straight
    # swim leaves it nothing for the turns, and the gap grows whatever it steers
    exp = _pursuit_experiment()
    fish = load_creature("fish")
    r = World(fish, follow=False).run(_Policy(fish.n_actuators, fish.expected_cycle), seconds=10.0)
    straight_m_s = r.distance / r.seconds
    assert 0.0 < exp.POINT_SPEED["fish"] <= 0.7 * straight_m_s, straight_m_s


def test_a_mirrored_spline_is_the_original_reflected_about_the_start_line():
    start = np.array([0.3, -0.2])
    path = FollowPath(start, 0.4, 0.1, 5.0, seed=9, lateral=True)
    mirror = FollowPath(start, 0.4, 0.1, 5.0, seed=9, lateral=True, mirror=True)
    assert np.allclose(mirror.points[:, 0], path.points[:, 0])
    assert np.allclose(mirror.points[:, 1] - start[1], -(path.points[:, 1] - start[1]))
    assert not np.allclose(mirror.points, path.points)  # the spline does weave


@pytest.mark.parametrize("seed", [8, 9])
def test_a_mirrored_spline_turns_left_where_the_original_turns_right(seed):
    path = FollowPath(np.zeros(2), 0.4, 0.1, 5.0, seed=seed, lateral=True)
    mirror = FollowPath(np.zeros(2), 0.4, 0.1, 5.0, seed=seed, lateral=True, mirror=True)
    left, right = path.turns(0.3, 3.0)
    assert left != pytest.approx(right, abs=0.05)  # a spline that turns one way harder
    assert mirror.turns(0.3, 3.0) == pytest.approx((right, left), abs=1e-9)


class _Mirrored:
    """A policy that sees each sensor as its mirror partner and drives each actuator as its
    mirror partner would: ``policy`` steering the mirrored fish."""

    def __init__(self, policy, sensor_swap, actuator_swap):
        self.policy, self.s, self.a = policy, sensor_swap, actuator_swap

    def reset(self):
        self.policy.reset()

    def step(self, sensors, dt):
        return -np.asarray(self.policy.step(sensors[self.s], dt))[self.a]


class _Steer:
    """Bends every joint towards the side whose eyes see the point, wiggling otherwise."""

    def __init__(self, left, right, n):
        self.left, self.right, self.n = left, right, n

    def reset(self):
        self.t = 0.0

    def step(self, sensors, dt):
        self.t += dt
        wave = 2.0 if (self.t / 0.5) % 1.0 < 0.5 else -2.0
        bias = float(sensors[self.left].any()) - float(sensors[self.right].any())
        return np.clip(np.full(self.n, wave * 0.5 + bias), -2.0, 2.0)


def _fish_mirror_swaps(fish):
    """Return the index maps that swap each of the fish's sensors with its mirror partner (same
    kind and target, range [lo, hi] -> [-hi, -lo]) and leave its actuators in place (a mirrored
    joint angle is the same joint's angle with its sign flipped)."""
    ranges = [(s.kind, s.target, round(s.lo, 9), round(s.hi, 9)) for s in fish.sensors]
    swap = [ranges.index((k, t, -hi, -lo)) for k, t, lo, hi in ranges]
    assert all(a.lo == pytest.approx(-a.hi) for a in fish.actuators)  # u -> -u mirrors
    return np.array(swap), np.arange(fish.n_actuators)


def test_a_symmetric_steerer_scores_the_same_on_a_spline_and_as_its_mirror_on_the_mirror():
    # the fish is left-right symmetric: a policy on a spline and the same policy with its
    # left and right swapped on the mirrored spline swim mirror-image paths, so they earn the
    # same pursuit metric; a steerer that turns one way harder does not
    fish = load_creature("fish")
    swap_s, swap_a = _fish_mirror_swaps(fish)
    left = [i for i, s in enumerate(fish.sensors) if s.kind == "eye" and s.lo > 0]
    right = [i for i, s in enumerate(fish.sensors) if s.kind == "eye" and s.hi < 0]
    steer = _Steer(left, right, fish.n_actuators)
    plain = World(fish, seed=9).run(steer, seconds=6.0, record_every=10)
    mirrored = World(fish, seed=9, mirror=True).run(
        _Mirrored(steer, swap_s, swap_a), seconds=6.0, record_every=10
    )
    assert plain.metric == pytest.approx(mirrored.metric, rel=1e-3, abs=1e-4)
    body, body_m = plain.poses[:, :, :2], mirrored.poses[:, :, :2]
    assert np.allclose(body[..., 0], body_m[..., 0], atol=1e-3)
    assert np.allclose(body[..., 1], -body_m[..., 1], atol=1e-3)
    unmirrored = World(fish, seed=9, mirror=True).run(steer, seconds=6.0)
    assert abs(unmirrored.metric - plain.metric) > 1e-3


def test_a_mirrored_mean_scores_each_spline_both_ways():
    from zoetic.san.tune import MeanEvaluator

    mean = MeanEvaluator([0, 9], mirror=True)
    assert [(p.seed, p.mirror) for p in mean.parts] == [
        (0, False),
        (0, True),
        (9, False),
        (9, True),
    ]
    assert [p.mirror for p in MeanEvaluator([0, 9]).parts] == [False, False]
