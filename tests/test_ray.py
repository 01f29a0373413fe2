"""The Ray evaluator: same history as in-process, bit for bit, even when a worker is killed."""

from __future__ import annotations

import csv
import os
import signal
from pathlib import Path

import numpy as np
import pytest
import ray

from zoetic.cli import main
from zoetic.learn.evaluate import BatchEvaluator, make_evaluator
from zoetic.learn.ray_eval import RayEvaluator
from zoetic.learn.run import LearnConfig, Run

CONFIG = dict(animal="snake", task="crawl-straight", optimizer="cmaes", budget=30, popsize=10,
              seed=5, nodes=4)  # fmt: skip


@pytest.fixture(scope="module")
def local_ray():
    ray.init(num_cpus=2, object_store_memory=80 * 1024**2, include_dashboard=False,
             log_to_driver=False, configure_logging=False)  # fmt: skip
    yield ray.get_runtime_context().gcs_address
    ray.shutdown()


def _history(evaluator, out: Path) -> tuple[np.ndarray, np.ndarray]:
    """Learn to the budget with ``evaluator``; return every candidate and its E, in order."""
    run = Run.create(out, LearnConfig(**CONFIG))
    while run.evaluations < run.setup.config.budget and run.step(evaluator):
        pass
    return np.array(run.log.X), np.array(run.log.E)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    return _history(BatchEvaluator(), tmp_path_factory.mktemp("batch"))


def test_same_history_as_in_process_bit_for_bit(local_ray, reference, tmp_path):
    ev = make_evaluator("ray", workers=2)
    try:
        X, E = _history(ev, tmp_path)
    finally:
        ev.close()
    assert len(E) == CONFIG["budget"]
    assert np.array_equal(X, reference[0]) and np.array_equal(E, reference[1])
    assert ray.is_initialized()  # a Ray the evaluator did not start is left running


def test_a_worker_killed_mid_run_loses_no_evaluation(local_ray, reference, tmp_path):
    killed: list[int] = []
    calls = {"n": 0}

    def kill_during_second_generation(ev: RayEvaluator) -> None:
        calls["n"] += 1
        if calls["n"] == 2:  # its sub-batches are in flight
            pid = ev.pids()[0]
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)

    ev = RayEvaluator(actors=2, on_submit=kill_during_second_generation)
    try:
        X, E = _history(ev, tmp_path)
        survivors = ev.pids()
    finally:
        ev.close()
    assert killed and killed[0] not in survivors and len(survivors) == 2  # restarted
    assert np.array_equal(X, reference[0]) and np.array_equal(E, reference[1])


def test_learn_cli_with_a_ray_address(local_ray, reference, tmp_path):
    c = CONFIG
    args = ["learn", c["animal"], "--task", c["task"], "--optimizer", c["optimizer"],
            "--budget", str(c["budget"]), "--popsize", str(c["popsize"]), "--nodes",
            str(c["nodes"]), "--seed", str(c["seed"]), "--no-video", "--out", str(tmp_path),
            "--evaluator", "ray", "--ray-address", local_ray]  # fmt: skip
    assert main(args) == 0
    with (tmp_path / "history.csv").open() as fh:
        assert [row["E"] for row in csv.DictReader(fh)] == [f"{e:.6g}" for e in reference[1]]
    assert 'evaluator = "ray"' in (tmp_path / "config.toml").read_text()


def test_repertoire_training_learns_on_ray(local_ray, tmp_path):
    from zoetic.behavior.training import train_repertoire

    class Stop(Exception):
        pass

    entries: list[str] = []

    def on_entry(name: str, run) -> None:
        if entries:
            raise Stop  # one entry is enough to see where it was evaluated
        entries.append(name)

    with pytest.raises(Stop):
        train_repertoire("snake", tmp_path, budget=10, nodes=4, on_entry=on_entry,
                         evaluator="ray")  # fmt: skip
    run_dir = tmp_path / "runs" / entries[0]
    assert 'evaluator = "ray"' in (run_dir / "config.toml").read_text()
    assert len((run_dir / "history.csv").read_text().splitlines()) > 10  # one CMA-ES generation


def test_san_search_on_ray_matches_the_process_pool(local_ray):
    from zoetic.san import load_creature
    from zoetic.san.search import search

    cart = load_creature("cart")
    here = search(cart, trials=6, seed=3, seconds=0.5, workers=1)
    on_ray = search(cart, trials=6, seed=3, seconds=0.5, workers=2, evaluator="ray")
    assert np.array_equal(here.metrics, on_ray.metrics)
    assert np.array_equal(here.distances, on_ray.distances) and np.ptp(here.distances) > 0


def test_macro_search_on_ray_matches_in_process(local_ray):
    from zoetic.behavior.macro import MacroProblem, ReachTask, search
    from zoetic.behavior.tracking import handmade_repertoire
    from zoetic.bodies import load_animal

    shark = load_animal("shark")
    task = ReachTask(goal=(1.8, 0.8), obstacles=((0.9, 0.3, 0.3),), horizon=2.0)
    problem = MacroProblem(shark, handmade_repertoire(shark), task, segments=3)
    here = search(problem, "ga", budget=16, seed=1, popsize=8)
    on_ray = search(problem, "ga", budget=16, seed=1, popsize=8, evaluator="ray")
    assert here.history == on_ray.history and np.array_equal(here.entries, on_ray.entries)
    assert np.array_equal(here.durations, on_ray.durations)
