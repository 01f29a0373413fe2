"""The aquarium's motor layer: the built-in swim / turn / pitch controllers calibrated on the
body's own steered wave (``behavior.motor.WaveMotor``), and depth keeping by the fins."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.behavior.aquarium.locomotion import Demand
from zoetic.behavior.aquarium.routines import Me, keep_depth
from zoetic.behavior.wave_motor import WAVE_SETTLE, WaveMotor
from zoetic.bodies import load_animal
from zoetic.learning.objective import heading_angles
from zoetic.physics import simulate


@pytest.fixture(scope="module")
def shark_motor():
    return WaveMotor.calibrate(load_animal("shark"), 3.0)


def _run(motor, length, **kw):
    body = motor.body
    steps = int(round(length / body.dt))
    act = motor.activations(np.arange(steps) * body.dt, **kw)
    tr = simulate(body, act[None], record_every=10)
    t = np.arange(tr.positions.shape[1]) * 10 * body.dt
    return t, tr.com(body)[0], heading_angles(body, tr.positions)[0]


def test_calibration_is_cached_and_faster_waves_swim_faster(shark_motor):
    assert WaveMotor.calibrate(shark_motor.body, 3.0) is shark_motor
    assert np.all(np.diff(shark_motor.speeds) > 0)
    assert np.all(shark_motor.rates[:, 0] == 0) and np.all(np.diff(shark_motor.rates, axis=1) >= 0)
    assert shark_motor.rates[-1, -1] > 0.1  # rad/s: the sharpest turn turns


def test_swim_at_a_speed_swims_that_speed(shark_motor):
    t, com, _ = _run(shark_motor, WAVE_SETTLE + 3.0, speed=0.3)
    sel = t >= WAVE_SETTLE
    path = np.linalg.norm(np.diff(com[sel][:, [0, 2]], axis=0), axis=1).sum()
    assert path / (t[sel][-1] - t[sel][0]) == pytest.approx(0.3, rel=0.2)


def test_turn_by_an_angle_turns_that_angle_to_the_side_asked(shark_motor):
    angle, seconds = np.radians(30.0), 4.0
    t, _, heading = _run(shark_motor, WAVE_SETTLE + seconds, speed=0.3, turn=angle, seconds=seconds)
    k0 = np.searchsorted(t, WAVE_SETTLE)
    assert heading[-1] - heading[k0] == pytest.approx(angle, rel=0.3)
    _, _, right = _run(shark_motor, WAVE_SETTLE + seconds, speed=0.3, turn=-angle, seconds=seconds)
    assert right[-1] - right[k0] == pytest.approx(-angle, rel=0.3)


def test_a_turn_too_fast_for_a_slow_wave_beats_harder(shark_motor):
    slow = shark_motor.swim(0.1)
    amp, bias = shark_motor.turn(np.radians(45.0), 1.0, slow)
    assert amp > slow and bias == pytest.approx(0.5, abs=0.11)
    amp, bias = shark_motor.turn(0.0, 1.0, slow)
    assert amp == pytest.approx(slow) and bias == 0.0


def test_fins_pitch_the_fish_up_and_down(shark_motor):
    t, up, _ = _run(shark_motor, 5.0, speed=0.43, pitch=0.3)
    _, down, _ = _run(shark_motor, 5.0, speed=0.43, pitch=-0.3)
    assert up[-1, 1] > 0.2 and down[-1, 1] < -0.2


def test_keep_depth_pitches_toward_the_layer_and_levels_off():
    def me(y, climb=0.0):
        fwd = np.array([np.cos(climb), np.sin(climb), 0.0])
        return Me(np.array([0.0, y, 0.0]), np.array([0.5, y, 0.0]), fwd, np.zeros(3), 0.2, 0.4)

    assert keep_depth(me(-1.0), Demand(0.2)).pitch > 0  # below the layer: nose up
    assert keep_depth(me(1.0), Demand(0.2)).pitch < 0
    assert keep_depth(me(0.0), Demand(0.2)).pitch == pytest.approx(0.0)
    assert keep_depth(me(0.0, 0.3), Demand(0.2)).pitch < 0  # climbing at the layer: level off
    assert keep_depth(me(0.0), Demand(0.2), 0.5).pitch > 0  # a target above
