"""Robust stunts: a trick's jitter moves its start (depth, heading, pitch); the search scores a
plan by the worst of its start and two moved ones, and a found plan is checked from six
others, one jitter at a time."""

from __future__ import annotations

import math

import numpy as np
import pytest

from zoetic.behavior.stunt_problem import (
    CHECK_SIGNS,
    SEARCH_SIGNS,
    StuntProblem,
    jittered_starts,
    starts_per_plan,
)
from zoetic.behavior.stunts import measures, perturbed_measures, perturbed_successes
from zoetic.behavior.tricks import parse_trick
from zoetic.errors import TaskError
from zoetic.tasks.terms import TERMS, BodyFrame, Signals, TermParams

START = {"depth": 0.6, "pitch": 0.6, "speed": 1.0, "heading": 0.1}
JITTER = {"depth": 0.05, "heading": 2.0, "pitch": 2.0}


def _doc(start=START, jitter=JITTER) -> dict:
    return {
        "name": "up",
        "horizon": 0.5,
        "record_hz": 20.0,
        "requires": ["surface"],
        "start": dict(start),
        "trick": {"segments": 2, "durations": [0.1, 0.4], "jitter": dict(jitter)},
        "terms": [
            {"kind": "apex_above_surface", "weight": -1.0},
            {"kind": "final_pitch", "weight": 1.0, "target": 0.0},
        ],
    }


def test_jittered_starts_move_depth_heading_and_pitch_by_the_trick_jitter(dolphin):
    trick = parse_trick(_doc(), "up")
    assert trick.jitter == (0.05, 2.0, 2.0)
    st = jittered_starts(trick, dolphin, ((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, -1)))
    w = dolphin.mass / dolphin.total_mass
    com = np.einsum("n,knd->kd", w, st.positions)
    assert com[1, 1] - com[0, 1] == pytest.approx(-0.05, abs=1e-9)  # 5 cm deeper
    v = st.velocities[:, 0]  # along the body's forward axis at 1 m/s

    def heading(u):
        return math.atan2(u[2], u[0])

    def pitch(u):
        return math.asin(u[1] / np.linalg.norm(u))

    assert math.degrees(heading(v[2]) - heading(v[0])) == pytest.approx(2.0, abs=1e-6)
    assert math.degrees(pitch(v[3]) - pitch(v[0])) == pytest.approx(-2.0, abs=1e-6)
    assert math.degrees(heading(v[1]) - heading(v[0])) == pytest.approx(0.0, abs=1e-9)


def test_the_robust_cost_is_the_worst_over_the_perturbed_starts(dolphin, beat_repertoire):
    """Each perturbed start rebuilt as its own trick (its [start] edited): the robust E is the
    worst of their E, and differs from the start's own."""
    robust = StuntProblem(dolphin, beat_repertoire, parse_trick(_doc(), "up"))
    assert len(robust.starts.positions) == len(SEARCH_SIGNS) == 3
    e = np.array([[1, 0], [0, 1]])
    d = np.array([[0.3, 0.2], [0.1, 0.4]])
    got = robust.evaluate(e, d)
    each = []
    for a, b, c in SEARCH_SIGNS:
        start = START | {
            "depth": START["depth"] + 0.05 * a,
            "heading": START["heading"] + math.radians(2.0 * b),
            "pitch": START["pitch"] + math.radians(2.0 * c),
        }
        one = StuntProblem(dolphin, beat_repertoire, parse_trick(_doc(start, {}), "up"))
        assert len(one.starts.positions) == 1  # no jitter: the start alone
        each.append(one.evaluate(e, d)["cost"])
    each = np.array(each)  # (starts, plans)
    assert np.ptp(each, axis=0).min() > 1e-6  # the moved starts score differently
    np.testing.assert_allclose(got["cost"], each.max(axis=0), rtol=1e-9)
    np.testing.assert_allclose(got["nominal"], each[0], rtol=1e-9)
    assert np.all(got["cost"] > got["nominal"])


def test_a_plan_is_checked_from_each_jittered_start(dolphin, beat_repertoire):
    """The check's measures from each moved start are those of the trick with that start."""
    doc = _doc() | {"name": "leap"}
    problem = StuntProblem(dolphin, beat_repertoire, parse_trick(doc, "leap"))
    e, d = np.array([1, 1]), np.array([0.3, 0.3])
    got = perturbed_measures(problem, e, d)
    assert len(got) == len(CHECK_SIGNS) == 6
    apex = [m["apex_above_surface_m"] for m in got]
    assert len(set(apex)) > 1
    for k in (0, 3):  # 5 cm deeper; turned 2 deg right
        a, b, c = CHECK_SIGNS[k]
        start = START | {
            "depth": START["depth"] + 0.05 * a,
            "heading": START["heading"] + math.radians(2.0 * b),
            "pitch": START["pitch"] + math.radians(2.0 * c),
        }
        one = StuntProblem(
            dolphin, beat_repertoire, parse_trick(_doc(start, {}) | {"name": "leap"}, "l")
        )
        rec = one.record(e[None], d[None], record_every=2)
        assert got[k] == measures(one, rec)
    # a leap that stays under leaves no water from any start: no target met
    assert perturbed_successes(problem, e, d) == [False] * 6


def test_a_robust_search_spends_its_budget_of_simulations_on_a_third_as_many_plans(
    dolphin, beat_repertoire
):
    from zoetic.behavior.stunts import discover

    robust = parse_trick(_doc(), "up")
    plain = parse_trick(_doc() | {"trick": _doc()["trick"] | {"robust": False}}, "up")
    assert starts_per_plan(robust) == 3 and starts_per_plan(plain) == 1
    assert len(StuntProblem(dolphin, beat_repertoire, plain).starts.positions) == 1
    found = discover(dolphin, beat_repertoire, robust, budget=24, seed=0)
    assert found.result.evaluations == 8
    assert found.summary()["perturbed_starts"] == 6  # checked all the same


def test_the_jitter_table_is_strict():
    bad = _doc(jitter={"depht": 0.05})
    with pytest.raises(TaskError, match=r"up: trick\.jitter: unknown key"):
        parse_trick(bad, "up")
    with pytest.raises(TaskError, match=r"up: trick\.jitter: 'pitch' must be"):
        parse_trick(_doc(jitter={"pitch": -1.0}), "up")
    with pytest.raises(TaskError, match=r"up: trick: 'robust' must be true or false"):
        parse_trick(_doc() | {"trick": {"robust": "yes"}}, "up")


def _rising(body, heights) -> Signals:
    """The rest pose with its centre of mass at each height (m), one record every 0.1 s."""
    w = body.mass / body.total_mass
    rel = body.rest_pos - w @ body.rest_pos
    pos = np.array([rel + [0.0, y, 0.0] for y in heights])[None]
    r = len(heights)
    acts = np.zeros((1, r, body.n_actuators))
    return Signals(np, BodyFrame.of(body), pos, acts, np.arange(r) * 0.1, 0.0, r * 0.1)


def test_dive_before_apex_counts_the_sinking_before_the_apex_up_to_its_target(dolphin):
    dive = TERMS["dive_before_apex"].fn
    dipped = _rising(dolphin, [-2.0, -2.6, -1.0, 0.5, -0.5, -3.0])
    straight = _rising(dolphin, [-2.0, -1.5, -1.0, 0.5, -0.5, -3.0])
    assert dive(np, dipped, TermParams())[0] == pytest.approx(0.6)  # the sink after: not
    assert dive(np, dipped, TermParams(0.5))[0] == pytest.approx(0.5)
    assert dive(np, straight, TermParams())[0] == pytest.approx(0.0)
