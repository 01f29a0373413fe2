"""Parameterised motor controllers: swim(speed), turn(angle), pitch(angle) from a repertoire."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.behavior.handmade import handmade_repertoire
from zoetic.behavior.motor import MotorControllers, blend, interp, interps, motor_repertoire
from zoetic.bodies import load_animal
from zoetic.learning.objective import heading_angles
from zoetic.physics import simulate


@pytest.fixture(scope="module")
def motor():
    body = load_animal("shark")
    return MotorControllers.calibrate(body, handmade_repertoire(body))


def test_a_blend_plays_the_weighted_sum_of_its_entries(motor):
    c = motor.rep.controllers
    t = np.linspace(0.0, 2.0, 41)
    mix = blend(c["go-straight"], c["sharp-turn-left"], 0.3)
    want = 0.7 * c["go-straight"].raw(t) + 0.3 * c["sharp-turn-left"].raw(t)
    np.testing.assert_allclose(mix.raw(t), want, atol=1e-12)


def test_swim_turn_and_pitch_do_what_they_are_asked(motor):
    body = motor.body
    assert motor.speeds[0] < 1e-3 < motor.speeds[-1]  # do-nothing rests, go-straight swims
    top = float(motor.speeds.max())
    slow, fast = motor.swim(0.3 * top), motor.swim(top)
    left, t_left = motor.turn(60.0)
    right, _ = motor.turn(-60.0)
    up, down = motor.pitch(0.4), motor.pitch(-0.4)
    steps = int(3.0 / body.dt)
    ctrls = [slow, fast, left, right, up, down]
    tr = simulate(body, np.stack([k.table(steps, body.dt) for k in ctrls]), record_every=10)
    com = tr.com(body)
    dist = np.linalg.norm(np.diff(com[..., [0, 2]], axis=1), axis=-1).sum(axis=1) / 3.0
    assert dist[0] < dist[1]  # slower when asked
    assert 0.15 * top < dist[0] < 0.6 * top  # and about the speed asked (within a factor 2)
    turned = np.degrees(heading_angles(body, tr.positions)[:, -1])
    assert turned[2] > 20 and turned[3] < -20 and t_left > 0  # left is left, right is right
    rise = com[:, -1, 1] - com[:, 0, 1]
    assert rise[4] > 0.2 and rise[5] < -0.2  # nose up rises, nose down sinks


def test_motor_entries_join_a_repertoire(motor):
    rep = motor_repertoire(motor, speeds=[0.2], turns=[45, -45], pitches=[0.3])
    assert {"swim-0.2", "turn-45", "turn--45", "pitch-0.3", "go-straight"} <= set(rep.names)
    assert rep.info["turn-45"]["source"] == "motor"


def test_interps_one_table_and_a_table_per_row_give_interp_of_each():
    """``interps`` over one table (P,) and over that table repeated per row (D, P) are each
    value's ``interp``, ends and repeated points included (the one table is indexed directly,
    not copied per row)."""
    xp = np.array([0.0, 0.5, 0.5, 1.0, 2.0])
    fp = np.array([1.0, 3.0, 4.0, 2.0, 5.0])
    x = np.array([-1.0, 0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0])
    want = [interp(v, xp.tolist(), fp.tolist()) for v in x.tolist()]
    assert interps(x, xp, fp).tolist() == want
    assert interps(x, np.tile(xp, (len(x), 1)), fp).tolist() == want
