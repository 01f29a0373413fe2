"""FFT abstraction, mirroring and blended sequences (section 3 of the muscle paper)."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.behavior.handmade import wave_abstraction
from zoetic.bodies import load_animal
from zoetic.control import FrequencyDomainController, TimeDomainController, from_dict
from zoetic.control.abstract import AbstractController, SequenceController
from zoetic.errors import ControllerError, ZoeticError
from zoetic.learning.abstraction import abstract, mirror_abstract, parse_modes, spectrum
from zoetic.learning.abstraction import measure as measure_motion


@pytest.fixture(scope="module")
def shark():
    return load_animal("shark")


def _known(shark, nodes: int = 41, duration: float = 4.0):
    """A time-domain controller sampling known sinusoids exactly at its nodes."""
    a = len(shark.actuator_names)
    t = np.linspace(0.0, duration, nodes)
    offset = np.linspace(0.3, 0.6, a)
    amp1, amp2 = np.linspace(0.2, 0.3, a), np.full(a, 0.05)
    ph1 = np.linspace(-2.5, 2.5, a)
    vals = (
        offset[:, None]
        + amp1[:, None] * np.cos(2 * np.pi * 1.0 * t + ph1[:, None])
        + amp2[:, None] * np.cos(2 * np.pi * 1.5 * t + 0.7)
    )
    ctrl = TimeDomainController("shark", tuple(shark.actuator_names), duration, vals)
    return ctrl, offset, amp1, ph1, amp2


def test_fft_recovers_known_sinusoids(shark):
    ctrl, offset, amp1, ph1, amp2 = _known(shark)
    ab = abstract(ctrl, "auto", threshold=0.1)
    c = ab.controller
    assert ab.modes_per_actuator().tolist() == [2] * len(offset)
    np.testing.assert_allclose(c.offset, offset, atol=1e-9)
    np.testing.assert_allclose(c.freq[:, 0], 1.0)  # strongest first
    np.testing.assert_allclose(c.freq[:, 1], 1.5)
    np.testing.assert_allclose(c.amp[:, 0], amp1, atol=1e-9)
    np.testing.assert_allclose(c.amp[:, 1], amp2, atol=1e-9)
    np.testing.assert_allclose(c.phase[:, 0], ph1, atol=1e-9)
    np.testing.assert_allclose(c.phase[:, 1], 0.7, atol=1e-9)
    t = np.linspace(0, 4, 200)
    expected = (
        offset
        + amp1 * np.cos(2 * np.pi * t[:, None] + ph1)
        + 0.05 * np.cos(2 * np.pi * 1.5 * t[:, None] + 0.7)
    )
    np.testing.assert_allclose(c.raw(t), expected, atol=1e-9)


def test_threshold_and_k_strongest_drop_the_weak_mode(shark):
    ctrl, offset, amp1, ph1, _ = _known(shark)
    for ab in (abstract(ctrl, "auto", 0.3), abstract(ctrl, 1)):
        assert ab.modes_per_actuator().tolist() == [1] * len(offset)
        np.testing.assert_allclose(ab.controller.freq[:, 0], 1.0)
        np.testing.assert_allclose(ab.controller.amp[:, 0], amp1, atol=1e-9)
    assert parse_modes("auto") == "auto" and parse_modes("3") == 3
    for bad in ("0", "-1", "many"):
        with pytest.raises(ZoeticError, match="--modes"):
            parse_modes(bad)


def test_frequency_domain_amplitudes_are_thresholded_directly(shark):
    a = len(shark.actuator_names)
    omega = 2 * np.pi * np.array([0.0, 1.0, 2.0, 1.0])  # two bases at 1 Hz add as phasors
    phase = np.array([0.0, 0.0, 0.3, np.pi / 2])
    amps = np.tile([0.5, 0.3, 0.02, 0.4], (a, 1))
    ctrl = FrequencyDomainController("shark", tuple(shark.actuator_names), omega, phase, amps)
    spec = spectrum(ctrl)
    np.testing.assert_allclose(spec.offset, 0.5)
    np.testing.assert_allclose(spec.amp[:, 0], 0.5, atol=1e-12)  # |0.3 + 0.4i|
    ab = abstract(ctrl, "auto", 0.3)
    assert ab.modes_per_actuator().tolist() == [1] * a  # the 0.02 mode at 2 Hz is dropped
    t = np.linspace(0, 3, 50)
    np.testing.assert_allclose(
        ab.controller.raw(t)[:, 0],
        0.5 + 0.3 * np.cos(2 * np.pi * t) - 0.4 * np.sin(2 * np.pi * t),
        atol=1e-9,
    )


def test_abstracted_controller_is_periodic_and_round_trips(shark):
    ab = abstract(_known(shark)[0], 2).controller
    t = np.linspace(0, 4, 100)
    np.testing.assert_allclose(ab.raw(t + 8.0), ab.raw(t), atol=1e-9)  # any duration
    again = from_dict(ab.to_dict())
    assert isinstance(again, AbstractController)
    np.testing.assert_allclose(again.raw(t), ab.raw(t), atol=1e-5)


def test_mirroring_twice_is_identity_and_mirrored_turn_turns_the_other_way(shark):
    left = wave_abstraction(shark, 0.2, 0.3)
    right = mirror_abstract(left, shark.actuator_mirror)
    twice = mirror_abstract(right, shark.actuator_mirror)
    t = np.linspace(0, 3, 80)
    np.testing.assert_array_equal(twice.raw(t), left.raw(t))
    assert not np.allclose(right.raw(t), left.raw(t))
    a = measure_motion(shark, left, 3.0)
    b = measure_motion(shark, right, 3.0)
    assert a["heading_change"] > 0.05  # turns left (+z) ...
    assert b["heading_change"] == pytest.approx(-a["heading_change"], rel=1e-3)  # ... and right
    assert b["forward"] == pytest.approx(a["forward"], rel=1e-3)
    with pytest.raises(ControllerError, match="permutation"):
        mirror_abstract(left, [0, 0, 1, 2, 3, 4])


def _two(shark):
    a = shark.n_actuators
    one = AbstractController(
        "shark",
        tuple(shark.actuator_names),
        np.full(a, 0.2),
        np.ones((a, 1)),
        np.full((a, 1), 0.1),
        np.zeros((a, 1)),
        1.0,
    )
    two = AbstractController(
        "shark",
        tuple(shark.actuator_names),
        np.full(a, 0.8),
        np.full((a, 1), 2.0),
        np.full((a, 1), 0.1),
        np.ones((a, 1)),
        0.5,
    )
    return one, two


def test_blending_is_continuous_at_the_seams(shark):
    one, two = _two(shark)
    seq = SequenceController("shark", tuple(shark.actuator_names), ((one, 2.0), (two, 2.0)))
    assert seq.duration == pytest.approx(2.0 + 2.0 * 0.95)
    s = seq.starts()[1]
    assert s == pytest.approx(1.9)
    h = 1e-4
    t = np.arange(0.0, seq.duration, h)
    u = seq.raw(t)
    slope = 2 * np.pi * 2.0 * 0.1 + 0.6 / 0.1 + 1.0  # waves + the 0.6 fade over 0.1 s
    assert np.abs(np.diff(u, axis=0)).max() <= slope * h * 1.01
    w = seq.weights(t)
    np.testing.assert_allclose(w.sum(axis=1), 1.0)
    np.testing.assert_allclose(u[t < s - 1e-9], one.raw(t[t < s - 1e-9]), atol=1e-12)
    late = t > 2.0 + 1e-9
    np.testing.assert_allclose(u[late], two.raw(t[late] - s), atol=1e-12)
    hard = SequenceController("shark", tuple(shark.actuator_names), ((one, 2.0), (two, 2.0)), 0.0)
    assert np.abs(np.diff(hard.raw(t), axis=0)).max() > 0.4  # without overlap: a jump


def test_the_measure_a_task_is_about_follows_its_turn_target():
    """A turn (heading or body-axis heading with a target) is judged on its heading change; a
    straight gait that only keeps its heading (target 0) on its distance."""
    from zoetic.learning.abstraction import primary_measure
    from zoetic.tasks import load_task

    assert primary_measure(load_task("sharp-turn-left")) == "heading_change"
    assert primary_measure(load_task("crawl-straight")) == "forward"
    assert primary_measure(load_task("swim-straight")) == "forward"
