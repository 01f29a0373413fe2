"""Runs learned together: one batched simulation a generation, the same search as alone."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import write_short_task
from zoetic.bodies import load_animal
from zoetic.learning.run import LearnConfig, Run
from zoetic.learning.together import _groups, learn_together


@pytest.fixture
def tasks(tmp_path):
    (tmp_path / "one").mkdir()
    (tmp_path / "half").mkdir()
    one = write_short_task(tmp_path / "one", horizon=1.0, nodes=5)
    half = write_short_task(tmp_path / "half", horizon=0.5, nodes=5)
    return [one, one, half]


def _runs(out, tasks, body, budget=24):
    runs = []
    for k, task in enumerate(tasks):
        config = LearnConfig(
            animal="shark", task=str(task), optimizer="cmaes", budget=budget, seed=k, popsize=8
        )
        runs.append(Run.create(out / f"run{k}", config, body))
    return runs


def _history(run):
    return np.array(run.log.E), run.setup.optimizer.best_x


@pytest.fixture(scope="module")
def shark():
    return load_animal("shark")


def test_runs_learned_together_search_as_each_alone(tmp_path, tasks, shark):
    alone = [run.learn() for run in _runs(tmp_path / "alone", tasks, shark)]
    together = _runs(tmp_path / "together", tasks, shark)
    # the three share each generation's calls: all to 0.5 s, the 1 s runs on to 1 s
    assert [len(g) for g in _groups(together)] == [3]
    learn_together(together)
    for a, b in zip(alone, together, strict=True):
        assert b.evaluations == a.evaluations == 24
        ea, xa = _history(a)
        eb, xb = _history(b)
        np.testing.assert_array_equal(ea, eb)  # bit for bit
        np.testing.assert_array_equal(xa, xb)
        assert (b.out / "checkpoint.npz").exists() and (b.out / "history.csv").exists()


def test_interrupted_runs_learned_together_resume_to_the_same_result(tmp_path, tasks, shark):
    whole = _runs(tmp_path / "whole", tasks, shark)
    learn_together(whole)
    parts = _runs(tmp_path / "parts", tasks, shark)

    def interrupt(run):
        if run.evaluations >= 16:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        learn_together(parts, progress=interrupt)
    assert any(run.evaluations < 24 for run in parts)
    resumed = [Run.resume(run.out) for run in parts]
    learn_together(resumed)
    for a, b in zip(whole, resumed, strict=True):
        np.testing.assert_array_equal(_history(a)[0], _history(b)[0])
        np.testing.assert_array_equal(_history(a)[1], _history(b)[1])


def test_learning_holds_blas_to_one_thread_and_lifts_it_after(tmp_path, tasks, shark, monkeypatch):
    """Every generation's actuator signals (a BLAS product) are made on one BLAS thread,
    together or alone (BLAS's idle threads spin against the kernel's), and the limit is
    lifted when learning ends."""
    from threadpoolctl import threadpool_info, threadpool_limits

    from zoetic.learning.objective import Objective

    def blas_threads() -> set[int]:
        return {i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}

    seen: list[set[int]] = []
    real = Objective.actuator_signals

    def actuator_signals(self, params):
        seen.append(blas_threads())
        return real(self, params)

    monkeypatch.setattr(Objective, "actuator_signals", actuator_signals)
    with threadpool_limits(limits=2, user_api="blas"):  # as on 2 cores, even on one
        learn_together(_runs(tmp_path / "together", tasks, shark, budget=16))
        n_together = len(seen)
        _runs(tmp_path / "alone", tasks[:1], shark, budget=16)[0].learn()
        assert n_together >= 6 and len(seen) > n_together
        assert all(s == {1} for s in seen)
        assert blas_threads() == {2}


def test_rollouts_of_different_lengths_share_calls_and_move_as_alone(shark):
    """Lanes of a 1 s and a 0.5 s rollout simulated in staged calls (``_simulate_staged``:
    both to 0.5 s, then the longer on) are recorded, and fail, exactly as in calls of their
    own: a lane that blows up in the first call stays failed in the next."""
    from zoetic.learning.together import _simulate_staged
    from zoetic.physics import rest_state, simulate
    from zoetic.physics.simulate import VMAX

    class Obj:  # what _simulate_staged reads of an objective
        body, medium, dt, record_every = shark, None, shark.dt, 10

    rng = np.random.default_rng(0)
    steps = int(round(1.0 / shark.dt))
    long = rng.random((6, steps, shark.n_actuators))
    short = rng.random((4, steps // 2, shark.n_actuators))
    short[1] = 40.0  # clipped to 1: every muscle held fully contracted
    starts = [rest_state(shark, 6), rest_state(shark, 4)]
    starts[1].velocities[2] += 3.0  # another start: moving
    starts[0].velocities[3] += 10 * VMAX  # blows up in the first call
    got = _simulate_staged(Obj, [t.transpose(0, 2, 1) for t in (long, short)], starts)
    for (positions, failed), table, start in zip(got, [long, short], starts, strict=True):
        alone = simulate(shark, table, None, shark.dt, start, 10)
        np.testing.assert_array_equal(positions, alone.positions)
        np.testing.assert_array_equal(failed, alone.failed)
    assert got[0][1][3] and not got[0][1][[0, 1, 2, 4, 5]].any()


def test_shared_activations_are_each_candidates_table_once_per_start(shark):
    """The kernel's activations of runs sharing a call: run r's candidate k from start s in
    lane k S + s after the runs before it, its actuator signal clipped to [0, 1] and cast to
    float32 (the values ``simulate`` would take from the tables repeated over the starts)."""
    from zoetic.learning.together import _laid_out

    rng = np.random.default_rng(0)
    a, b = rng.normal(0.5, 0.6, (3, 8, 7)), rng.normal(0.5, 0.6, (2, 8, 7))
    act_t = _laid_out([a, b], [6, 6])  # a from 2 starts, b from 3
    tables = [np.clip(x.transpose(0, 2, 1), 0.0, 1.0) for x in (a, b)]
    lanes = np.concatenate([np.repeat(tables[0], 2, axis=0), np.repeat(tables[1], 3, axis=0)])
    assert act_t.dtype == np.float32 and act_t.shape == (7, 8, 12)
    assert np.array_equal(act_t, lanes.transpose(1, 2, 0).astype(np.float32))
