"""No silent NaN, no surprises with names, nothing deleted: the time-step bound, blow-ups,
zoo names against folders, ``demo --out`` and the reader's limits."""

from __future__ import annotations

import os

import numpy as np
import pytest

from zoetic.bodies import list_animals, load_animal
from zoetic.cli import main
from zoetic.control import wave_controller
from zoetic.errors import BlowUpError, SimulationError
from zoetic.physics.simulate import check_dt, simulate, stable_dt


@pytest.mark.parametrize("name", list_animals())
def test_the_animals_own_dt_is_accepted_and_a_dt_above_the_bound_refused(name):
    body = load_animal(name)
    limit = stable_dt(body)
    assert body.dt <= limit
    assert check_dt(body, body.dt) == body.dt
    with pytest.raises(SimulationError, match="too large") as info:
        check_dt(body, 1.05 * limit, where="--dt")
    assert name in str(info.value) and "--dt" in str(info.value)


@pytest.mark.parametrize("name", list_animals())
def test_just_under_the_bound_the_gait_runs(name):
    """The bound is safe: just under it the wave gait runs for 3 s without failing. (Above
    it the multirate step sub-steps more springs, so the bound is conservative there.)"""
    body = load_animal(name)
    dt = 0.95 * stable_dt(body)
    steps = int(3.0 / dt)
    tr = simulate(body, wave_controller(body).table(steps, dt), dt=dt, check_step=False)
    assert not tr.failed[0]


def test_the_bound_follows_the_stiffest_spring_and_lightest_node():
    """dt^2 K/m + 2 dt C/m < 4: four times the stiffness (twice the damping) or a quarter
    of the mass (half the damping) halves the step; the floor is absent in water."""
    from dataclasses import replace

    body = load_animal("shark")
    body = replace(body, dt=body.dt / 8)  # a step at which no spring needs sub-stepping
    half = stable_dt(body) / 2
    stiffer = replace(body, stiffness=body.stiffness * 4, spring_damping=body.spring_damping * 2)
    lighter = replace(body, mass=body.mass / 4, spring_damping=body.spring_damping / 2)
    assert stable_dt(stiffer) == pytest.approx(half, rel=1e-4)
    assert stable_dt(lighter) == pytest.approx(half, rel=1e-4)


def test_simulate_refuses_a_large_dt_and_its_suggestion_works(tmp_path, capsys):
    body = load_animal("shark")
    dt = 2 * stable_dt(body)
    out = tmp_path / "o"
    assert main(["simulate", "shark", "--dt", str(dt), "--seconds", "0.5", "--no-video",
                 "--out", str(out)]) == 2  # fmt: skip
    err = capsys.readouterr().err
    assert "--dt" in err and "shark" in err and "nan" not in err and not out.exists()
    good = err.split("use dt <= ")[1].split(" s")[0]
    assert main(["simulate", "shark", "--dt", good, "--seconds", "0.5", "--no-video",
                 "--out", str(out)]) == 0  # fmt: skip
    assert "distance_m" in capsys.readouterr().out


def test_a_blow_up_that_gets_past_the_check_exits_3_naming_step_animal_and_dt(
    tmp_path, capsys, monkeypatch
):
    import importlib

    sim = importlib.import_module("zoetic.physics.simulate")  # the module, not the function
    monkeypatch.setattr(sim, "_stable_cached", lambda body, med: 1.0)  # a wrong bound
    import weakref

    from zoetic.physics import model, multirate

    def no_split(body, dt):  # and no sub-stepping of the stiff springs either
        every, nodes = np.arange(body.n_springs), np.arange(body.n_nodes)
        return multirate.Split(every, every[:0], 1, nodes, nodes[:0])

    monkeypatch.setattr(model, "split", no_split)
    monkeypatch.setattr(model, "_MODELS", weakref.WeakKeyDictionary())  # none built before
    code = main(["simulate", "shark", "--dt", "0.05", "--seconds", "2", "--no-video",
                 "--out", str(tmp_path / "o")])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 3 and BlowUpError.exit_code == 3
    assert "blew up at step" in err and "shark" in err and "--dt" in err
    assert "Traceback" not in err


def test_too_long_a_simulation_is_refused_before_it_starts(tmp_path, capsys):
    code = main(["simulate", "shark", "--seconds", "200000", "--no-video",
                 "--out", str(tmp_path / "o")])  # fmt: skip
    assert code == 2 and "--seconds" in capsys.readouterr().err


def test_a_folder_named_like_a_zoo_entry_does_not_hide_it(tmp_path, monkeypatch, capsys):
    from zoetic.san import load_creature

    monkeypatch.chdir(tmp_path)
    for name in ("shark", "cart", "shark.toml"):
        (tmp_path / name).mkdir()
    assert load_animal("shark").name == "shark"
    assert load_creature("cart").name == "cart"
    assert main(["simulate", "./shark", "--no-video", "--seconds", "0.1"]) == 2
    assert "is a directory" in capsys.readouterr().err
    with pytest.raises(SimulationError.__mro__[1], match="no such creature file"):
        load_creature("./cart.toml")


def test_a_file_is_used_when_written_as_a_path(tmp_path, monkeypatch):
    from zoetic.bodies import ZOO_DIR

    monkeypatch.chdir(tmp_path)
    text = (ZOO_DIR / "shark.toml").read_text().replace('name = "shark"', 'name = "myshark"', 1)
    (tmp_path / "shark.toml").write_text(text)
    assert load_animal("shark").name == "shark"  # the zoo
    assert load_animal("shark.toml").name == "myshark"  # the file
    assert load_animal("./shark.toml").name == "myshark"


def test_demo_never_deletes_what_it_did_not_make(tmp_path, capsys):
    out = tmp_path / "d"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    argv = ["demo", "--out", str(out), "--budget", "16", "--no-video"]
    assert main(argv) == 0
    made = set(os.listdir(out))
    assert {"notes.txt", "checkpoint.npz", ".zoetic-demo"} <= made
    assert main(argv) == 0  # again: it replaces its own files only
    assert (out / "notes.txt").read_text() == "mine"
    other = tmp_path / "learned"
    other.mkdir()
    (other / "checkpoint.npz").write_bytes(b"a run made by zoetic learn")
    (other / "config.toml").write_text("[run]\n")
    capsys.readouterr()
    assert main(["demo", "--out", str(other), "--budget", "16", "--no-video"]) == 2
    assert "did not make" in capsys.readouterr().err
    assert (other / "checkpoint.npz").read_bytes() == b"a run made by zoetic learn"


def test_learn_options_are_checked_with_suggestions(tmp_path, capsys):
    code = main(["learn", "shark", "--optimizer", "cmaess", "--out", str(tmp_path / "r")])
    err = capsys.readouterr().err
    assert code == 2 and "did you mean 'cmaes'" in err and not (tmp_path / "r").exists()


def test_an_edited_run_config_names_the_run_directory(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["learn", "shark", "--optimizer", "cmaes", "--budget", "24", "--nodes", "4",
                 "--no-video", "--out", str(out)]) == 0  # fmt: skip
    cfg = out / "config.toml"
    cfg.write_text(cfg.read_text().replace("seed = 0", "seed = 7"))
    capsys.readouterr()
    assert main(["learn", "--resume", str(out), "--no-video"]) == 2
    err = capsys.readouterr().err
    assert str(out) in err and "edited" in err


def test_messages_abbreviate_long_values():
    from zoetic.io import abbrev, numbers

    assert len(abbrev(list(range(2_000_000)))) < 80
    with pytest.raises(Exception) as info:
        numbers(["x"] * 10 + list(range(300_000)), "f.json: values")
    assert len(str(info.value)) < 200


def test_reader_refuses_deep_nesting_and_oversized_files(tmp_path):
    from zoetic.errors import ZoeticError
    from zoetic.io import LIMITS, load_json

    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000 + "]" * 100_000)  # deeper than Python's recursion limit
    with pytest.raises(ZoeticError, match="deep"):
        load_json(deep)
    big = tmp_path / "big.json"
    with open(big, "wb") as fh:
        fh.truncate(LIMITS.file_bytes + 1)
    with pytest.raises(ZoeticError, match="too large"):
        load_json(big)


def test_nan_never_reaches_a_summary(tmp_path, capsys, monkeypatch):
    """Even a NaN the kernel did not flag ends in an error (exit 3), not in distance_m: nan."""
    import zoetic.control.rollout as rollout_module

    real = rollout_module.rollout

    def poisoned(*args, **kwargs):
        result = real(*args, **kwargs)
        result.positions[0][0, -1, 0, 0] = np.nan
        return result

    monkeypatch.setattr(rollout_module, "rollout", poisoned)
    code = main(["simulate", "shark", "--seconds", "1", "--no-video", "--out", str(tmp_path)])
    captured = capsys.readouterr()
    assert code == 3 and "distance_m" not in captured.out and "blew up" in captured.err


def test_an_animal_without_actuators_is_refused_before_learning(tmp_path, capsys):
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parents[1] / "scripts"))
    import make_bad_corpus as corpus

    text = corpus.ANIMAL.replace('actuators = [{ name = "m", side = "center" }]\n', "")
    text = text.replace('actuator = "m"\nmax_shortening = 0.2\n', "").split("[wave]")[0]
    path = tmp_path / "lump.toml"
    path.write_text(text.replace('name = "tri"', 'name = "shark"'))
    assert load_animal(str(path)).n_actuators == 0  # a passive body is a valid animal
    code = main(["learn", str(path), "--out", str(tmp_path / "r"), "--no-video"])
    err = capsys.readouterr().err
    assert code == 2 and "no actuators" in err and str(path) in err


def test_an_output_path_that_is_a_file_is_an_error_not_a_traceback(tmp_path, capsys):
    afile = tmp_path / "afile"
    afile.write_text("keep me")
    for out in (afile, afile / "sub"):
        code = main(["simulate", "shark", "--seconds", "0.1", "--no-video", "--out", str(out)])
        err = capsys.readouterr().err
        assert code == 2 and str(out) in err and "Traceback" not in err
        code = main(["learn", "shark", "--budget", "20", "--no-video", "--out", str(out)])
        err = capsys.readouterr().err
        assert code == 2 and str(afile) in err and "Traceback" not in err
    assert afile.read_text() == "keep me"


def test_learning_says_how_many_candidates_failed_and_refuses_an_all_failed_run(tmp_path, capsys):
    from types import SimpleNamespace

    from zoetic.runs import finish_run

    dead = SimpleNamespace(out=tmp_path, log=SimpleNamespace(E=[np.inf] * 5))
    with pytest.raises(BlowUpError, match="every one of the 5 candidates"):
        finish_run(dead)
    out = tmp_path / "r"
    assert main(["learn", "shark", "--budget", "8", "--popsize", "4", "--no-video",
                 "--out", str(out)]) == 0  # fmt: skip
    assert "failed_candidates: 0" in capsys.readouterr().out.replace("  ", "")
