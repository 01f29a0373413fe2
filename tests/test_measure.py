"""The motion every run record carries (control.measure): the sensors' speed, depth, heading,
pitch and roll, read from recorded positions, for one animal or a batch of them."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.bodies import load_animal
from zoetic.control.measure import measure_record, motion_scalars
from zoetic.control.sensors import SENSORS, Senses
from zoetic.physics import get_medium
from zoetic.record import Animal, Record


@pytest.fixture(scope="module")
def shark():
    return load_animal("shark")


def _turned(body, yaw: float, pitch: float, shift=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Return the rest pose pitched nose up by ``pitch`` then turned left by ``yaw`` (rad)
    about the centre of mass, moved by ``shift`` m: (N, 3)."""
    rest = np.asarray(body.rest_pos, float)
    com = body.mass @ rest / body.total_mass
    cp, sp, cy, sy = np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    rz = np.array([[cp, -sp, 0], [sp, cp, 0], [0, 0, 1]])  # x toward y: nose up
    ry = np.array([[cy, 0, -sy], [0, 1, 0], [sy, 0, cy]])  # x toward z: a left turn
    return (rest - com) @ (ry @ rz).T + com + np.asarray(shift)


def test_a_pose_turned_and_pitched_reads_its_angles_and_an_upright_one_no_roll(shark):
    f = np.asarray(shark.forward, float)
    assert abs(f[1]) < 1e-9 and abs(f[2]) < 1e-9  # the zoo shark faces +x at rest
    times = np.array([0.0, 0.5, 1.0])
    pos = np.stack(
        [
            _turned(shark, 0.0, 0.0),
            _turned(shark, 0.4, 0.0, (0.5, 0, 0)),
            _turned(shark, 0.4, 0.2, (1.0, -0.3, 0)),
        ]
    )[None]
    m = motion_scalars(shark, pos, times, get_medium("sea"))
    np.testing.assert_allclose(m["heading"][0], np.degrees([0.0, 0.4, 0.4]), atol=1e-6)
    np.testing.assert_allclose(m["pitch"][0], np.degrees([0.0, 0.0, 0.2]), atol=1e-6)
    np.testing.assert_allclose(m["roll"][0], 0.0, atol=1e-6)
    com0 = shark.mass @ shark.rest_pos / shark.total_mass
    np.testing.assert_allclose(m["depth"][0], -com0[1] + np.array([0, 0, 0.3]), atol=1e-9)
    # in a medium without a surface: the height of the centre of mass instead
    m = motion_scalars(shark, pos, times, get_medium("water"))
    assert "depth" not in m
    np.testing.assert_allclose(m["height"][0], com0[1] - np.array([0, 0, 0.3]), atol=1e-9)


def test_speed_is_the_centre_of_mass_velocity_along_the_forward_axis(shark):
    times = np.linspace(0.0, 1.0, 11)
    pos = np.stack([_turned(shark, 0.3, 0.0, (0.8 * t, 0.0, 0.0)) for t in times])
    m = motion_scalars(shark, pos[None], times, get_medium("water"))
    np.testing.assert_allclose(m["speed"][0], 0.8 * np.cos(0.3), atol=1e-9)


def test_a_batch_reads_as_each_animal_alone_and_agrees_with_the_sensors(shark):
    rng = np.random.default_rng(1)
    times = np.linspace(0.0, 0.4, 5)
    base = np.stack([_turned(shark, 0.1 * k, 0.05 * k, (0.2 * k, 0, 0)) for k in range(5)])
    pos = base[None] + rng.normal(0, 0.01, (3,) + base.shape)
    sea = get_medium("sea")
    both = motion_scalars(shark, pos, times, sea)
    for a in range(3):
        alone = motion_scalars(shark, pos[a : a + 1], times, sea)
        for q in alone:
            np.testing.assert_allclose(both[q][a], alone[q][0], atol=1e-9)
    vel = np.gradient(pos[0], times, axis=0)
    s = Senses(shark, pos[0], vel, sea, 0.0, np.zeros((5, 0), bool))
    np.testing.assert_allclose(both["roll"][0], np.degrees(SENSORS["roll"](s)), atol=1e-9)
    np.testing.assert_allclose(both["depth"][0], SENSORS["depth"](s), atol=1e-9)
    np.testing.assert_allclose(both["speed"][0], SENSORS["forward_speed"](s), atol=1e-9)


def test_a_record_with_control_periods_gets_the_motion_at_its_period_times(shark):
    times = np.linspace(0.0, 1.0, 11)
    pos = np.stack([_turned(shark, 0.0, 0.0, (0.0, -0.5 * t, 0.0)) for t in times])
    fish = Animal(
        "s",
        "shark",
        np.asarray(shark.faces, np.int32),
        pos.astype(np.float32),
        np.asarray(shark.mass, np.float32),
    )
    periods = np.array([0.0, 0.25, 0.5])
    rec = Record(
        "aquarium",
        "t",
        "sea",
        times,
        (fish,),
        period_times=periods,
        scalars={"s": {"hunger": np.zeros(3, np.float32)}},
    )
    got = measure_record(rec, [shark])
    assert set(got.scalars["s"]) == {"hunger", "speed", "depth", "heading", "pitch", "roll"}
    d0 = got.scalars["s"]["depth"][0]
    np.testing.assert_allclose(got.scalars["s"]["depth"] - d0, 0.5 * periods, atol=1e-6)
    assert got.units["depth"] == "m" and got.units["roll"] == "deg"
    # without periods the recorded instants become the periods
    bare = measure_record(Record("simulate", "t", "sea", times, (fish,)), [shark])
    np.testing.assert_array_equal(bare.period_times, times)
    assert len(bare.scalars["s"]["pitch"]) == len(times)


def test_muscle_work_is_tension_times_the_rest_length_moved(shark):
    """Held still at its rest pose, each muscle's tension is k (l - r); moving u from 0 to 1
    in one interval moves r by (contracted - relaxed) and costs |k (l - r_mid) dr| (trapezoid
    tension) summed over muscles; a constant activation spends nothing."""
    from zoetic.control.measure import muscle_work

    pos = np.repeat(np.asarray(shark.rest_pos, float)[None, None], 2, axis=1)  # (1, 2, N, 3)
    u = np.zeros((1, 2, shark.n_actuators))
    u[:, 1] = 1.0
    m = np.flatnonzero(np.asarray(shark.spring_actuator) >= 0)
    a, b = shark.spring_a[m], shark.spring_b[m]
    length = np.linalg.norm(shark.rest_pos[a] - shark.rest_pos[b], axis=-1)
    dr = shark.contracted[m] - shark.relaxed[m]
    mid = shark.stiffness[m] * (length - shark.relaxed[m] - 0.5 * dr)
    assert muscle_work(shark, pos, u)[0] == pytest.approx(np.abs(mid * dr).sum())
    assert muscle_work(shark, pos, np.full_like(u, 0.4))[0] == 0.0


def test_a_stronger_stroke_spends_more_muscle_work(shark):
    """The same wave at half and at full amplitude about the half-contracted pose: the full
    stroke moves every rest length twice as far against larger tensions."""
    from zoetic.control import wave_controller
    from zoetic.control.measure import muscle_work
    from zoetic.physics.simulate import simulate

    t = np.arange(400) * shark.dt
    u = wave_controller(shark).sample(t)
    spent = []
    for scale in (0.5, 1.0):
        acts = np.clip(0.5 + scale * (u - 0.5), 0.0, 1.0)[None]
        traj = simulate(shark, acts, record_every=1)
        spent.append(muscle_work(shark, traj.positions[:, 1:], acts)[0])
    assert 0.0 < 1.5 * spent[0] < spent[1]
