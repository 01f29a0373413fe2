"""Basic training into a repertoire, its files, and the commands that use it."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys

import numpy as np
import pytest

from zoetic.behavior.handmade import handmade_repertoire
from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.training import build_sequence, parse_sequence, plan_for
from zoetic.bodies import load_animal
from zoetic.cli import main
from zoetic.control import load_controller
from zoetic.control.abstract import AbstractController, SequenceController
from zoetic.errors import ZoeticError


@pytest.fixture(scope="module")
def shark():
    return load_animal("shark")


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    out = tmp_path_factory.mktemp("memory") / "shark"
    code = main(["repertoire", "train", "shark", "--out", str(out), "--budget", "30"])
    assert code == 0
    return out


def test_plans_follow_the_medium():
    assert [e.name for e in plan_for(load_animal("shark"))] == [
        "go-straight",
        "sharp-turn-left",
        "wide-turn-left",
        "swim-up",
        "swim-down",
    ]
    snake = plan_for(load_animal("snake"))
    assert snake[0].task.name == "crawl-straight"
    dolphin = plan_for(load_animal("dolphin"))  # the five basic motor tasks (right: mirrored)
    assert [e.name for e in dolphin] == [
        "move-forward",
        "turn-down",
        "turn-up",
        "turn-left",
        "sprint",
    ]
    assert all(e.task.start.speed == 0.0 and e.task.starts[1].speed == "cruise" for e in dolphin)


def test_training_writes_a_reloadable_mirrored_repertoire(trained, shark):
    rep = Repertoire.load(trained, shark)
    assert rep.names == [
        "do-nothing",
        "go-straight",
        "sharp-turn-left",
        "sharp-turn-right",
        "wide-turn-left",
        "wide-turn-right",
        "swim-up",
        "swim-down",
    ]
    assert all(isinstance(c, AbstractController) for c in rep.controllers.values())
    t = np.linspace(0, 3, 50)
    left, right = rep.controllers["sharp-turn-left"], rep.controllers["sharp-turn-right"]
    np.testing.assert_allclose(right.raw(t), left.raw(t)[:, shark.actuator_mirror])
    info = rep.info["go-straight"]
    assert info["task"] == "swim-straight" and 0 < max(info["modes_per_actuator"])
    assert (trained / "runs" / "go-straight" / "controller.json").exists()
    # do nothing: muscles relaxed, fins held level
    assert np.all(rep.controllers["do-nothing"].raw(t) == np.nan_to_num(shark.wave_held))


def test_trainings_figure_is_the_one_show_draws(trained):
    """repertoire.png as training's figure process drew it is the one ``repertoire show``
    draws in its own process, byte for byte."""
    trained_png = (trained / "repertoire.png").read_bytes()
    assert main(["repertoire", "show", str(trained)]) == 0
    assert (trained / "repertoire.png").read_bytes() == trained_png


def test_training_again_resumes_without_learning_more(trained):
    before = (trained / "runs" / "go-straight" / "history.csv").read_text()
    args = ["repertoire", "train", "shark", "--out", str(trained), "--resume"]
    assert main(args) == 0  # its budget of 30 is spent: nothing more is learned
    assert (trained / "runs" / "go-straight" / "history.csv").read_text() == before


def test_a_trained_directory_is_refused_without_resume_or_force(trained, capsys):
    capsys.readouterr()
    args = ["repertoire", "train", "shark", "--out", str(trained), "--budget", "30"]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "--resume" in err and "--force" in err and "Traceback" not in err
    assert main([*args, "--resume", "--force"]) == 2


def test_resume_takes_a_new_budget_and_force_starts_again(tmp_path):
    out = tmp_path / "m"
    assert main(["repertoire", "train", "shark", "--out", str(out), "--budget", "12"]) == 0
    runs = out / "runs" / "go-straight"
    learned = len((runs / "history.csv").read_text().splitlines())
    assert (
        main(["repertoire", "train", "shark", "--out", str(out), "--resume", "--budget", "24"]) == 0
    )
    assert len((runs / "history.csv").read_text().splitlines()) > learned  # learned on
    assert "budget = 24" in (runs / "config.toml").read_text()
    assert (
        main(["repertoire", "train", "shark", "--out", str(out), "--force", "--budget", "12"]) == 0
    )
    assert "budget = 12" in (runs / "config.toml").read_text()
    assert main(["repertoire", "train", "shark", "--out", str(tmp_path / "new"), "--resume"]) == 2


def test_an_entry_learned_for_an_older_task_is_not_resumed(tmp_path, capsys):
    import shutil

    from zoetic.io import read_toml, write_toml

    out = tmp_path / "m"
    assert main(["repertoire", "train", "shark", "--out", str(out), "--budget", "12"]) == 0
    stale = tmp_path / "stale"
    shutil.copytree(out, stale)
    cfg = stale / "runs" / "sharp-turn-left" / "config.toml"
    doc = read_toml(cfg)
    doc["task"]["terms"][0]["target"] = 1.0  # as if learned before the task file changed
    write_toml(cfg, doc)
    capsys.readouterr()
    assert main(["repertoire", "train", "shark", "--out", str(stale), "--resume"]) == 2
    err = capsys.readouterr().err
    assert "config.toml" in err and "quick-turn-left" in err and "fresh --out" in err


def test_the_plan_digest_changes_with_the_body_or_a_task(tmp_path):
    import shutil

    from zoetic.behavior.training import plan_digest
    from zoetic.bodies import ZOO_DIR

    assert plan_digest("shark") == plan_digest("shark")
    assert plan_digest("shark") != plan_digest("ray")
    mine = tmp_path / "shark.toml"
    shutil.copy(ZOO_DIR / "shark.toml", mine)
    copy_digest = plan_digest(str(mine))
    mine.write_text(mine.read_text().replace('name = "shark"', 'name = "shark2"', 1))
    assert plan_digest(str(mine)) != copy_digest


def test_repertoire_round_trip(tmp_path, shark):
    rep = handmade_repertoire(shark)
    rep.add("extra", rep.controllers["go-straight"], 2.5, note="kept", kept=0.9)
    rep.save(tmp_path / "m")
    again = Repertoire.load(tmp_path / "m", shark)
    assert again.names == rep.names and again.durations == rep.durations
    assert again.info["extra"] == {"note": "kept", "kept": 0.9}
    t = np.linspace(0, 4, 40)
    for name in rep.names:
        np.testing.assert_allclose(
            again.controllers[name].raw(t), rep.controllers[name].raw(t), atol=1e-5
        )


def test_show_prints_and_plots(trained, capsys):
    assert main(["repertoire", "show", str(trained), "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    by = {r["entry"]: r for r in rows}
    assert by["do-nothing"]["modes"] == 0 and by["do-nothing"]["forward_m"] == pytest.approx(0)
    assert by["sharp-turn-right"]["turn_deg"] == pytest.approx(
        -by["sharp-turn-left"]["turn_deg"], abs=0.2
    )
    assert (trained / "repertoire.png").stat().st_size > 10_000


def test_broken_repertoire_is_refused_with_its_file_named(tmp_path, shark, capsys):
    handmade_repertoire(shark).save(tmp_path / "m")
    (tmp_path / "m" / "go-straight.json").write_text('{"type": "abstract", "animal": "shark"')
    assert main(["repertoire", "show", str(tmp_path / "m")]) == 2
    err = capsys.readouterr().err
    assert "go-straight" in err and "repertoire.json" in err
    assert main(["repertoire", "show", str(tmp_path / "nothing")]) == 2
    assert "not a zoetic repertoire" in capsys.readouterr().err


def test_abstract_command_on_a_learned_run(trained, tmp_path, capsys):
    run = trained / "runs" / "wide-turn-left"
    assert main(["abstract", str(run), "--modes", "1", "--out", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert "kept" in printed and "heading_change" in printed
    ctrl = load_controller(tmp_path / "abstract.json", load_animal("shark"))
    assert isinstance(ctrl, AbstractController)
    assert np.count_nonzero(ctrl.amp, axis=1).max() == 1
    assert (tmp_path / "abstract.png").stat().st_size > 10_000
    assert main(["abstract", str(tmp_path / "none"), "--out", str(tmp_path)]) == 2
    assert main(["abstract", str(run), "--modes", "zero", "--out", str(tmp_path)]) == 2


def test_sequence_command_simulates_a_cross_faded_controller(tmp_path, capsys):
    shark = load_animal("shark")
    handmade_repertoire(shark).save(tmp_path / "m")
    args = [
        "sequence",
        "shark",
        "--memory",
        str(tmp_path / "m"),
        "--entries",
        "go-straight:2,sharp-turn-left:2",
        "--out",
        str(tmp_path / "s"),
        "--no-video",
    ]
    import zoetic.viz.plots

    with pytest.MonkeyPatch.context() as mp:  # path.png is drawn once, with the side view
        mp.setattr(zoetic.viz.plots, "plot_path", lambda *a, **k: pytest.fail("top view only"))
        assert main(args) == 0
    seq = load_controller(tmp_path / "s" / "sequence.json", shark)
    assert isinstance(seq, SequenceController)
    assert seq.duration == pytest.approx(2 + 2 * 0.95)
    assert (tmp_path / "s" / "path.png").exists() and (tmp_path / "s" / "record.npz").exists()
    from PIL import Image

    w, h = Image.open(tmp_path / "s" / "path.png").size
    assert w > 2 * h  # the top view beside the side view of the depth
    args[5] = "go-straight:2,backflip"
    assert main(args) == 2
    assert "no entry 'backflip'" in capsys.readouterr().err


def test_parse_sequence_defaults_and_errors(shark):
    rep = handmade_repertoire(shark)
    items = parse_sequence("go-straight, wide-turn-left:1.5", rep)
    assert items == [("go-straight", rep.durations["go-straight"]), ("wide-turn-left", 1.5)]
    assert build_sequence(rep, items).duration > 1.5
    for bad in ("", "go-straight:-1", "go-straight:abc"):
        with pytest.raises(ZoeticError):
            parse_sequence(bad, rep)


def _judged_memory(tmp_path, shark, promise: str):
    """A hand-made repertoire whose go-straight claims a task promising ``promise``."""
    tmp_path.mkdir(parents=True, exist_ok=True)
    task = tmp_path / "claim.toml"
    task.write_text(
        'name = "claim"\nrequires = ["water"]\nhorizon = 2.0\n'
        '[[terms]]\nkind = "distance_along_heading"\nweight = -1.0\n'
        f"[promise]\n{promise}\n"
    )
    rep = handmade_repertoire(shark)
    memory = tmp_path / "memory"
    rep.add("go-straight", rep.controllers["go-straight"], 2.0, task=str(task))
    rep.save(memory)
    return memory


def test_show_flags_an_entry_that_breaks_its_promise_and_strict_exits_1(tmp_path, shark, capsys):
    # the hand-made go-straight turns less than 15 degrees in 2 s, not past 90
    broken = _judged_memory(tmp_path / "a", shark, "turn_deg = [90.0, inf]")
    assert main(["repertoire", "show", str(broken)]) == 0  # a warning, not a failure
    text = capsys.readouterr().out.replace("\n", " ")
    assert "'go-straight' does not do what task 'claim' promises" in text
    assert "turn_deg >= 90" in text
    assert main(["repertoire", "show", str(broken), "--strict"]) == 1
    kept = _judged_memory(tmp_path / "b", shark, "turn_deg = [-15.0, 15.0]")
    assert main(["repertoire", "show", str(kept), "--strict"]) == 0
    assert "keeps its task's promises" in capsys.readouterr().out
    assert main(["repertoire", "show", str(broken), "--json", "--strict"]) == 1
    rows = json.loads(capsys.readouterr().out)
    row = next(r for r in rows if r["entry"] == "go-straight")
    assert row["promise"]["met"] is False and row["promise"]["promises"][0]["worst"] < 90


def test_trainings_report_writes_the_figure_before_strict_exits_1(tmp_path, shark):
    """repertoire train's report under --strict: an entry that breaks its promise exits 1,
    and repertoire.png, drawn by the figure process meanwhile, is written all the same."""
    from zoetic.behavior.promises import PromiseError
    from zoetic.cli.repertoire import _report_trained
    from zoetic.viz.drawer import Drawer

    broken = _judged_memory(tmp_path / "a", shark, "turn_deg = [90.0, inf]")
    with Drawer() as drawer, pytest.raises(PromiseError) as exited:
        _report_trained(broken, True, drawer)
    assert exited.value.exit_code == 1
    assert (broken / "repertoire.png").stat().st_size > 10_000


def test_a_promise_must_be_a_known_quantity_and_a_range(tmp_path):
    from zoetic.errors import TaskError
    from zoetic.tasks import load_task

    assert {p.quantity for p in load_task("quick-turn-left").promises} >= {"turn_deg", "roll_deg"}
    base = 'name = "x"\nhorizon = 1.0\n[[terms]]\nkind = "effort"\n[promise]\n'
    for bad, words in (("turn = [1, 2]", "turn"), ("turn_deg = [2, 1]", "low <= high")):
        f = tmp_path / "bad.toml"
        f.write_text(base + bad + "\n")
        with pytest.raises(TaskError, match=words):
            load_task(f)


def test_the_abstraction_keeps_a_weak_mode_when_the_promise_needs_it(tmp_path, shark):
    """A weak mode below the auto threshold that the promised motion depends on is kept: the
    training steps the threshold down (FALLBACK_THRESHOLDS) rather than keep a broken entry."""
    from zoetic.behavior.promises import entry_motion, judge_entry
    from zoetic.behavior.training import abstract_keeping_promises
    from zoetic.tasks import load_task

    muscles = np.array([kind == "muscle" for kind in shark.actuator_kind])
    phase = -2 * np.pi * np.nan_to_num(np.asarray(shark.wave_phase, float))
    f = shark.wave_frequency
    freq = np.tile([f, 2 * f], (shark.n_actuators, 1))
    amp = np.where(muscles[:, None], [0.5, 0.12], 0.0)  # the second mode 0.24 x the first
    gait = AbstractController(
        "shark",
        shark.actuator_names,
        np.full(shark.n_actuators, 0.5),
        freq,
        amp,
        np.stack([phase, 2 * phase], axis=1),
        1.0 / f,
    )
    path = tmp_path / "swim.toml"
    task_text = (
        'name = "swim"\nrequires = ["water"]\nhorizon = 1.5\n'
        '[[terms]]\nkind = "effort"\nweight = 1.0\n'
    )
    path.write_text(task_text)
    plain = dataclasses.replace(gait, amp=np.where(muscles[:, None], [0.5, 0.0], 0.0))
    task = load_task(path)
    full, weak = (entry_motion(shark, c, task)[0]["speed_bl_s"] for c in (gait, plain))
    assert abs(full - weak) > 0.01  # the weak mode changes how fast it swims
    low, high = ((full + weak) / 2, "inf") if full > weak else (0.0, (full + weak) / 2)
    path.write_text(task_text + f"[promise]\nspeed_bl_s = [{low}, {high}]\n")
    task = load_task(path)
    ab = abstract_keeping_promises(shark, gait, task, "auto", 0.3)
    assert ab.rule == "auto (threshold 0.1)" and ab.modes_per_actuator().max() == 2
    assert judge_entry(shark, ab.controller, task)["met"]
    # the default abstraction drops the mode and breaks the promise; a rule of K modes is kept
    assert not judge_entry(
        shark, abstract_keeping_promises(shark, gait, task, 1, 0.3).controller, task
    )["met"]


def test_repertoire_plot_is_drawn_without_pyplot(tmp_path):
    """The repertoire's figure is drawn on a canvas of its own: a fresh process writes it
    without importing pyplot (slow to import, and global state)."""
    code = (
        "import sys, numpy as np, pathlib\n"
        "from zoetic.viz.abstraction import plot_repertoire\n"
        "t = np.linspace(0.0, 1.0, 50)\n"
        "u = 0.5 + 0.5 * np.sin(np.outer(t, [6.0, 9.0]))\n"
        "path = np.c_[t, 0 * t, t**2]\n"
        f"out = pathlib.Path({str(tmp_path / 'rep.png')!r})\n"
        "plot_repertoire({'swim': (t, u)}, {'swim': path}, ('left', 'right'), out)\n"
        "print('matplotlib.pyplot' in sys.modules)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["False"]
    assert (tmp_path / "rep.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
