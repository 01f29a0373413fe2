"""Learning that ends early or starts from a known gait: the plateau stop and the wave start."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import write_short_task
from zoetic.bodies import load_animal
from zoetic.cli import main
from zoetic.control import wave_controller
from zoetic.errors import RunDirError, ZoeticError
from zoetic.io import read_toml, write_toml
from zoetic.learning.checks import check_learn_config
from zoetic.learning.optimizers import make_optimizer
from zoetic.learning.optimizers.base import plateaued
from zoetic.learning.run import START_FILE, LearnConfig, Run, build


@pytest.fixture
def short_task(tmp_path):
    return write_short_task(tmp_path, horizon=1.0, nodes=5)


def test_plateau_rule_counts_the_improvement_over_the_last_generations():
    improving = [-1.0 - 0.1 * g for g in range(30)]  # 0.1 a generation, about 3 % of |E|
    assert not any(plateaued(improving[: g + 1], 5, 0.01) for g in range(30))
    flat = improving[:10] + [improving[9]] * 5  # no better E for the last 5 generations
    assert plateaued(flat, 5, 0.0) and not plateaued(flat[:-1], 5, 0.0)
    assert plateaued(improving, 5, 0.2) and not plateaued(improving, 5, 0.1)
    assert not plateaued([np.inf] * 10, 5, 0.5)  # nothing finite yet: not a plateau


def _cmaes(f, plateau, budget=4000, n=6):
    """Run CMA-ES on ``f`` to the budget or its stop; return the optimizer."""
    lo, hi = -np.ones(n), np.ones(n)
    opt = make_optimizer("cmaes", np.full(n, 0.8), lo, hi, seed=1, budget=budget, popsize=8)
    opt.plateau = plateau
    while opt.evaluations < budget and not opt.done():
        X = opt.ask()
        opt.tell(X, f(X))
    return opt


def test_plateau_stop_ends_a_converged_search_and_not_an_improving_one():
    # a bowl with a flat floor: once the floor is reached nothing is better
    def floored(X):
        return np.maximum((X**2).sum(axis=1), 0.05)

    def bowl(X):
        return (X**2).sum(axis=1)

    stopped = _cmaes(floored, (15, 1e-3))
    assert stopped.evaluations < 4000 and stopped.best_f == pytest.approx(0.05)
    assert stopped.bests[-16] - stopped.bests[-1] <= 1e-3 * 0.05  # flat for 15 generations
    assert not plateaued(stopped.bests[:-1], 15, 1e-3)  # and stopped the first time it was
    improving = _cmaes(bowl, (15, 1e-3), budget=400)  # still descending: runs to the budget
    assert improving.evaluations == 400 and not improving.done()
    assert improving.bests[-1] < 1e-2 * improving.bests[0]


def test_a_run_with_a_plateau_stop_ends_early_and_resumes_to_the_same_result(tmp_path, short_task):
    config = LearnConfig(
        task=str(short_task),
        budget=2000,
        seed=2,
        popsize=8,
        stop_generations=3,
        stop_improvement=0.05,
    )
    whole = Run.create(tmp_path / "whole", config).learn()
    assert whole.evaluations < 2000 and whole.setup.optimizer.done()
    assert plateaued(whole.setup.optimizer.bests, 3, 0.05)
    cut = Run.create(tmp_path / "cut", config)

    def interrupt(r):
        if r.evaluations >= whole.evaluations // 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        cut.learn(progress=interrupt)
    resumed = Run.resume(tmp_path / "cut").learn()
    assert resumed.log.E == whole.log.E  # stopped at the same generation, same history
    doc = read_toml(tmp_path / "whole" / "config.toml")
    assert doc["run"]["stop_generations"] == 3 and doc["run"]["stop_improvement"] == 0.05


@pytest.mark.parametrize(
    "bad, message",
    [
        ({"stop_generations": 0, "stop_improvement": 0.01}, "stop_generations must be at least 1"),
        ({"stop_generations": 5, "stop_improvement": -0.1}, "stop_improvement must be at least 0"),
        ({"stop_generations": 5, "stop_improvement": 2.0}, "stop_improvement must be at most 1"),
        ({"stop_generations": 5}, "stop_generations needs stop_improvement"),
        ({"stop_improvement": 0.01}, "stop_improvement needs stop_generations"),
        ({"start": "handmade"}, "start: unknown value .*random, wave, stored"),
    ],
)
def test_stop_and_start_settings_are_checked(bad, message):
    with pytest.raises(RunDirError, match=message):
        check_learn_config({"animal": "shark", **bad}, "config.toml: [run]")


def test_bad_stop_settings_exit_2_naming_the_setting(tmp_path, short_task, capsys):
    out = tmp_path / "r"
    args = ["learn", "shark", "--task", str(short_task), "--budget", "8", "--no-video"]
    assert main([*args, "--out", str(out), "--stop-generations", "4"]) == 2
    assert "stop_generations needs stop_improvement" in capsys.readouterr().err
    assert main([*args, "--out", str(out), "--start", "nowhere"]) == 2
    err = capsys.readouterr().err
    assert "unknown value 'nowhere'" in err and "random, wave, stored" in err
    assert main([*args, "--out", str(out), "--popsize", "4"]) == 0
    doc = read_toml(out / "config.toml")
    doc["run"] |= {"stop_generations": 3, "stop_improvement": -1.0}  # an edited config.toml
    write_toml(out / "config.toml", doc)
    assert main(["learn", "--resume", str(out), "--no-video"]) == 2
    err = capsys.readouterr().err
    assert "stop_improvement must be at least 0" in err and "config.toml" in err
    assert "Traceback" not in err


def test_a_stored_start_is_kept_in_the_run_and_read_back_on_resume(tmp_path, short_task):
    shark = load_animal("shark")
    wave = wave_controller(shark)
    config = LearnConfig(task=str(short_task), budget=16, popsize=8, start="stored")
    with pytest.raises(ZoeticError, match="needs the gait to start from"):
        build(config, body=shark)
    run = Run.create(tmp_path / "r", config, shark, start=wave)
    assert (tmp_path / "r" / START_FILE).exists()
    obj = run.setup.objective
    assert np.allclose(obj.tables(run.setup.optimizer.x0[None])[0], wave.table(obj.steps, obj.dt))
    resumed = Run.resume(tmp_path / "r")
    assert np.array_equal(resumed.setup.optimizer.x0, run.setup.optimizer.x0)


def test_wave_start_plays_the_animals_own_wave(short_task):
    setup = build(LearnConfig(task="swim-straight", start="wave", popsize=8))
    obj = setup.objective
    wave = wave_controller(obj.body).table(obj.steps, obj.dt)
    assert np.allclose(obj.tables(setup.optimizer.x0[None])[0], wave, atol=1e-6)
    random = build(LearnConfig(task="swim-straight", popsize=8)).optimizer.x0
    assert not np.allclose(random, setup.optimizer.x0)
    # the same start whatever the seed: the seed draws only the search's samples
    other = build(LearnConfig(task="swim-straight", start="wave", seed=5, popsize=8))
    assert np.array_equal(other.optimizer.x0, setup.optimizer.x0)
