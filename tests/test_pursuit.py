"""Vision-guided pursuit: a short chase closes in on the prey with it foveated, and the
``zoetic pursue`` command writes its pictures and summary."""

from __future__ import annotations

import json

import numpy as np
import pytest

from zoetic.behavior.aquarium.locomotion import LearnedLocomotion, MotorLocomotion
from zoetic.behavior.wave_motor import WaveMotor
from zoetic.bodies import load_animal
from zoetic.cli import main
from zoetic.errors import ZoeticError
from zoetic.perception.pursuit import gazed_range, make_chase, run_chase, steer, summarize
from zoetic.physics.world import Animal, World


def test_the_turn_bias_contracts_one_side_more():
    chase = make_chase(0, distractors=0, rocks=False)
    body = chase.world.bodies[0]
    t = np.linspace(0, 1, 50)
    left = np.array([s == "left" for s in body.actuator_side])
    u = steer(body, t, 0.3)
    assert u[:, left].mean() > u[:, ~left].mean() + 0.2 and u.min() >= 0 and u.max() <= 1


def test_the_fins_tilt_from_level_with_pitch_and_raise_or_sink_the_shark():
    shark = load_animal("shark")
    fins = np.array([k == "fin" for k in shark.actuator_kind])
    t = np.arange(400) * shark.dt
    level = steer(shark, t, 0.0)[:, fins]
    assert np.allclose(steer(shark, t, 0.0, pitch=0.3)[:, fins], level + 0.3)
    world = World(
        [Animal(shark, (0.0, 0.0, 0.0), 0.0), Animal(shark, (0.0, 0.0, 3.0), 0.0)], medium="water"
    )
    t = np.arange(world.steps_for(1.0)) * world.dt
    world.step(1.0, [steer(shark, t, 0.0, pitch=p)[None] for p in (0.4, -0.4)])
    rise, sink = (world.positions(a)[0][:, 1].mean() for a in (0, 1))
    assert rise > 0.015 and sink < -0.015


def test_a_short_pursuit_keeps_the_prey_foveated_and_closes_in():
    chase = make_chase(0, distractors=0, rocks=False, start_distance=2.0)
    result = run_chase(chase, 4.0, fps=15.0)
    s = summarize(result, chase.predator.gaze.spec)
    assert s["foveated_fraction"] > 0.95
    assert s["final_distance_m"] < s["start_distance_m"] - 0.3
    # verged on the prey: the triangulated range is near the true one
    assert s["median_range_error"] is not None and s["median_range_error"] < 0.15


def test_the_fins_pitch_the_predator_toward_a_prey_above_it():
    gaps = []
    for gain in (2.0, 0.0):
        chase = make_chase(0, distractors=0, rocks=False, start_distance=2.0, prey_height=0.5)
        chase.predator.fin_gain = gain
        result = run_chase(chase, 2.5, fps=15.0)
        gaps.append(result.positions[1][-1, :, 1].mean() - result.positions[0][-1, 0, 1])
        assert np.mean([r.phi_p for r in chase.predator.log[1:]]) > 0  # phi_P points up
    assert gaps[0] < gaps[1] - 0.15 and gaps[0] < 0.3


def test_pursue_command_writes_its_outputs(tmp_path):
    out = tmp_path / "chase"
    rc = main(["pursue", "--seconds", "0.5", "--seed", "1", "--out", str(out), "--width", "96"])
    assert rc == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["frames"] == 15 and s["seed"] == 1 and isinstance(s["caught"], bool)
    for name in ("gaze.png", "frames.png", "video.mp4"):
        assert (out / name).stat().st_size > 1000


def test_a_chase_stops_at_the_catch_with_the_frames_the_eyes_saw():
    chase = make_chase(0, distractors=0, rocks=False, start_distance=1.6)
    result = run_chase(chase, 3.0, fps=15.0, catch_radius=0.75)
    assert result.caught and result.time_to_catch < 3.0
    # one record per control period, at its start: the frames the predator looked at
    assert len(result.times) == len(result.log) == len(result.positions[0])
    np.testing.assert_allclose([r.time for r in result.log], result.times)
    assert result.time_to_catch == pytest.approx(result.times[-1] + 1 / 15.0, abs=0.006)


def test_the_predator_steers_through_its_turn_motor_controller_with_theta_p(monkeypatch):
    asked = []
    real = WaveMotor.turns

    def spy(self, angle, seconds, amplitude):
        asked.extend(np.asarray(angle).tolist())
        return real(self, angle, seconds, amplitude)

    monkeypatch.setattr(WaveMotor, "turns", spy)
    chase = make_chase(0, distractors=0, rocks=False, start_distance=2.0)
    run_chase(chase, 1.0, fps=15.0)
    log = chase.predator.log
    assert len(asked) == len(log)
    # locked on: the turn asked is theta_P itself above the threshold, nothing below it
    for angle, rec in zip(asked, log, strict=True):
        if rec.locked.any():
            big = abs(rec.theta_p) >= chase.predator.threshold
            assert angle == pytest.approx(rec.theta_p if big else 0.0)
    assert any(abs(a) > 0 for a in asked)


@pytest.mark.parametrize("skills", ["built-in", "learned"])
def test_the_gaze_angles_go_to_the_motor_skills_the_aquarium_fishes_use(monkeypatch, skills):
    chase = make_chase(0, distractors=0, rocks=False, start_distance=2.0, skills=skills)
    loco = chase.predator.locomotion
    assert isinstance(loco, MotorLocomotion if skills == "built-in" else LearnedLocomotion)
    demands = []
    real = type(loco).activations

    def spy(self, demand, times):
        demands.append(demand)
        return real(self, demand, times)

    monkeypatch.setattr(type(loco), "activations", spy)
    run_chase(chase, 1.0, fps=15.0)
    pred = chase.predator
    assert len(demands) == len(pred.log)
    for d, rec in zip(demands, pred.log, strict=True):
        assert d.speed == pytest.approx(loco.top_speed)
        if not rec.locked.any():
            assert d.turn == pred.search_turn
            continue
        # left-turn-MC for theta_P above threshold, right-turn-MC below -threshold: |theta_P|
        big = abs(rec.theta_p) >= pred.threshold
        assert d.turn == pytest.approx(rec.theta_p if big else 0.0)
        up = abs(rec.phi_p) >= pred.threshold
        assert d.pitch == pytest.approx(pred.fin_gain * rec.phi_p if up else 0.0)
    assert any(abs(d.turn) > pred.threshold for d in demands)


def test_a_learned_predator_catches_its_prey():
    chase = make_chase(0, distractors=0, rocks=False, start_distance=1.6, skills="learned")
    result = run_chase(chase, 3.0, fps=15.0, catch_radius=0.75)
    assert result.caught


def test_unknown_skills_are_refused_by_name(tmp_path):
    with pytest.raises(ZoeticError, match="no learned repertoire"):
        make_chase(0, distractors=0, rocks=False, skills=str(tmp_path))
    out = tmp_path / "chase"
    assert main(["pursue", "--seconds", "0.2", "--skills", str(tmp_path), "--out", str(out)]) == 2


def test_the_gazed_range_is_where_the_gaze_ray_meets_the_surface():
    # a square wall of two triangles 2 m ahead of eyes 0.1 m apart, looking straight at it
    nodes = np.array([[2.0, -1, -1], [2.0, 1, -1], [2.0, 1, 1], [2.0, -1, 1]])
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    eyes = np.array([[0.0, 0.0, -0.05], [0.0, 0.0, 0.05]])
    # the left eye's ray meets the wall at (2, 0, -0.05): its range from the eyes' midpoint
    assert gazed_range(faces, nodes, eyes, np.array([1.0, 0, 0])) == pytest.approx(
        np.hypot(2, 0.05)
    )
    tilted = np.array([2.0, 0.0, 0.5]) / np.linalg.norm([2.0, 0.0, 0.5])
    assert gazed_range(faces, nodes, eyes, tilted) == pytest.approx(np.hypot(2.0, 0.45), abs=1e-9)
    # looking away: the node nearest the ray
    assert gazed_range(faces, nodes, eyes, np.array([-1.0, 0, 0])) == pytest.approx(
        np.linalg.norm(nodes[0] - eyes.mean(0))
    )
