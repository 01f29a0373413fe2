"""A trick without objects is recorded by the open-loop kernel in one call a batch: the same
records and scores, to the bit, as its World stepped slice by slice."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.behavior.stunt_problem import StuntProblem
from zoetic.behavior.tricks import load_trick


def _no_world(self, *args, **kwargs):
    raise AssertionError("the open-loop record stepped a World")


def _recorded(problem, e, d, open_loop: bool, monkeypatch, **kw):
    with monkeypatch.context() as m:
        m.setattr(StuntProblem, "open_loop", open_loop)
        if open_loop:  # the one kernel call, not the World slice by slice
            m.setattr(StuntProblem, "world", _no_world)
        rec = problem.record(e, d, **kw)
    return rec, problem.scores(rec)


@pytest.mark.parametrize("trick", ["leap", "somersault"])  # one start; three (robust)
def test_open_loop_records_equal_the_worlds_to_the_bit(
    dolphin, beat_repertoire, trick, monkeypatch
):
    problem = StuntProblem(dolphin, beat_repertoire, load_trick(trick))
    assert not problem.trick.objects
    e, d = problem.random(np.random.default_rng(5), 3)
    # the search's batch from its starts, and one plan's replay recorded every other step
    for plans, kw in (((e, d), {"starts": problem.starts}), ((e[:1], d[:1]), {"record_every": 2})):
        fast, fast_scores = _recorded(problem, *plans, True, monkeypatch, **kw)
        slow, slow_scores = _recorded(problem, *plans, False, monkeypatch, **kw)
        assert np.isfinite(slow.traj.positions).all()  # nothing blew up: every record compared
        np.testing.assert_array_equal(fast.traj.times, slow.traj.times)
        np.testing.assert_array_equal(fast.traj.positions, slow.traj.positions)
        np.testing.assert_array_equal(fast.traj.final.positions, slow.traj.final.positions)
        np.testing.assert_array_equal(fast.traj.final.velocities, slow.traj.final.velocities)
        np.testing.assert_array_equal(fast.activations, slow.activations)
        np.testing.assert_array_equal(fast.contacts, slow.contacts)
        np.testing.assert_array_equal(fast.failed, slow.failed)
        assert fast.balls.shape == slow.balls.shape and fast.touch is slow.touch is None
        assert fast_scores.keys() == slow_scores.keys()
        for k in slow_scores:
            np.testing.assert_array_equal(fast_scores[k], slow_scores[k])
