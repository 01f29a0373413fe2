"""Learned motor skills in the aquarium: a species file names a repertoire directory, the
fish swims by ``LearnedMotor`` (swim blends, the sharp turns played from their start), and bad
references are refused."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from zoetic.behavior.aquarium.locomotion import Demand, LearnedLocomotion, learned_motor
from zoetic.behavior.aquarium.species import (
    SKILLS_DIR,
    SpeciesError,
    load_species,
    with_skills,
)
from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live
from zoetic.behavior.handmade import handmade_repertoire
from zoetic.behavior.learned_motor import LEARNED_SWIM
from zoetic.bodies import load_animal
from zoetic.learning.objective import heading_angles
from zoetic.physics import simulate


@pytest.fixture(scope="module")
def skills(tmp_path_factory):
    """A small repertoire for the shark (hand-made entries, no training) saved to disk."""
    d = tmp_path_factory.mktemp("memory") / "shark"
    handmade_repertoire(load_animal("shark")).save(d)
    return d


def _species_file(tmp_path, skills_value: str):
    text = open(load_species("shark").source).read()
    assert 'skills = "learned"' in text
    path = tmp_path / "shark.toml"
    path.write_text(text.replace('skills = "learned"', f"skills = {json.dumps(skills_value)}"))
    return path


def test_a_species_naming_a_repertoire_loads_relative_to_its_file(tmp_path, skills):
    import shutil

    shutil.copytree(skills, tmp_path / "mem")
    spec = load_species(_species_file(tmp_path, "mem"))
    assert spec.motor.skills == str(tmp_path / "mem")
    absolute = load_species(_species_file(tmp_path, str(skills)))
    assert absolute.motor.skills == str(skills)


def _swim(loco: LearnedLocomotion, demand: Demand, seconds: float):
    """Drive the fish as the tank does: one demand a 0.1 s control period."""
    body = loco.body
    per = int(round(0.1 / body.dt))
    steps = int(round(seconds / body.dt)) // per * per
    t = np.arange(steps) * body.dt
    act = np.concatenate([loco.activations(demand, t[k : k + per]) for k in range(0, steps, per)])
    tr = simulate(body, act[None], record_every=10)
    return tr.com(body)[0], heading_angles(body, tr.positions)[0]


def test_a_fish_driven_by_learned_skills_swims_forward_and_turns_the_side_asked(skills):
    body = load_animal("shark")
    loco = LearnedLocomotion(body, learned_motor(body, skills))
    assert learned_motor(body, skills) is loco.motor  # calibrated once per body and directory
    assert loco.top_speed > 0.2 and loco.turn_radius > 0
    com, head = _swim(loco, Demand(0.3), 4.0)
    forward = np.array([np.cos(head[0]), np.sin(head[0])])
    assert (com[-1, [0, 2]] - com[0, [0, 2]]) @ forward > 0.5  # m, ahead of where it started
    straight = head[-1] - head[0]
    _, left = _swim(LearnedLocomotion(body, loco.motor), Demand(0.3, turn=0.6), 4.0)
    _, right = _swim(LearnedLocomotion(body, loco.motor), Demand(0.3, turn=-0.6), 4.0)
    assert left[-1] - left[0] > straight + np.radians(8.0)
    assert right[-1] - right[0] < straight - np.radians(8.0)


def test_a_tank_predator_lives_on_learned_skills(skills):
    cfg = TankConfig(fishes=2, food=1, obstacles=0, seconds=0.6, predator_skills=str(skills))
    tank = build_tank(cfg)
    pred = next(f for f in tank.fishes if f.species.predator)
    assert pred.species.motor.skills == str(skills)
    life = live(tank)
    assert np.all(np.isfinite(life.positions))


def test_bad_skills_references_are_refused_naming_the_file(tmp_path, skills):
    missing = _species_file(tmp_path, "nowhere")
    with pytest.raises(SpeciesError, match=r"\[motor\] skills.*not a directory") as err:
        load_species(missing)
    assert str(missing) in str(err.value)
    # a repertoire for another body
    other = tmp_path / "minnow-mem"
    handmade_repertoire(load_animal("dolphin")).save(other)
    with pytest.raises(SpeciesError, match="not the shark"):
        load_species(_species_file(tmp_path, str(other)))
    # one lacking the go-straight entry
    lacking = tmp_path / "lacking"
    rep = handmade_repertoire(load_animal("shark"))
    for name in ("go-straight",):
        del rep.controllers[name], rep.durations[name], rep.info[name]
    rep.save(lacking)
    with pytest.raises(SpeciesError, match="lacks the entries go-straight"):
        load_species(_species_file(tmp_path, str(lacking)))


def test_cli_refuses_bad_predator_skills_with_exit_2(tmp_path, capsys):
    from zoetic.cli import main

    code = main(
        [
            "aquarium",
            "--fishes",
            "2",
            "--seconds",
            "0.2",
            "--no-video",
            "--predator-skills",
            str(tmp_path / "none"),
            "--out",
            str(tmp_path / "o"),
        ]
    )
    assert code == 2
    err = capsys.readouterr().err
    assert "not a directory" in err
    # the message names the option and its value, not the built-in species file
    assert f"--predator-skills '{tmp_path / 'none'}'" in err and "shark.toml" not in err


def test_a_learned_turn_plays_the_sharp_turn_from_its_start(skills):
    from zoetic.behavior.aquarium.locomotion import TURN_BURST, TURN_MIN, TURN_REST

    body = load_animal("shark")
    motor = learned_motor(body, skills)
    # the calibration: a longer sharp turn turns further, left positive, right negative
    assert np.all(np.diff(motor.turned[0]) >= 0) and motor.turned[0, -1] > 0
    assert np.all(np.diff(motor.turned[1]) <= 0) and motor.turned[1, -1] < 0
    small, large = motor.turn(0.1), motor.turn(0.5)
    assert small[0] == large[0] == 0 and motor.turn(-0.3)[0] == 1
    assert small[1] <= large[1]
    loco = LearnedLocomotion(body, motor)
    t = np.arange(20) * body.dt
    sharp = motor.turn_signal(t, 10.0 + t, 0, motor.swim(0.3), 0.0)
    # a big left turn starts the sharp turn at its own time 0, whatever the clock says
    out = loco.activations(Demand(0.3, turn=1.5), 10.0 + t)
    assert loco.turning is not None and loco.turning[0] == 0
    np.testing.assert_allclose(out, sharp)
    assert loco.turning[2] <= TURN_BURST
    # it ends when asked to turn the other way; that turn waits TURN_REST s of swimming
    swim = loco.activations(Demand(0.3, turn=-2 * TURN_MIN), 10.1 + t)
    assert loco.turning is None
    np.testing.assert_allclose(swim, motor.swim_signal(10.1 + t, motor.swim(0.3), 0.0))
    loco.activations(Demand(0.3, turn=-2 * TURN_MIN), 10.1 + TURN_REST + t)
    assert loco.turning is not None and loco.turning[0] == 1
    # a turn to the same side, asked again and again, also waits TURN_REST s after the last
    start, duration = loco.turning[1], loco.turning[2]
    end = start + duration
    loco.activations(Demand(0.3, turn=-1.5), end + t)
    assert loco.turning is None and loco.last == (1, end)
    loco.activations(Demand(0.3, turn=-1.5), end + TURN_REST / 2 + t)
    assert loco.turning is None
    loco.activations(Demand(0.3, turn=-1.5), end + TURN_REST + t)
    assert loco.turning is not None and loco.turning[0] == 1
    loco.turning = None
    # a small turn swims on
    straight = loco.activations(Demand(0.3, turn=TURN_MIN / 2), 11.0 + t)
    assert loco.turning is None
    np.testing.assert_allclose(straight, motor.swim_signal(11.0 + t, motor.swim(0.3), 0.0))


def test_learned_names_the_repertoire_shipped_for_the_body(tmp_path):
    # both species swim with the shark lattice, so one shipped repertoire serves both, and
    # both swim by it by default; "built-in" selects the calibrated wave instead
    for name in ("minnow", "shark"):
        assert load_species(name).motor.skills == str(SKILLS_DIR / "shark")
        text = open(load_species(name).source).read()
        path = tmp_path / f"{name}.toml"
        path.write_text(text.replace('skills = "learned"', 'skills = "built-in"'))
        assert load_species(path).motor.skills == "built-in"
    # a body with no shipped repertoire is refused, naming where the value came from
    snake = replace(load_species("minnow"), body="snake")
    with pytest.raises(SpeciesError, match=r"--x.*no learned repertoire is shipped for body"):
        with_skills(snake, "learned", "--x")


def test_the_shipped_repertoire_swims_and_turns_sharply():
    motor = learned_motor(load_animal("shark"), SKILLS_DIR / "shark")
    assert motor.top_speed > 0.6  # m/s: faster than the species ask for
    assert np.degrees(motor.turned[0, -1]) > 90 and np.degrees(motor.turned[1, -1]) < -90
    size = sum(p.stat().st_size for p in (SKILLS_DIR / "shark").iterdir())
    assert size < 64 * 1024  # the index and controller files only, not the training runs


def test_the_shipped_steer_turns_while_swimming_at_the_rate_asked():
    from zoetic.behavior.aquarium.locomotion import STEER_MAX, TURN_SECONDS
    from zoetic.behavior.learned_motor import STEER_WEIGHTS

    body = load_animal("shark")
    motor = learned_motor(body, SKILLS_DIR / "shark")
    assert len(motor.steers) == 2 and motor.steer_rates is not None
    # the calibration: more of the steering gait turns faster, from 0 at none of it
    assert np.all(np.diff(motor.steer_rates, axis=1) >= 0)
    assert np.all(motor.steer_rates[:, 0] == 0)
    a = motor.swim(0.3)
    assert motor.steer(0.0, a) == (0, 0.0)
    side, w = motor.steer(-0.5 * motor.steer_top, a)
    assert side == 1 and 0.0 < w < 1.0
    assert motor.steer(10 * motor.steer_top, a) == (0, float(STEER_WEIGHTS[-1]))
    # a fish asked, every period, to turn a little left steers left while it swims on: no
    # sharp turn under way, a steady heading change, and most of its speed kept
    turn = min(0.6, 0.9 * STEER_MAX)
    loco = LearnedLocomotion(body, motor)
    com, head = _swim(loco, Demand(0.3, turn=turn), 5.0)
    assert loco.turning is None
    rec = 10 * body.dt
    k = int(round(2.0 / rec))  # after 2 s to speed
    rate = (head[-1] - head[k]) / ((len(head) - 1 - k) * rec)
    assert rate > 0.5 * min(turn / TURN_SECONDS, motor.steer_top)
    speed = np.linalg.norm(np.diff(com[k:, [0, 2]], axis=0), axis=1).sum() / (
        (len(head) - 1 - k) * rec
    )
    assert speed > 0.15  # m/s: swimming, not spinning on the spot
    _, right = _swim(LearnedLocomotion(body, motor), Demand(0.3, turn=-turn), 5.0)
    assert right[-1] - right[k] < -0.5 * rate * (len(head) - 1 - k) * rec


def test_length_keeping_measures_the_head_to_tail_shortfall():
    from zoetic.tasks.terms import TERMS, BodyFrame, Signals, TermParams

    body = load_animal("shark")
    frame = BodyFrame.of(body)
    rest = np.asarray(body.rest_pos, float)
    tail = frame.part_mask("tail") > 0
    centre = rest[tail].mean(axis=0)
    towards = rest[body.head] - centre
    shorter = rest.copy()
    shorter[tail] += 0.2 * towards  # the tail's centre moved a fifth of the way to the head
    longer = rest.copy()
    longer[tail] -= 0.2 * towards  # stretched: no shortfall
    pos = np.stack([np.stack([rest, shorter]), np.stack([rest, longer])])  # (2, 2, N, 3)
    s = Signals(np, frame, pos, np.zeros((2, 2, body.n_actuators)), np.array([0.0, 0.1]), 0.0, 0.1)
    got = TERMS["length_keeping"].fn(np, s, TermParams())
    np.testing.assert_allclose(got, [0.2**2 / 2, 0.0], atol=1e-6)


def test_fishes_sharing_a_learned_motor_get_what_each_would_alone():
    """The tank's fishes of one motor share its gaits' evaluations in a control period
    (``LearnedMotor._raw``): their activations equal each fish's with a motor of its own,
    bit for bit, while turns start and end and swims and steers mix."""
    from types import SimpleNamespace

    from zoetic.behavior.aquarium.shoal import activations
    from zoetic.control.policy import Period

    body = load_animal("shark")
    motor = learned_motor(body, SKILLS_DIR / "shark")
    assert motor.steers  # the shipped repertoire steers while swimming
    demands = [
        Demand(0.3),
        Demand(0.5, 0.4, 0.2),
        Demand(0.2, -1.0),
        Demand(0.4, 2.5),
        Demand(0.1, -2.8, -0.3),
        None,
    ]
    shared = [
        SimpleNamespace(body=body, locomotion=LearnedLocomotion(body, motor)) for _ in demands
    ]
    alone = [LearnedLocomotion(body, replace(motor)) for _ in demands]
    per = int(round(0.1 / body.dt))
    for k in range(8):
        # every third period the turns reverse: sharp turns end, rests and steers follow
        now = [d if d is None or k % 3 else Demand(d.speed, -d.turn, d.pitch) for d in demands]
        rows = activations(shared, now, Period(k * per, per, body.dt))
        t = (k * per + np.arange(per)) * body.dt
        for row, loco, d in zip(rows, alone, now, strict=True):
            want = np.zeros((per, body.n_actuators)) if d is None else loco.activations(d, t)
            assert np.array_equal(row[0], want)
    # the swim weight read from the table kept once is np.interp's over the sorted speeds
    top = int(np.argmax(motor.speeds))
    order = np.argsort(motor.speeds[: top + 1])
    for v in np.linspace(motor.speeds[0], 1.5, 31):
        want = np.interp(v, motor.speeds[: top + 1][order], LEARNED_SWIM[: top + 1][order])
        assert motor.swim(v) == float(want)


def test_the_bend_is_one_at_rest_and_falls_as_the_tail_comes_forward():
    from zoetic.behavior.aquarium.bodystate import bend_indices, fish_bends
    from zoetic.behavior.aquarium.locomotion import FOLDED, TAIL_NODE, bend

    body = load_animal("shark")
    rest = np.asarray(body.rest_pos, float)
    tail = body.node_names.index(TAIL_NODE)
    folded = rest.copy()
    folded[tail] = rest[0] + 0.7 * (rest[tail] - rest[0])  # the tail fin 30 % nearer the nose
    assert bend(body, rest) == pytest.approx(1.0)
    assert bend(body, folded) == pytest.approx(0.7) and bend(body, folded) < FOLDED
    np.testing.assert_allclose(bend(body, np.stack([rest, folded])), [1.0, 0.7])
    # the tank's per-fish measure is the same, read off the world's node array
    allpos = np.concatenate([folded, rest])
    got = fish_bends(allpos, bend_indices([body, body], np.array([0, body.n_nodes])))
    np.testing.assert_allclose(got, [0.7, 1.0])


def test_a_bent_fish_swims_straight_ending_its_turn():
    """The fold guard: a slow fish bent under ``BEND_GUARD`` is not steered nor turned sharply
    this period (a steer at low speed folded the shark's tail fin for good in the tank); a
    fast one steers on."""
    from zoetic.behavior.aquarium.locomotion import BEND_GUARD, GUARD_SPEED

    body = load_animal("shark")
    motor = learned_motor(body, SKILLS_DIR / "shark")
    per = int(round(0.1 / body.dt))
    t = np.arange(per) * body.dt
    straight = motor.swim_signal(t, motor.swim(0.15), 0.0)
    bent = BEND_GUARD - 0.02
    for turn in (-0.4, 0.4, 2.5):
        loco = LearnedLocomotion(body, motor, righting=False)
        assert not np.array_equal(loco.activations(Demand(0.15, turn), t), straight)
    loco = LearnedLocomotion(body, motor, righting=False)
    for turn in (-0.4, 2.5):
        assert np.array_equal(loco.activations(Demand(0.15, turn, bend=bent), t), straight)
    loco.activations(Demand(0.15, 2.5), t)  # a sharp turn under way
    assert loco.turning is not None
    got = loco.activations(Demand(0.15, 2.5, bend=bent), t + 0.1)
    assert np.array_equal(got, motor.swim_signal(t + 0.1, motor.swim(0.15), 0.0))
    assert loco.turning is None
    fast = GUARD_SPEED + 0.1
    loco = LearnedLocomotion(body, motor, righting=False)
    got = loco.activations(Demand(fast, -0.4, bend=bent), t)
    assert not np.array_equal(got, motor.swim_signal(t, motor.swim(fast), 0.0))


def test_a_slow_steering_learned_fish_keeps_its_tail():
    """Seed 10's all-learned tank: a minnow steering right at 0.15 m/s, upright, folded its
    tail fin at 16.4 s without the fold guard (bend 0.84 then 0.66)."""
    from zoetic.behavior.aquarium.locomotion import FOLDED, bend

    tank = build_tank(TankConfig(seed=10, seconds=17.0, record_period=0.1, skills="learned"))
    life = live(tank)
    ends = [float(bend(f.body, p[-1])) for f, p in zip(tank.fishes, life.positions, strict=True)]
    assert min(ends) > FOLDED


def test_a_crowds_learned_gaits_at_once_are_each_fishs_own():
    from zoetic.behavior.aquarium.locomotion import learned_activations
    from zoetic.behavior.aquarium.species import load_species

    minnow = load_species("minnow")
    body = load_animal(minnow.body)
    motor = learned_motor(body, minnow.motor.skills)
    rng = np.random.default_rng(8)
    n, steps = 12, max(1, int(round(0.1 / body.dt)))
    crowd = [LearnedLocomotion(body, motor) for _ in range(n)]
    alone = [LearnedLocomotion(body, motor) for _ in range(n)]
    turned = 0
    for period in range(40):
        times = (period * steps + np.arange(steps)) * body.dt
        demands = [
            Demand(
                float(rng.uniform(0.0, 0.5)),
                float(rng.choice([0.0, 0.5, -1.0, 2.5, -3.0])),
                float(rng.uniform(-0.5, 0.5)),
                float(rng.normal(0, 0.1)),
                float(rng.normal(0, 0.3)),
                float(rng.choice([1.0, 0.8])),  # now and then bent: the fold guard
            )
            for _ in range(n)
        ]
        together = learned_activations(crowd, demands, times)
        for k in range(n):
            assert (together[k] == alone[k].activations(demands[k], times)).all()
            assert (crowd[k].turning, crowd[k].last) == (alone[k].turning, alone[k].last)
        turned += sum(f.turning is not None for f in crowd)
    assert turned > 20  # sharp turns were under way
