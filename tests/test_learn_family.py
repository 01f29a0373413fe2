"""Learning as one family: every registered optimizer saves and restores its whole state,
runs resume from that state (after Ctrl-C, an exception mid-step, or SIGKILL) to the same
history, checkpoints are verified, and the budget is an upper bound."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from conftest import write_short_task
from zoetic.errors import RunDirError
from zoetic.learning.checkpoint import CHECKPOINT, PREVIOUS, Log, checkpoint_bytes, read_checkpoint
from zoetic.learning.optimizers import OPTIMIZERS, make_optimizer
from zoetic.learning.run import LearnConfig, Run

TARGET = np.array([0.3, 0.7, 0.2, 0.55, 0.8])


def _f(X):
    return np.sum((X - TARGET) ** 2, axis=1)


def _grad(X):
    return 2 * (X - TARGET)


def _make(name):
    opts = {"popsize": 6} if name == "cmaes" else {}
    if name == "anneal":
        opts = {"chains": 3}
    return make_optimizer(
        name, np.full(5, 0.9), np.zeros(5), np.ones(5), seed=4, budget=400, **opts
    )


def _steps(opt, n):
    asked = []
    for _ in range(n):
        X = opt.ask()
        if len(X) == 0:
            break
        asked.append(X.copy())
        opt.tell(X, _f(X), _grad(X) if opt.needs_gradient else None)
    return asked


@pytest.mark.parametrize("name", sorted(OPTIMIZERS))
def test_every_optimizer_resumes_from_its_saved_state_to_the_same_history(tmp_path, name):
    if name == "gradient":
        pytest.importorskip("jax")
    whole = _make(name)
    full = _steps(whole, 40)
    first = _make(name)
    head = _steps(first, 15)
    # through the real checkpoint file: arrays and plain values only, checksummed
    path = tmp_path / CHECKPOINT
    path.write_bytes(checkpoint_bytes(Log(), first.state_dict()))
    _, state = read_checkpoint(path)
    again = _make(name)
    again.load_state_dict(state)
    tail = _steps(again, 25)
    assert len(head) + len(tail) == len(full)
    for a, b in zip(head + tail, full, strict=True):
        assert np.array_equal(a, b)
    assert again.best_f == whole.best_f and np.array_equal(again.best_x, whole.best_x)
    assert again.evaluations == whole.evaluations
    assert whole.best_f < 0.5 * _f(np.full((1, 5), 0.9))[0]  # and it learned something
    for opt in (whole, first, again):
        opt.close()


def test_cmaes_state_survives_a_cma_release_that_cannot_read_the_pickle():
    opt = _make("cmaes")
    _steps(opt, 10)
    state = opt.state_dict() | {"pickle": np.zeros(8, np.uint8)}  # unreadable
    again = _make("cmaes")
    again.load_state_dict(state)
    assert np.allclose(again.es.mean, opt.es.mean) and again.es.sigma == opt.es.sigma
    assert np.allclose(again.es.sm.C, opt.es.sm.C)
    _steps(again, 10)  # and it carries on learning from there
    assert again.best_f <= opt.best_f


@pytest.fixture
def short_task(tmp_path):
    return write_short_task(tmp_path, horizon=0.5, nodes=4)


def _config(task, optimizer="cmaes", budget=50):
    return LearnConfig(
        animal="shark", task=str(task), optimizer=optimizer, budget=budget, seed=5, popsize=8
    )


def test_budget_is_an_upper_bound(tmp_path, short_task):
    run = Run.create(tmp_path / "r", _config(short_task, budget=50)).learn()
    assert run.evaluations == 50 and run.log.batches[-1] == 2  # 6 x 8 + 2
    resumed = Run.resume(tmp_path / "r")
    assert resumed.evaluations == 50
    resumed.learn()
    assert resumed.evaluations == 50


def test_interrupt_inside_a_step_resumes_to_the_same_history(tmp_path, short_task):
    whole = Run.create(tmp_path / "whole", _config(short_task, "anneal", 30)).learn()
    cut = Run.create(tmp_path / "cut", _config(short_task, "anneal", 30))
    calls = {"n": 0}
    evaluate = cut.setup.objective.evaluate

    def flaky(X):
        calls["n"] += 1
        if calls["n"] == 12:
            raise KeyboardInterrupt  # Ctrl-C while simulating: the step never finished
        return evaluate(X)

    cut.setup.objective.evaluate = flaky
    with pytest.raises(KeyboardInterrupt):
        cut.learn()
    resumed = Run.resume(tmp_path / "cut")
    assert resumed.evaluations == 11
    resumed.learn()
    assert resumed.log.E == whole.log.E


def test_a_damaged_checkpoint_says_so_and_offers_the_previous_one(tmp_path, short_task):
    run = Run.create(tmp_path / "r", _config(short_task, "anneal", 6))
    run.learn(every_s=0.0)
    assert (tmp_path / "r" / PREVIOUS).exists()
    data = bytearray((tmp_path / "r" / CHECKPOINT).read_bytes())
    data[len(data) // 2] ^= 0xFF
    (tmp_path / "r" / CHECKPOINT).write_bytes(bytes(data))
    with pytest.raises(RunDirError, match=r"damaged checkpoint.*checkpoint.prev.npz.*afresh"):
        Run.resume(tmp_path / "r")
    (tmp_path / "r" / CHECKPOINT).unlink()  # as if killed between the two writes
    assert Run.resume(tmp_path / "r").evaluations == 5
    (tmp_path / "r" / PREVIOUS).replace(tmp_path / "r" / CHECKPOINT)
    assert Run.resume(tmp_path / "r").evaluations == 5
    np.savez(tmp_path / "r" / CHECKPOINT, X=np.zeros((2, 3)), E=np.zeros(2))  # an old format
    with pytest.raises(RunDirError, match="older zoetic that saved no optimizer state"):
        Run.resume(tmp_path / "r")


def _history_E(path):
    lines = path.read_text().splitlines()[1:]
    return [line.split(",")[1] for line in lines]


@pytest.mark.slow
def test_sigkill_during_learning_then_resume_gives_the_same_history(tmp_path, short_task):
    whole = Run.create(tmp_path / "whole", _config(short_task, "anneal", 60)).learn()
    out = tmp_path / "killed"
    cmd = [
        sys.executable,
        "-m",
        "zoetic",
        "learn",
        "shark",
        "--task",
        str(short_task),
        "--optimizer",
        "anneal",
        "--budget",
        "60",
        "--seed",
        "5",
        "--popsize",
        "8",
        "--checkpoint-every",
        "0",
        "--no-video",
        "--out",
        str(out),
    ]
    env = os.environ | {"COLUMNS": "200"}
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            if (out / "history.csv").exists() and len(_history_E(out / "history.csv")) >= 5:
                break
            time.sleep(0.01)
        assert proc.poll() is None, "the run finished before it could be killed"
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait()
    assert proc.returncode == -signal.SIGKILL
    done = len(_history_E(out / "history.csv"))
    assert 5 <= done < 60
    from zoetic.cli import main  # the same entry point, in this process (imports are warm)

    assert main(["learn", "--resume", str(out), "--no-video"]) == 0
    assert _history_E(out / "history.csv") == _history_E(tmp_path / "whole" / "history.csv")
    assert len(whole.log.E) == 60


def test_cmaes_draws_what_plain_cma_draws():
    import cma

    opt = _make("cmaes")
    es = cma.CMAEvolutionStrategy(
        list(np.full(5, 0.9)),
        0.3,
        {
            "bounds": [[0.0] * 5, [1.0] * 5],
            "seed": 5,
            "verbose": -9,
            "CMA_stds": [1.0] * 5,
            "popsize": 6,
        },
    )
    for _ in range(3):
        X, Y = opt.ask(), np.array(es.ask())
        assert np.array_equal(X, Y)
        opt.tell(X, _f(X))
        es.tell(list(Y), list(_f(Y)))
