"""Objective terms written once: NumPy and JAX agree on every term; tasks are strict and fit
animals by capability; a user's own animal file can take every task that fits it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from zoetic.bodies import load_animal
from zoetic.cli import main
from zoetic.control import time_domain, wave_controller
from zoetic.errors import TaskError
from zoetic.learning.objective import Objective, heading_angles, motion_terms, signals
from zoetic.physics import rest_state, simulate
from zoetic.tasks import (
    Term,
    capabilities,
    check_fits,
    fits,
    list_tasks,
    load_task,
    parse_task,
    start_state,
)
from zoetic.tasks.terms import TERMS, evaluate_terms


def _task(**extra) -> dict:
    return {"name": "t", "horizon": 1.0, "terms": [{"kind": "distance_along_heading"}]} | extra


@pytest.fixture(scope="module")
def dolphin_record():
    """A dolphin swimming up through the surface: every term sees something change."""
    body = load_animal("dolphin")
    steps = int(round(1.0 / body.dt))
    table = wave_controller(body).table(steps, body.dt)
    start = rest_state(body, 2, offset=(0.0, -0.15, 0.0), velocity=(0.5, 1.2, 0.1))
    every = int(round(0.05 / body.dt))
    traj = simulate(body, np.stack([table, table[::-1]]), None, body.dt, start, every)
    rows = np.minimum(np.arange(traj.positions.shape[1]) * every, steps - 1)
    acts = np.stack([table, table[::-1]])[:, rows]
    return body, traj.positions, acts, every * body.dt


@pytest.mark.parametrize("name", sorted(TERMS))
def test_every_term_is_the_same_in_numpy_and_jax(dolphin_record, name):
    jnp = pytest.importorskip("jax.numpy")
    body, pos, acts, dt = dolphin_record
    task = parse_task(_task(terms=[{"kind": name, "target": 0.3, "goal": [0.5, 0.1, -0.2]}]))
    a = evaluate_terms(np, signals(task, body, pos, acts, dt), task.terms)[0]
    s = signals(
        task, body, jnp.asarray(pos, jnp.float32), jnp.asarray(acts, jnp.float32), dt, xp=jnp
    )
    b = np.asarray(evaluate_terms(jnp, s, task.terms)[0])
    assert a.shape == (2,) and np.all(np.isfinite(a))
    assert np.allclose(a, b, rtol=2e-4, atol=2e-5), (name, a, b)


def test_terms_measure_what_they_say_on_rigid_motions():
    body = load_animal("shark")
    rest = body.rest_pos
    com = body.mass @ rest / body.total_mass
    theta = 0.4  # turn left (toward +z) by 0.4 rad, moving 1 m forward and 0.2 m up
    c, s = math.cos(theta), math.sin(theta)
    turn = np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]])
    end = (rest - com) @ turn.T + com + np.array([1.0, 0.2, 0.0])
    pos = np.stack([rest, end])[None]  # (1, 2, N, 3)
    terms = [
        Term("distance_along_heading", 1),
        Term("lateral_deviation", 1),
        Term("heading_change", 1, target=0.1),
        Term("max_height", 1),
        Term("roll_keeping", 1),
        Term("goal_distance2", 1, goal=(1.0, 0.2, 0.0)),
        Term("air_time", 1),
    ]
    task = parse_task(
        _task(terms=[{"kind": t.kind, "target": t.target, "goal": list(t.goal)} for t in terms])
    )
    got = motion_terms(task, body, pos, medium="water")
    assert got["distance_along_heading"][0] == pytest.approx(1.0)
    assert got["lateral_deviation"][0] == pytest.approx(0.0, abs=1e-12)
    assert got["heading_change"][0] == pytest.approx((theta - 0.1) ** 2)
    assert got["max_height"][0] == pytest.approx(0.2)
    assert got["roll_keeping"][0] == pytest.approx(0.0, abs=1e-12)
    assert got["air_time"][0] == 0.0  # everything is under water in "water"
    head_end = end[body.head] - (rest[body.head] + np.array([1.0, 0.2, 0.0]))
    assert got["goal_distance2"][0] == pytest.approx(np.sum(head_end**2))
    assert heading_angles(body, pos)[0, -1] == pytest.approx(theta)


def test_steady_speed_is_the_second_halfs_in_body_lengths():
    body = load_animal("shark")
    length = body.length
    assert length == pytest.approx(np.ptp(body.rest_pos @ body.forward))
    # still for 1 s, then 2 body lengths forward and 1 sideways (top view) in the last 1 s
    xs = [0.0, 0.0, 0.0, 0.5, 1.0]
    pos = np.stack([body.rest_pos + length * np.array([2 * x, 0.3 * x, x]) for x in xs])[None]
    task = parse_task(_task(terms=[{"kind": "steady_speed_bl", "target": 1.5}]))
    got = motion_terms(task, body, pos, dt=0.5)["steady_speed_bl"][0]
    assert got == pytest.approx((math.sqrt(5.0) - 1.5) ** 2)  # 2.24 BL/s asked 1.5


def test_heading_shortfall_rewards_reaching_the_heading_early():
    body = load_animal("shark")
    rest = body.rest_pos
    com = body.mass @ rest / body.total_mass

    def turned(angle: float) -> np.ndarray:
        c, s = math.cos(angle), math.sin(angle)
        return (rest - com) @ np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]]).T + com

    early, late = [0.0, 0.2, 0.4, 0.4, 0.4], [0.0, 0.1, 0.2, 0.3, 0.4]  # rad, left
    pos = np.stack(
        [[turned(a) for a in early], [turned(a) for a in late], [turned(-a) for a in early]]
    )
    terms = [
        {"kind": "heading_shortfall", "target": 0.4},
        {"kind": "heading_shortfall", "target": -0.4, "weight": 1.0},
        {"kind": "heading_change", "target": 0.4},
    ]
    got = evaluate_terms(
        np,
        signals(parse_task(_task(terms=terms)), body, pos, None, 0.05),
        parse_task(_task(terms=terms)).terms,
    )
    left, right, final = (np.asarray(g) for g in got)
    # mean over the records of the squared shortfall: (0.4^2 + 0.2^2) / 5 for the early turn
    assert left[0] == pytest.approx((0.16 + 0.04) / 5)
    assert left[1] == pytest.approx((0.16 + 0.09 + 0.04 + 0.01) / 5)
    assert final[0] == pytest.approx(0.0, abs=1e-12) and final[1] == pytest.approx(0, abs=1e-12)
    assert right[2] == pytest.approx(left[0])  # a right turn toward a negative target
    wrong_way = (0.4**2 + 0.6**2 + 3 * 0.8**2) / 5  # turning right while 0.4 left is wanted
    assert left[2] == pytest.approx(wrong_way) and right[0] == pytest.approx(wrong_way)


def test_start_state_places_turns_pitches_and_launches_the_body():
    body = load_animal("dolphin")
    task = parse_task(
        _task(
            start={
                "position": [1.0, 0.0, 2.0],
                "depth": 0.5,
                "heading": 0.5,
                "pitch": 0.3,
                "speed": 2.0,
            }
        )
    )
    st = start_state(task, body)
    s = signals(task, body, st.positions[:, None], None, 0.05)
    assert np.allclose(s.com[0, 0], [1.0, -0.5, 2.0])
    assert s.heading[0, 0] == pytest.approx(0.5, abs=1e-9)
    assert s.pitch[0, 0] == pytest.approx(0.3, abs=0.02)  # the head sits a little off-axis
    fwd = np.array([math.cos(0.3) * math.cos(0.5), math.sin(0.3), math.cos(0.3) * math.sin(0.5)])
    assert np.allclose(st.velocities[0], 2.0 * fwd)
    # and the objective starts its rollouts there
    obj = Objective(task, body, time_domain(body, 5, 1.0))
    assert np.array_equal(obj.start.positions, st.positions)
    with pytest.raises(TaskError, match="needs a water surface"):
        start_state(parse_task(_task(start={"depth": 1.0})), load_animal("shark"))


def test_task_files_are_strict_and_say_what_is_wrong():
    with pytest.raises(
        TaskError,
        match=r"x.toml: terms\[0\]: unknown kind 'heading_chnage' "
        r"\(did you mean 'heading_change'\?\)",
    ):
        parse_task(_task(terms=[{"kind": "heading_chnage"}]), "x.toml")
    with pytest.raises(
        TaskError,
        match=r"x.toml: terms\[0\]: unknown key 'wieght' \(did you "
        r"mean 'weight'\?\)",
    ):
        parse_task(_task(terms=[{"kind": "effort", "wieght": 2.0}]), "x.toml")
    with pytest.raises(TaskError, match="unknown key 'animals'"):
        parse_task(_task(animals=["shark"]), "x.toml")
    with pytest.raises(TaskError, match="'weight' is a non-finite number"):
        parse_task(_task(terms=[{"kind": "effort", "weight": float("nan")}]))
    with pytest.raises(TaskError, match="'horizon' is a non-finite number"):
        parse_task(_task(horizon=float("inf")))
    with pytest.raises(TaskError, match="'horizon' must be at most"):
        parse_task(_task(horizon=1e9))  # bounded before anything is allocated
    with pytest.raises(TaskError, match="'goal' must be"):
        parse_task(_task(terms=[{"kind": "goal_distance2", "goal": "north"}]))
    with pytest.raises(TaskError, match="'goal'.*must be a number"):
        parse_task(_task(terms=[{"kind": "goal_distance2", "goal": ["1", 0, 0]}]))
    with pytest.raises(TaskError, match=r"start: unknown key 'headng' \(did you mean 'heading'"):
        parse_task(_task(start={"headng": 1.0}))
    with pytest.raises(TaskError, match=r"unknown capability 'fin' \(did you mean 'fins'"):
        parse_task(_task(requires=["fin"]))
    # a round trip through to_dict keeps everything
    task = load_task("swim-straight")
    assert parse_task(task.to_dict(), task.source) == task


def test_tasks_fit_animals_by_capability():
    snake, shark, dolphin = (load_animal(n) for n in ("snake", "shark", "dolphin"))
    assert {"ground", "head", "mirror"} <= capabilities(snake) and "water" not in capabilities(
        snake
    )
    assert {"water", "deep-water", "fins"} <= capabilities(shark)
    assert "surface" not in capabilities(shark)  # the shark's water has no free surface
    assert {"water", "surface", "fins"} <= capabilities(dolphin)
    assert "fins" not in capabilities(load_animal("ray"))
    swim, crawl = load_task("swim-straight"), load_task("crawl-straight")
    assert fits(swim, shark) and fits(swim, dolphin) and not fits(swim, snake)
    assert fits(crawl, snake) and not fits(crawl, shark)
    assert fits(swim, snake, "sea")  # the medium is part of it
    with pytest.raises(TaskError, match="cannot apply to the snake .*requires water"):
        check_fits(swim, snake)
    either = parse_task(_task(requires=["ground|deep-water"]))
    assert fits(either, snake) and fits(either, shark) and not fits(either, dolphin)
    for name in list_tasks():  # every built-in task fits at least one zoo animal
        assert any(fits(load_task(name), b) for b in (snake, shark, dolphin))


@pytest.fixture
def my_eel(tmp_path):
    """A user's own animal, outside the zoo: the shark's body under another name."""
    from zoetic.bodies import ZOO_DIR

    text = (ZOO_DIR / "shark.toml").read_text().replace('name = "shark"', 'name = "my_eel"', 1)
    path = tmp_path / "my_eel.toml"
    path.write_text(text)
    return path


def test_a_users_animal_takes_every_task_that_fits(my_eel, tmp_path, capsys):
    eel = load_animal(str(my_eel))
    assert eel.name == "my_eel"
    fitting = [n for n in list_tasks() if fits(load_task(n), eel)]
    assert {"swim-straight", "turn-left", "reach-goal"} <= set(fitting)
    short = tmp_path / "short.toml"
    short.write_text(
        'name = "short"\nrequires = ["water"]\nhorizon = 0.3\nnodes = 3\n'
        '[[terms]]\nkind = "distance_along_heading"\nweight = -1.0\n'
    )
    code = main(
        [
            "learn",
            str(my_eel),
            "--task",
            str(short),
            "--budget",
            "4",
            "--no-video",
            "--out",
            str(tmp_path / "run"),
        ]
    )
    assert code == 0 and (tmp_path / "run" / "controller.json").exists()
    code = main(
        [
            "learn",
            str(my_eel),
            "--task",
            "crawl-straight",
            "--budget",
            "4",
            "--no-video",
            "--out",
            str(tmp_path / "no"),
        ]
    )
    assert code == 2
    said = " ".join("".join(capsys.readouterr()).split())  # Rich wraps long lines
    assert "cannot apply to the my_eel (medium 'water'): it requires ground" in said
    from zoetic.behavior.training import plan_for

    assert [e.name for e in plan_for(eel)] == [
        "go-straight",
        "sharp-turn-left",
        "wide-turn-left",
        "swim-up",
        "swim-down",
    ]


@pytest.mark.slow
def test_jax_objective_scores_like_the_numpy_objective():
    pytest.importorskip("jax")
    from zoetic.learning.gradient import value_and_grad

    body = load_animal("shark")
    task = parse_task(
        _task(
            horizon=0.3,
            nodes=4,
            nu1=0.01,
            mu1=1.0,
            start={"heading": 0.3, "speed": 0.2},
            terms=[
                {"kind": k, "target": 0.2}
                for k in ("distance_along_heading", "heading_change", "effort")
            ],
        )
    )
    obj = Objective(task, body, time_domain(body, 4, 0.3))
    X = np.random.default_rng(1).uniform(*obj.bounds(), size=(2, obj.dimension))
    ev = obj.evaluate(X)
    jev, grad = value_and_grad(obj, X)
    assert np.allclose(ev.E, jev.E, rtol=1e-3, atol=1e-5)
    assert np.allclose(ev.E_u, jev.E_u, rtol=1e-4)
    assert grad.shape == X.shape and np.all(np.isfinite(grad)) and np.any(grad != 0)


def test_abstraction_measure_scores_like_the_objective_from_the_tasks_start():
    from zoetic.learning.abstraction import measure

    body = load_animal("shark")
    task = parse_task(
        _task(
            horizon=0.6,
            nodes=4,
            start={"heading": -0.4, "speed": 0.3},
            terms=[
                {"kind": k, "target": 0.1}
                for k in ("distance_along_heading", "heading_change", "effort", "mean_speed")
            ],
        )
    )
    obj = Objective(task, body, time_domain(body, 4, 0.6))
    x = np.random.default_rng(2).uniform(*obj.bounds())
    ev = obj.evaluate(x[None])
    m = measure(body, obj.controller(x), task.horizon, task=task)
    assert m["E"] == pytest.approx(ev.E[0], rel=1e-6, abs=1e-9)
    assert m["forward"] == pytest.approx(ev.terms["distance_along_heading"][0], abs=1e-9)


def test_a_users_repertoire_finds_its_animal_file(my_eel, tmp_path):
    from zoetic.errors import BodyError
    from zoetic.io import write_toml
    from zoetic.runs import repertoire_body

    memory = tmp_path / "memory"
    (memory / "runs" / "go-straight").mkdir(parents=True)
    write_toml(memory / "runs" / "go-straight" / "config.toml", {"run": {"animal": str(my_eel)}})
    assert repertoire_body(memory, "my_eel").name == "my_eel"
    assert repertoire_body(memory, "shark").name == "shark"
    with pytest.raises(BodyError):
        repertoire_body(memory, "my_newt")


def test_a_repertoire_of_a_variant_named_like_a_zoo_animal_is_judged_as_the_variant(tmp_path):
    import dataclasses

    from zoetic.learning.stored_body import ANIMAL_FILE, save_body
    from zoetic.runs import repertoire_body

    ray = load_animal("ray")
    heavier = dataclasses.replace(ray, mass=ray.mass * 1.5)  # a variant file's ray
    memory = tmp_path / "memory"
    (memory / "runs" / "go-straight").mkdir(parents=True)
    save_body(heavier, memory / "runs" / "go-straight" / ANIMAL_FILE)
    got = repertoire_body(memory, "ray")
    assert np.allclose(got.mass, heavier.mass) and not np.allclose(got.mass, ray.mass)
    assert repertoire_body(memory, "shark").name == "shark"


def test_body_heading_change_follows_the_body_axis_not_a_swung_head():
    body = load_animal("snake")
    rest = body.rest_pos
    com = body.mass @ rest / body.total_mass
    theta = 0.5  # the whole body turned left by 0.5 rad ...
    c, s = math.cos(theta), math.sin(theta)
    end = (rest - com) @ np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]]).T + com
    swung = end.copy()  # ... and then its head alone swung 5 cm further left
    swung[body.head] += 0.05 * np.array([-s, 0.0, c])
    pos = np.stack([[rest, end], [rest, swung]])
    terms = [
        {"kind": "body_heading_change", "target": theta},
        {"kind": "heading_change", "target": theta},
    ]
    task = parse_task(_task(terms=terms))
    axis, head = (
        np.asarray(v) for v in evaluate_terms(np, signals(task, body, pos, None, 0.05), task.terms)
    )
    assert axis[0] == pytest.approx(0.0, abs=1e-10) and head[0] == pytest.approx(0.0, abs=1e-10)
    # the head-based heading counts the swing as a turn; the body axis barely moves
    assert math.sqrt(head[1]) > 0.08 and math.sqrt(axis[1]) < 0.2 * math.sqrt(head[1])


def test_promise_terms_cost_only_a_roll_or_turn_beyond_their_bound():
    body = load_animal("shark")
    rest = body.rest_pos
    com = body.mass @ rest / body.total_mass
    f = body.forward / np.linalg.norm(body.forward)

    def rolled(angle: float) -> np.ndarray:  # about the forward axis (Rodrigues)
        k = np.array([[0, -f[2], f[1]], [f[2], 0, -f[0]], [-f[1], f[0], 0]])
        r = np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k
        return (rest - com) @ r.T + com

    def turned(angle: float) -> np.ndarray:  # about the vertical, left positive
        c, s = math.cos(angle), math.sin(angle)
        return (rest - com) @ np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]]).T + com

    pos = np.stack(
        [
            [rest, rolled(0.2), rest],  # a small roll, within the bound
            [rest, rolled(0.5), rest],  # 0.5 rad at its worst instant
            [rest, rolled(-0.5), rest],  # the other way
            [rest, rolled(math.pi), rolled(math.pi)],  # upside down
            [rest, turned(0.4), turned(0.4)],  # a turn of 0.4 rad left ...
            [rest, turned(-0.4), turned(-0.4)],  # ... and right
            [rest, turned(0.05), turned(0.05)],  # a turn within the bound
        ]
    )
    terms = [
        {"kind": "roll_excess", "target": 0.3},
        {"kind": "turn_excess", "target": 0.1},
        {"kind": "roll_keeping"},
    ]
    task = parse_task(_task(terms=terms))
    roll, turn, keep = (
        np.asarray(v) for v in evaluate_terms(np, signals(task, body, pos, None, 0.05), task.terms)
    )
    assert roll[0] == pytest.approx(0.0, abs=1e-10)
    assert roll[1] == pytest.approx(0.2**2, rel=1e-6) and roll[2] == pytest.approx(roll[1])
    # upside down costs the whole half turn, where roll_keeping reads it as upright
    assert roll[3] == pytest.approx((math.pi - 0.3) ** 2, rel=1e-6) and keep[3] < 1e-6
    assert np.allclose(roll[4:], 0.0, atol=1e-10)  # a turn is no roll
    assert turn[4] == pytest.approx(0.3**2, rel=1e-6) and turn[5] == pytest.approx(turn[4])
    assert turn[6] == pytest.approx(0.0, abs=1e-12)
    assert np.allclose(turn[:4], 0.0, atol=1e-10)  # a roll is no turn
