"""The motor layer's righting reflex: the pectoral fins pitched differentially against the
fish's roll (``behavior.motor.righting``), fed the roll the tank measures
(``tasks.terms.roll_angle``)."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.behavior.aquarium.bodystate import fish_rolls, heading_weights, roll_pairs
from zoetic.behavior.aquarium.locomotion import (
    Demand,
    LearnedLocomotion,
    MotorLocomotion,
    learned_motor,
)
from zoetic.behavior.aquarium.species import SKILLS_DIR
from zoetic.behavior.motor import RIGHTING_MAX, fin_activation, righting
from zoetic.bodies import load_animal
from zoetic.physics import simulate
from zoetic.physics.simulate import State
from zoetic.tasks.terms import BodyFrame, roll_angle

PERIOD = 20  # steps of a control period (0.1 s on the shark)


def rolled(body, degrees: float) -> np.ndarray:
    """The body's rest pose rolled ``degrees`` about its long (x) axis, left side down."""
    a = np.radians(degrees)
    p = body.rest_pos.copy()
    c = body.mass @ p / body.total_mass
    y, z = p[:, 1] - c[1], p[:, 2] - c[2]
    p[:, 1] = c[1] + y * np.cos(a) - z * np.sin(a)
    p[:, 2] = c[2] + y * np.sin(a) + z * np.cos(a)
    return p


def test_roll_angle_reads_the_roll_and_with_the_heading_tells_upside_down():
    body = load_animal("shark")
    frame = BodyFrame.of(body)
    fwd = np.asarray(body.forward, float)
    for deg in (0.0, 45.0, -30.0, 100.0, -150.0):
        p = rolled(body, deg)
        assert np.degrees(roll_angle(np, p, frame.left, frame.right, fwd)) == pytest.approx(
            deg, abs=1e-6
        )
        folded = np.degrees(roll_angle(np, p, frame.left, frame.right))
        assert folded == pytest.approx(np.sign(deg) * min(abs(deg), 180 - abs(deg)), abs=1e-6)
    # the tank's per-fish rolls: the same definition, the heading from the nodes
    pos = [rolled(body, 60.0), rolled(body, -170.0)]
    fwd2 = np.array([heading_weights(body) @ p for p in pos])
    pairs = roll_pairs([body, body], np.array([0, body.n_nodes]))
    assert np.degrees(fish_rolls(np.concatenate(pos), fwd2, pairs)) == pytest.approx(
        [60.0, -170.0], abs=0.5
    )


def test_the_fins_lean_against_the_roll_within_their_range():
    body = load_animal("shark")
    left, right = body.fin_actuator  # fin_left, fin_right, each -0.5 to 0.5 rad
    level = fin_activation(body, 0.0)
    assert level == {left: 0.5, right: 0.5}
    lean = fin_activation(body, 0.1, lean=0.2)
    assert lean[left] == pytest.approx(0.8) and lean[right] == pytest.approx(0.4)
    assert fin_activation(body, 0.4, lean=0.3) == {left: 1.0, right: pytest.approx(0.6)}
    assert righting(0.0, 0.0) == 0.0
    assert righting(0.05) > 0.0 > righting(-0.05)  # left side down: the left fin up
    assert righting(0.05, -1.0) < righting(0.05)  # already righting itself: less
    assert righting(3.0) == RIGHTING_MAX and righting(-3.0) == -RIGHTING_MAX


def _rights(loco, body, degrees: float, seconds: float, speed: float = 0.3) -> np.ndarray:
    """Swim the fish ``seconds`` from rest rolled ``degrees``, the demand's roll and rate
    measured each control period as the tank does; return its roll (deg) each period."""
    frame = BodyFrame.of(body)
    state = State(rolled(body, degrees)[None], np.zeros((1, body.n_nodes, 3)))
    w, last, out = heading_weights(body), None, []
    for k in range(int(round(seconds / (PERIOD * body.dt)))):
        times = (k * PERIOD + np.arange(PERIOD)) * body.dt
        p = state.positions[0]
        roll = float(roll_angle(np, p, frame.left, frame.right, w @ p))
        rate = 0.0 if last is None else (roll - last) / (PERIOD * body.dt)
        last = roll
        out.append(np.degrees(roll))
        act = loco.activations(Demand(speed, roll=roll, roll_rate=rate), times)
        state = simulate(body, act[None], state=state, record_every=PERIOD).final
    return np.array(out)


def test_the_reflex_rights_a_fish_swimming_on_the_built_in_wave():
    body = load_animal("shark")
    on = _rights(MotorLocomotion(body, 3.0), body, 45.0, 5.0)
    off = _rights(MotorLocomotion(body, 3.0, righting=False), body, 45.0, 5.0)
    assert off.min() > 40.0  # nothing else rights it: the water has no roll moment
    assert abs(on[-1]) < 10.0 and np.abs(on[-10:]).max() < 15.0
    on_right = _rights(MotorLocomotion(body, 3.0), body, -45.0, 5.0)
    assert abs(on_right[-1]) < 10.0


def test_the_reflex_rights_a_fish_swimming_on_learned_skills():
    body = load_animal("shark")
    motor = learned_motor(body, SKILLS_DIR / "shark")
    on = _rights(LearnedLocomotion(body, motor), body, 45.0, 4.0)
    off = _rights(LearnedLocomotion(body, motor, righting=False), body, 45.0, 4.0)
    assert abs(off[-1]) > 30.0
    assert abs(on[-1]) < 15.0 and abs(on[-1]) < 0.3 * abs(off[-1])


def test_the_right_steer_beats_in_phase_with_the_swim_so_switching_sides_keeps_upright():
    body = load_animal("shark")
    motor = learned_motor(body, SKILLS_DIR / "shark")
    gait = motor.bases[1]  # go-straight: its mirror image is itself half a stroke later
    assert motor.steer_lag == pytest.approx(gait.period / 2, abs=body.dt / 2)
    t = np.arange(40) * body.dt
    np.testing.assert_allclose(
        body.mirror_actuators(gait.raw(t)), gait.raw(t + motor.steer_lag), atol=1e-6
    )
    # steering right is steering left mirrored: the same swim, the other side
    a, w = motor.swim(0.4), 0.75
    right = motor.steer_signal(t, a, w, 1, 0.0)
    left = motor.steer_signal(t + motor.steer_lag, a, w, 0, 0.0)
    np.testing.assert_allclose(right, body.mirror_actuators(left), atol=1e-6)
    # a fish asked to turn left and right by turns every 0.3 s stays upright without the
    # reflex (played at the clock's time, the right steer rolled it over)
    frame, hw = BodyFrame.of(body), heading_weights(body)
    loco = LearnedLocomotion(body, motor, righting=False)
    state = State(body.rest_pos[None].copy(), np.zeros((1, body.n_nodes, 3)))
    rolls = []
    for k in range(60):
        times = (k * PERIOD + np.arange(PERIOD)) * body.dt
        side = 1.0 if int(times[0] / 0.3) % 2 == 0 else -1.0
        act = loco.activations(Demand(0.4, turn=0.3 * side), times)
        state = simulate(body, act[None], state=state, record_every=PERIOD).final
        p = state.positions[0]
        rolls.append(float(roll_angle(np, p, frame.left, frame.right, hw @ p)))
    assert np.degrees(np.abs(rolls)).max() < 10.0
