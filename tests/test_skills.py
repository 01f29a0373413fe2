"""Learning with defaults: periodic gaits that go the right way, keep going, and fit any body."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.bench.skills import skill_figures
from zoetic.bodies import ZOO_DIR, load_animal
from zoetic.learning.objective import heading_angles
from zoetic.learning.run import LearnConfig, build
from zoetic.physics import simulate
from zoetic.tasks import load_task, parse_task


def _short(name: str, horizon: float):
    task = load_task(name)
    return parse_task({**task.to_dict(), "horizon": horizon}, task.source)


def _learn(config: LearnConfig, task):
    setup = build(config, task)
    opt, obj = setup.optimizer, setup.objective
    while opt.evaluations < config.budget:
        X = opt.ask()
        opt.tell(X, obj(X))
    return obj.controller(opt.best_x), setup


def test_default_controller_is_periodic_at_the_animals_stroke_frequency():
    body = load_animal("shark")
    _, setup = _learn(LearnConfig(animal="shark", budget=1), _short("swim-straight", 1.0))
    ctrl = setup.template
    assert ctrl.kind == "frequency" and setup.optimizer.name == "cmaes"
    assert np.allclose(ctrl.omega, 2 * np.pi * body.wave_frequency * np.array([0, 1, 1, 2, 2]))
    t = np.linspace(0.0, 3.0, 50)
    period = 1.0 / body.wave_frequency
    probe = ctrl.with_params(np.random.default_rng(0).uniform(-0.5, 0.5, ctrl.params().size))
    assert np.allclose(probe.raw(t), probe.raw(t + 7 * period))  # it never runs out


def test_a_small_default_budget_swims_forward_and_keeps_swimming_past_the_horizon():
    body = load_animal("shark")
    task = _short("swim-straight", 2.0)
    ctrl, _ = _learn(LearnConfig(animal="shark", budget=160, seed=1), task)
    steps = int(6.0 / body.dt)
    tr = simulate(body, ctrl.table(steps, body.dt), record_every=steps // 3)
    c = tr.com(body)[0]
    x = c[:, 0]
    assert 0.1 < x[1] - x[0] < 5.0  # forward, metres in 2 s: the right order of magnitude
    # and still swimming at 4-6 s (in 3-D: fins learned over 2 s may pitch it past then)
    assert np.linalg.norm(c[3] - c[2]) > 0.5 * (x[1] - x[0])


def test_a_small_default_budget_turns_left_not_right():
    body = load_animal("shark")
    task = _short("sharp-turn-left", 2.0)
    ctrl, _ = _learn(LearnConfig(animal="shark", task="sharp-turn-left", budget=160), task)
    fig = skill_figures(body, ctrl, task)
    assert 20.0 < fig["heading_deg"] < 200.0  # degrees, positive = left
    right = ctrl.mirrored(body.actuator_mirror)
    steps = int(task.horizon / body.dt)
    tr = simulate(body, right.table(steps, body.dt), record_every=steps)
    turned = heading_angles(body, tr.positions)[0]
    assert turned[-1] - turned[0] == pytest.approx(-np.radians(fig["heading_deg"]), abs=0.05)


def test_a_users_own_animal_file_learns_with_a_built_in_task(tmp_path):
    # the zoo shark under another name, saved outside the zoo; the built-in task, unchanged,
    # fits it by what it declares it needs (water), not by a list of names
    text = (ZOO_DIR / "shark.toml").read_text().replace('name = "shark"', 'name = "my_fish"')
    path = tmp_path / "my_fish.toml"
    path.write_text(text)
    task = _short("swim-straight", 2.0)
    ctrl, setup = _learn(LearnConfig(animal=str(path), budget=96, seed=2), task)
    assert ctrl.animal == "my_fish"
    fig = skill_figures(load_animal(str(path)), ctrl, task)
    assert fig["E"] < 0 and fig["speed_bl_s"] > 0.05


def test_depth_change_with_the_fins_and_the_dolphins_burst_are_reported():
    from zoetic.behavior.handmade import handmade_repertoire
    from zoetic.bench.skills import burst, depth_change

    shark = load_animal("shark")
    gait = handmade_repertoire(shark).controllers["go-straight"]
    d = depth_change(shark, gait, seconds=2.0)
    assert d["up_bl"] > 0.3 and d["down_bl"] < -0.3  # fins up rise, fins down sink
    assert burst(shark, gait) is None  # no free surface in the shark's water
    assert depth_change(load_animal("snake"), gait) is None  # no fins
    dolphin = load_animal("dolphin")
    b = burst(dolphin, handmade_repertoire(dolphin).controllers["go-straight"], seconds=1.0)
    assert 0.2 < b["top_speed_m_s"] < 20.0 and b["t_surface_s"] is None  # 2 m deep: 1 s


def test_the_skills_bench_compares_every_entry_of_the_dolphins_plan_with_a_hand_made_one():
    from zoetic.bench.skills import bench_skills

    got = bench_skills(["dolphin"], budget=32)["dolphin"]
    assert set(got) == {"move-forward", "turn-down", "turn-up", "turn-left", "sprint"}
    assert got["move-forward"]["hand_made_entry"] == "go-straight"
    assert got["sprint"]["hand_made_entry"] == "go-straight"  # the burst beside the swim
    assert got["turn-left"]["hand_made_entry"] == "sharp-turn-left"
    assert "burst" in got["move-forward"]  # the sea has a surface to burst toward
    assert all(isinstance(v["learned_beats_hand_made"], bool) for v in got.values())
    # the figures from both starts: rest (the existing keys) and cruising, each its own E
    for v in got.values():
        assert v["starts"]["rest"] == 0.0 and v["starts"]["cruising"] > 1.0  # m/s
        assert v["learned"]["E"] != v["learned_cruising"]["E"]
        assert v["hand_made"]["E"] != v["hand_made_cruising"]["E"]
    assert (
        got["move-forward"]["hand_made_cruising"]["speed_bl_s"]
        > got["move-forward"]["hand_made"]["speed_bl_s"]
    )


def test_a_steered_wave_biases_the_muscles_and_tilts_the_fins():
    from zoetic.control import steered_wave, wave_controller

    shark = load_animal("shark")
    t = np.linspace(0.0, 1.0, 40)
    muscle = np.array([k == "muscle" for k in shark.actuator_kind])
    left = np.array([s == "left" for s in shark.actuator_side]) & muscle
    plain = steered_wave(shark, t)
    np.testing.assert_allclose(plain, wave_controller(shark).sample(t))
    turned = steered_wave(shark, t, bias=0.2, fins=0.1)
    assert turned[:, left].mean() > plain[:, left].mean() + 0.1
    assert turned[:, muscle & ~left].mean() < plain[:, muscle & ~left].mean() - 0.1
    np.testing.assert_allclose(turned[:, ~muscle], plain[:, ~muscle] + 0.1)
    weak = steered_wave(shark, t, amplitude=0.5)
    assert np.ptp(weak[:, muscle], axis=0).max() < 0.6 * np.ptp(plain[:, muscle], axis=0).max()


def test_turn_radius_is_the_arc_through_the_start_and_end_of_the_turn():
    from zoetic.bench.skills import turn_radius

    a = np.linspace(0.0, np.pi / 2, 20)  # a quarter circle of radius 2 m, centre at z = 2
    com = np.stack([2 * np.sin(a), np.zeros_like(a), 2 - 2 * np.cos(a)], axis=1)
    assert turn_radius(com, np.pi / 2, 0.5) == pytest.approx(4.0)  # body lengths of 0.5 m
    assert turn_radius(com, -np.pi / 2, 1.0) == pytest.approx(2.0)  # either direction
    assert turn_radius(com[:1].repeat(5, 0), np.pi / 2, 1.0) == 0.0  # on the spot
    assert turn_radius(com, np.radians(0.5), 1.0) is None  # not a turn
