"""Tasks with several start states: a strict format, one batched objective that is the mean of
the single-start ones, batch-position independence, and basic training from rest and cruising."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.behavior.training import plan_for
from zoetic.bodies import list_animals, load_animal
from zoetic.cli import main
from zoetic.control import frequency_domain
from zoetic.errors import TaskError
from zoetic.learning.objective import Objective
from zoetic.tasks import cruise_speed, parse_task, start_state, start_states

TERMS = [
    {"kind": "distance_along_heading", "weight": -1.0},
    {"kind": "heading_change", "weight": 1.0, "target": 0.5},
    {"kind": "roll_keeping", "weight": 2.0},
]
REST = {"name": "rest"}
MOVING = {"name": "moving", "speed": 0.8, "heading": 0.4}


def _doc(**extra) -> dict:
    return {"name": "two", "horizon": 0.4, "terms": TERMS} | extra


def test_a_task_with_two_starts_loads_and_round_trips(tmp_path):
    path = tmp_path / "two.toml"
    path.write_text(
        'name = "two"\nhorizon = 0.4\n'
        '[[starts]]\nname = "rest"\n'
        '[[starts]]\nname = "cruising"\nspeed = "cruise"\npitch = 0.1\n'
        '[[terms]]\nkind = "distance_along_heading"\n'
    )
    from zoetic.tasks import load_task

    task = load_task(path)
    assert task.start_names() == ["rest", "cruising"]
    assert task.start.speed == 0.0 and task.starts[1].speed == "cruise"
    assert parse_task(task.to_dict(), task.source) == task
    shark = load_animal("shark")
    st = start_states(task, shark)
    assert st.positions.shape == (2, shark.n_nodes, 3)
    assert np.all(st.velocities[0] == 0.0)
    # the cruising start moves at the speed the shark's own wave sustains, along its heading
    v = st.velocities[1, 0]
    assert np.linalg.norm(v) == pytest.approx(
        cruise_speed(shark, None, start_state(parse_task(_doc(start={"pitch": 0.1})), shark)),
        rel=1e-9,
    )
    assert v[1] == pytest.approx(np.tan(0.1) * v[0], rel=1e-6) and v[0] > 0.3


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (
            {"start": REST, "starts": [REST]},
            r"bad.toml: give one \[start\] table or \[\[starts\]\]",
        ),
        ({"starts": []}, r"bad.toml: 'starts' must be one or more"),
        (
            {"starts": [REST, {"speed": 1.0, "headng": 0.2}]},
            r"bad.toml: starts\[1\]: unknown key 'headng' \(did you mean 'heading'",
        ),
        (
            {"starts": [REST, {"name": "rest", "speed": 1.0}]},
            r"bad.toml: starts\[1\]: the name 'rest' is given to 2 starts",
        ),
        ({"starts": [REST, {"speed": "fast"}]}, r"bad.toml: starts\[1\]: 'speed' must be m/s or"),
    ],
)
def test_a_bad_start_is_refused_naming_the_file_and_entry(extra, message):
    with pytest.raises(TaskError, match=message):
        parse_task(_doc(**extra), "bad.toml")


def test_the_cli_refuses_a_bad_start_with_exit_2(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(
        'name = "bad"\nhorizon = 0.4\n[[starts]]\nspeed = "fast"\n'
        '[[terms]]\nkind = "distance_along_heading"\n'
    )
    assert (
        main(
            [
                "learn",
                "shark",
                "--task",
                str(path),
                "--budget",
                "4",
                "--no-video",
                "--out",
                str(tmp_path / "run"),
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert "bad.toml: starts[0]: 'speed' must be m/s" in err and "Traceback" not in err


@pytest.fixture(scope="module")
def objectives():
    """The two-start objective and one objective per start, on a short horizon."""
    body = load_animal("shark")
    template = frequency_domain(body, 5, 0.4, base=body.wave_frequency)
    both = Objective(parse_task(_doc(starts=[REST, MOVING])), body, template, fins="free")
    each = [
        Objective(parse_task(_doc(start=s)), body, template, fins="free") for s in (REST, MOVING)
    ]
    rng = np.random.default_rng(3)
    lo, hi = both.bounds()
    X = rng.uniform(lo, hi, (3, both.dimension))
    return both, each, X


def test_the_two_start_objective_is_the_mean_of_the_single_start_ones(objectives):
    both, each, X = objectives
    ev = both.evaluate(X)
    singles = [o.evaluate(X) for o in each]
    assert not np.allclose(singles[0].E, singles[1].E, rtol=0.05)  # the starts matter
    np.testing.assert_allclose(
        ev.per_start, np.stack([s.E for s in singles], axis=1), rtol=1e-12, atol=1e-12
    )
    np.testing.assert_allclose(ev.E, (singles[0].E + singles[1].E) / 2, rtol=1e-12, atol=1e-12)
    for name in ev.terms:
        np.testing.assert_allclose(
            ev.terms[name], (singles[0].terms[name] + singles[1].terms[name]) / 2, rtol=1e-12
        )
    # one kernel call plays every candidate from every start: 3 candidates x 2 starts
    assert both.simulate(X).positions.shape[0] == 6


def test_a_candidates_score_does_not_depend_on_its_place_in_the_batch(objectives):
    both, _, X = objectives
    e = both(X)
    assert np.array_equal(both(X[[2, 0, 1]]), e[[2, 0, 1]])
    assert np.array_equal(both(X[1:2]), e[1:2])
    assert np.array_equal(both(X), e)  # and the same seed, the same result


def test_basic_training_learns_every_entry_from_rest_and_a_cruising_start():
    for name in list_animals():
        body = load_animal(name)
        for entry in plan_for(body):
            task = entry.task
            assert task.start_names() == ["rest", "cruising"], (name, entry.name)
            speeds = np.linalg.norm(start_states(task, body).velocities[:, 0], axis=1)
            assert speeds[0] == 0.0 and speeds[1] > 0.1, (name, entry.name, speeds)


@pytest.mark.slow
def test_the_jax_objective_takes_the_same_mean_over_the_starts(objectives):
    from zoetic.learning.gradient import jax_objective

    both, each, X = objectives
    e, _ = jax_objective(both)(X[0].astype(np.float32))
    mean = (each[0](X[:1])[0] + each[1](X[:1])[0]) / 2
    assert float(e) == pytest.approx(mean, rel=2e-3, abs=2e-4)
    assert abs(mean - each[0](X[:1])[0]) > 1e-2  # the second start counts
