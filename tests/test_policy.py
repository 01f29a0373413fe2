"""Policies and sensors: open-loop controllers as policies, closed-loop rollouts, readings."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.bodies import load_animal
from zoetic.control import wave_controller
from zoetic.control.policy import OpenLoopPolicy, Period, Policy, TablePolicy, as_policy
from zoetic.control.rollout import rollout
from zoetic.control.sensors import observe, orientation
from zoetic.errors import ControllerError
from zoetic.physics import simulate
from zoetic.physics.objects import Ball
from zoetic.physics.world import Animal, World


def test_an_open_loop_controller_as_a_policy_follows_simulate():
    body = load_animal("shark")
    ctrl = wave_controller(body)
    steps = 301
    traj = simulate(body, ctrl.table(steps, body.dt), record_every=4)
    ro = rollout(World([body]), OpenLoopPolicy(ctrl), steps * body.dt, record_every=4)
    got = ro.trajectory(0)
    np.testing.assert_allclose(got.times, traj.times)
    np.testing.assert_allclose(got.positions, traj.positions, atol=1e-5)
    np.testing.assert_allclose(got.final.positions, traj.final.positions, atol=1e-5)
    # a table policy plays the same rows
    table = TablePolicy(ctrl.table(steps, body.dt))
    again = rollout(World([body]), table, steps * body.dt, record_every=4).trajectory(0)
    np.testing.assert_allclose(again.positions, traj.positions, atol=1e-5)


class Recorder:
    """A closed-loop policy that holds rest and writes down what it saw."""

    sensors = ("heading", "contacts", "target_distance")

    def __init__(self, n_act: int) -> None:
        self.n_act = n_act
        self.seen: list[tuple[Period, dict]] = []
        self.seed = "unset"

    def reset(self, seed=None) -> None:
        self.seed = seed

    def act(self, observation, period):
        self.seen.append((period, dict(observation)))
        return np.zeros((len(observation["time"]), self.n_act))


def test_a_policy_sees_every_control_period_and_its_contacts():
    body = load_animal("shark").with_(node_damping=np.zeros(23))
    nose = body.rest_pos[body.head] + body.start_offset
    ball = Ball(radius=0.1, mass=0.3, position=tuple(nose + 0.2 * body.forward))
    world = World([Animal(body, velocity=tuple(0.8 * body.forward)), ball], medium="vacuum")
    pol = Recorder(body.n_actuators)
    assert isinstance(pol, Policy)
    ro = rollout(world, pol, 0.5, control_period=0.1, target="ball", seed=7)
    assert pol.seed == 7
    assert [p.start for p, _ in pol.seen] == [0, 20, 40, 60, 80]
    assert all(p.steps == 20 for p, _ in pol.seen)
    first, later = pol.seen[0][1], pol.seen[-1][1]
    assert not first["contacts"].any()
    assert any(o["contacts"][0, 0] for _, o in pol.seen[1:])
    assert ro.contacts.sum() > 0
    assert later["target_distance"][0] > first["target_distance"][0]  # the ball flew off
    assert ro.ball_positions.shape == (1, 6, 1, 3)


def test_sensors_read_heading_pitch_roll_depth_and_bearing():
    body = load_animal("dolphin")
    world = World([Animal(body, offset=(0.0, -2.0, 0.0), yaw=0.7)], batch=2)
    obs = observe(world, target=(0.0, -2.0, 5.0))
    assert obs["heading"] == pytest.approx([0.7, 0.7], abs=1e-6)
    assert obs["pitch"] == pytest.approx([0.0, 0.0], abs=1e-6)
    assert obs["roll"] == pytest.approx([0.0, 0.0], abs=1e-6)
    com = obs["com"][0]
    assert obs["depth"][0] == pytest.approx(world.medium.water_level - com[1])
    bearing = np.arctan2(5.0 - com[2], -com[0]) - 0.7
    assert obs["target_bearing"][0] == pytest.approx(bearing, abs=1e-6)
    assert obs["target_distance"][0] == pytest.approx(np.linalg.norm([0, -2, 5] - com))
    # orientation recovers a known rotation: roll by 0.3 about the forward axis (x)
    c, s = np.cos(0.3), np.sin(0.3)
    rx = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    turned = body.rest_pos @ rx.T
    np.testing.assert_allclose(orientation(body, turned[None])[0], rx, atol=1e-9)
    q = np.linalg.qr(np.random.default_rng(2).normal(size=(20, 3, 3)))[0]
    q *= np.sign(np.linalg.det(q))[:, None, None]  # proper rotations only
    moved = np.einsum("bij,nj->bni", q, body.rest_pos) + [1.0, -2.0, 0.5]
    np.testing.assert_allclose(orientation(body, moved), q, atol=1e-9)
    with pytest.raises(ControllerError, match="unknown sensor"):
        observe(world, sensors=("smell",))
    with pytest.raises(ControllerError, match="no target"):
        observe(world, sensors=("target_bearing",))


def test_as_policy_and_bad_policies():
    body = load_animal("snake")
    ctrl = wave_controller(body)
    assert isinstance(as_policy(ctrl), OpenLoopPolicy)
    assert isinstance(as_policy(np.zeros((1, 3, body.n_actuators))), TablePolicy)
    with pytest.raises(ControllerError, match="not a policy"):
        as_policy("wave")
    world = World([body, body])
    with pytest.raises(ControllerError, match="each of the world's 2 animals"):
        rollout(world, ctrl, 0.1)
    short = OpenLoopPolicy([ctrl, ctrl, ctrl])
    with pytest.raises(ControllerError, match="3 controllers for 1 lanes"):
        rollout(World([body]), short, 0.1)
