"""A ``stop_when_met`` trick's search ends once its best plan meets the trick's targets from
the start and from every perturbed start of the check; otherwise it spends its budget."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.stunt_problem import StuntProblem
from zoetic.behavior.stunts import (
    STOP_CHECK_EVERY,
    StopWhenMet,
    discover,
    perturbed_successes,
)
from zoetic.behavior.training import rest_abstraction
from zoetic.behavior.tricks import parse_trick
from zoetic.errors import TaskError

JITTER = {"depth": 0.05, "heading": 2.0, "pitch": 2.0}
# dropped nose down from 1.5 m above the surface: out of the water at the start, wholly back
# in it within the horizon whatever the plan, so a clean-dive's targets are met from any start
DROPPED = {"depth": -1.5, "pitch": -1.2}
UNDER = {"depth": 0.6, "pitch": 0.6, "speed": 1.0}  # under and slow: never leaves the water
CHAINS = 16  # the annealing's batch of plans (discover's chains)


def _trick(start: dict, stop: bool, jitter: dict = JITTER):
    doc = {
        "name": "clean-dive",
        "horizon": 1.2,
        "record_hz": 20.0,
        "requires": ["surface"],
        "start": dict(start),
        "trick": {
            "segments": 2,
            "durations": [0.1, 0.6],
            "jitter": dict(jitter),
            "robust": False,
            "stop_when_met": stop,
        },
        "terms": [{"kind": "apex_above_surface", "weight": -1.0}],
    }
    return parse_trick(doc, "dive")


@pytest.fixture(scope="module")
def repertoire(dolphin):
    rep = Repertoire(dolphin.name, tuple(dolphin.actuator_names))
    rep.add("do-nothing", rest_abstraction(dolphin), 1.0)
    return rep


def test_a_search_stops_at_its_first_check_once_the_targets_are_met_everywhere(dolphin, repertoire):
    budget = 10 * CHAINS
    found = discover(dolphin, repertoire, _trick(DROPPED, stop=True), budget=budget)
    # the best plan meets the targets from every start: the first check (after
    # STOP_CHECK_EVERY batches) ends the search
    assert found.result.stopped and found.summary()["stopped_when_met"]
    assert found.result.evaluations == STOP_CHECK_EVERY * CHAINS < budget
    assert found.perturbed == [True] * 6
    full = discover(dolphin, repertoire, _trick(DROPPED, stop=False), budget=budget)
    assert not full.result.stopped and full.result.evaluations == budget


def test_a_search_whose_targets_are_not_met_spends_its_budget(dolphin, repertoire):
    budget = 8 * CHAINS
    trick = _trick(UNDER, stop=True)
    found = discover(dolphin, repertoire, trick, budget=budget)
    assert not found.result.stopped and found.result.evaluations == budget
    assert not any(found.perturbed)


def test_the_stop_rule_checks_an_improved_best_plan_at_most_every_few_batches(dolphin, repertoire):
    problem = StuntProblem(dolphin, repertoire, _trick(UNDER, stop=True))
    rule = StopWhenMet(problem, every=3)

    class Opt:  # the search's best plan, as the rule reads it
        best_f = 1.0
        best = (np.array([0, 0]), np.array([0.3, 0.3]))

    opt = Opt()
    assert [rule(opt) for _ in range(3)] == [False] * 3 and rule.checks == 1
    assert [rule(opt) for _ in range(5)] == [False] * 5 and rule.checks == 1  # no better plan
    opt.best_f = 0.5
    assert not rule(opt) and rule.checks == 2  # better, and 3 batches since the last check
    # without a jitter the start alone is checked
    plain = StuntProblem(dolphin, repertoire, _trick(DROPPED, stop=True, jitter={}))
    assert StopWhenMet(plain).signs == ((0, 0, 0),)
    assert perturbed_successes(plain, *Opt.best, StopWhenMet(plain).signs) == [True]


def test_stop_when_met_is_true_or_false():
    doc = _trick(UNDER, stop=True).to_dict()
    assert doc["stop_when_met"] is True
    bad = {
        "name": "x",
        "horizon": 1.0,
        "requires": ["surface"],
        "trick": {"stop_when_met": "yes"},
        "terms": [{"kind": "apex_above_surface", "weight": -1.0}],
    }
    with pytest.raises(TaskError, match=r"x: trick: 'stop_when_met' must be true or false"):
        parse_trick(bad, "x")
