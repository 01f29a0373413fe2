"""A learning run learns the Body it is given, stores it, and resumes it as itself; the Python
API and the command line refuse the same runs with the same messages (learning.checks)."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

import zoetic
from conftest import write_short_task
from zoetic.cli import main
from zoetic.learning.evaluate import BatchEvaluator
from zoetic.learning.run import LearnConfig, Run
from zoetic.learning.stored_body import ANIMAL_FILE, body_digest, load_body

OPTIONS = {"optimizer": "cmaes", "budget": 16, "seed": 3, "popsize": 4, "controller": "periodic"}


@pytest.fixture(scope="module")
def short_task(tmp_path_factory):
    return write_short_task(tmp_path_factory.mktemp("task"), horizon=0.5, nodes=4)


@pytest.fixture(scope="module")
def heavy():
    shark = zoetic.load_animal("shark")
    return dataclasses.replace(shark, mass=shark.mass * 20)


def test_a_changed_body_is_learned_stored_and_resumed_as_itself(tmp_path, short_task, heavy):
    zoo = zoetic.learn("shark", str(short_task), out=tmp_path / "zoo", **OPTIONS)
    changed = zoetic.learn(heavy, str(short_task), out=tmp_path / "heavy", **OPTIONS)
    assert changed.best_E != zoo.best_E  # not the zoo shark under another name
    stored = load_body(tmp_path / "heavy" / ANIMAL_FILE)
    assert body_digest(stored) == body_digest(heavy)
    assert stored.total_mass == pytest.approx(20 * zoetic.load_animal("shark").total_mass)
    # interrupted after one batch, resumed from the run directory alone: the same history
    config = LearnConfig(animal="shark", task=str(short_task), **OPTIONS)
    cut = Run.create(tmp_path / "cut", config, heavy)
    cut.step(BatchEvaluator())
    cut.checkpoint()
    resumed = Run.resume(tmp_path / "cut")
    assert body_digest(resumed.setup.body) == body_digest(heavy)
    resumed.learn()
    assert resumed.log.E == changed.history.tolist()
    assert resumed.setup.optimizer.best_f == changed.best_E


def test_a_swapped_stored_animal_is_refused_on_resume(tmp_path, short_task, heavy):
    config = LearnConfig(animal="shark", task=str(short_task), **OPTIONS)
    run = Run.create(tmp_path / "r", config, heavy)
    run.step(BatchEvaluator())
    run.checkpoint()
    from zoetic.learning.stored_body import save_body

    save_body(zoetic.load_animal("shark"), tmp_path / "r" / ANIMAL_FILE)
    with pytest.raises(zoetic.ZoeticError, match="animal_sha256"):
        Run.resume(tmp_path / "r")


def test_the_cli_learns_an_animal_file_and_resumes_it_without_the_file(
    tmp_path, short_task, capsys
):
    text = Path(zoetic.load_animal("shark").source).read_text()
    heavy_text = re.sub(
        r"^mass = (\S+)$", lambda m: f"mass = {20 * float(m[1])!r}", text, flags=re.M
    )
    assert heavy_text != text
    path = tmp_path / "heavy_shark.toml"
    path.write_text(heavy_text)
    heavy_body = zoetic.load_animal(str(path))
    args = [
        "--task",
        str(short_task),
        "--optimizer",
        "cmaes",
        "--budget",
        "16",
        "--seed",
        "3",
        "--popsize",
        "4",
        "--no-video",
    ]
    assert main(["learn", str(path), *args, "--out", str(tmp_path / "heavy")]) == 0
    assert main(["learn", "shark", *args, "--out", str(tmp_path / "zoo")]) == 0
    out = capsys.readouterr().out
    best = [float(v) for v in re.findall(r"best_E: (\S+)", out)]
    assert len(best) == 2 and best[0] != best[1]
    path.unlink()  # the run keeps its own animal: the file is not needed to resume
    assert main(["learn", "--resume", str(tmp_path / "heavy"), "--no-video"]) == 0
    resumed = Run.resume(tmp_path / "heavy")
    assert body_digest(resumed.setup.body) == body_digest(heavy_body)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"optimizer": "cmaess"}, "did you mean 'cmaes'"),
        ({"interp": "spline"}, "interp"),
        ({"evaluator": "threads"}, "evaluator"),
        ({"medium": "vacuum"}, "cannot apply to the shark"),
    ],
)
def test_the_api_and_the_cli_refuse_the_same_runs_alike(tmp_path, capsys, options, message):
    with pytest.raises(zoetic.ZoeticError) as caught:
        zoetic.learn("shark", "swim-straight", out=tmp_path / "api", **options)
    assert message in str(caught.value)
    assert not (tmp_path / "api").exists()
    config = LearnConfig(animal="shark", **options)
    with pytest.raises(zoetic.ZoeticError) as again:
        Run.create(tmp_path / "lib", config)
    assert str(again.value) == str(caught.value)
    if "medium" in options:
        return  # the command line has no --medium; the library refuses it above
    flags = [f"--{k}={v}" for k, v in options.items()]
    assert main(["learn", "shark", *flags, "--no-video", "--out", str(tmp_path / "cli")]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert " ".join(str(caught.value).split()) in err
    assert not (tmp_path / "cli").exists()


def test_caches_key_by_the_body_not_its_name(tmp_path, heavy):
    """An edited body with the same name gets its own calibration, cruise speed and compiled
    file: a cache keyed by the name (and counts) would hand it the zoo shark's."""
    from zoetic.behavior.wave_motor import WaveMotor
    from zoetic.tasks import cruise_speed

    shark = zoetic.load_animal("shark")
    assert heavy.name == shark.name and heavy.n_nodes == shark.n_nodes
    zoo, edited = WaveMotor.calibrate(shark), WaveMotor.calibrate(heavy)
    assert edited is not zoo and edited.body is heavy
    assert not np.array_equal(edited.speeds, zoo.speeds)
    assert WaveMotor.calibrate(shark) is zoo  # and the same body is measured once
    assert cruise_speed(heavy, seconds=1.0) != cruise_speed(shark, seconds=1.0)
    path = tmp_path / "fish.toml"
    text = Path(shark.source).read_text()
    path.write_text(text)
    first = zoetic.load_animal(str(path))
    assert zoetic.load_animal(str(path)) is first
    path.write_text(text.replace("mass = 0.66", "mass = 0.7"))  # same name, same second
    assert zoetic.load_animal(str(path)).total_mass != first.total_mass
