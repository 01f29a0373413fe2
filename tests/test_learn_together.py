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
    # the two runs of the 1 s task share each generation's simulation; the 0.5 s one cannot
    assert [len(g) for g in _groups(together)] == [2, 1]
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
    """Every generation's activation tables (a BLAS product) are made on one BLAS thread,
    together or alone (BLAS's idle threads spin against the kernel's), and the limit is
    lifted when learning ends."""
    from threadpoolctl import threadpool_info, threadpool_limits

    from zoetic.learning.objective import Objective

    def blas_threads() -> set[int]:
        return {i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}

    seen: list[set[int]] = []
    real = Objective.tables

    def tables(self, params):
        seen.append(blas_threads())
        return real(self, params)

    monkeypatch.setattr(Objective, "tables", tables)
    with threadpool_limits(limits=2, user_api="blas"):  # as on 2 cores, even on one
        learn_together(_runs(tmp_path / "together", tasks, shark, budget=16))
        n_together = len(seen)
        _runs(tmp_path / "alone", tasks[:1], shark, budget=16)[0].learn()
        assert n_together >= 6 and len(seen) > n_together
        assert all(s == {1} for s in seen)
        assert blas_threads() == {2}
