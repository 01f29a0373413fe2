"""``zoetic repertoire train --pipeline paper``: the 1995 paper's learning, abstraction and use."""

from __future__ import annotations

import json

import numpy as np
import pytest

from zoetic.behavior.repertoire import Repertoire
from zoetic.bodies import load_animal
from zoetic.cli import main
from zoetic.control import TimeDomainController, load_controller
from zoetic.control.abstract import AbstractController
from zoetic.learning.abstraction import abstract, mirror_abstract, spectrum
from zoetic.learning.config import stroke_nodes
from zoetic.tasks import load_task

THRESHOLD = 0.9  # keeps one or a few modes per actuator of a freshly learned controller


@pytest.fixture(scope="module")
def paper(tmp_path_factory):
    out = tmp_path_factory.mktemp("memory") / "shark-paper"
    args = ["repertoire", "train", "shark", "--out", str(out), "--budget", "10"]
    args += ["--pipeline", "paper", "--optimizer", "simplex", "--threshold", str(THRESHOLD)]
    assert main(args) == 0
    return out


def test_entries_are_the_fft_abstractions_of_time_domain_controllers(paper):
    shark = load_animal("shark")
    rep = Repertoire.load(paper, shark)
    learned = [n for n in rep.names if "task" in rep.info[n]]
    assert learned == ["go-straight", "sharp-turn-left", "wide-turn-left", "swim-up", "swim-down"]
    for name in learned:
        info = rep.info[name]
        # the run it came from: its own, or a restart that kept more of its promises
        original = load_controller(paper / info["source"] / "controller.json", shark)
        task = load_task(info["task"])
        # learned from scratch in the time domain, M nodes a quarter of a stroke apart
        assert isinstance(original, TimeDomainController)
        assert original.nodes == stroke_nodes(shark.wave_frequency, task.horizon)
        # the entry is that controller's FFT abstraction at the threshold, not the original
        expected = abstract(original, "auto", THRESHOLD).controller
        entry = rep.controllers[name]
        assert isinstance(entry, AbstractController)
        for field in ("offset", "freq", "amp", "phase"):
            assert np.allclose(getattr(entry, field), getattr(expected, field), atol=1e-5)
        all_modes = int(np.count_nonzero(spectrum(original).amp >= 1e-3))
        assert 0 < entry.modes < all_modes / 4  # a few modes of the many the FFT finds
        assert info["pipeline"] == "paper" and info["optimizer"] == "simplex"
        assert info["modes_kept"] == entry.modes == sum(info["modes_per_actuator"])
        assert info["rule"] == f"auto (threshold {THRESHOLD:g})"
        o, a = info["original"]["distance"], info["abstract"]["distance"]
        assert info["distance_kept"] == pytest.approx(a / o, abs=1e-3)
    right = rep.controllers["sharp-turn-right"]
    mirrored = mirror_abstract(rep.controllers["sharp-turn-left"], shark.actuator_mirror)
    assert np.allclose(right.amp, mirrored.amp) and np.allclose(right.offset, mirrored.offset)


def test_show_and_track_use_the_paper_entries(paper, tmp_path, capsys):
    assert main(["repertoire", "show", str(paper), "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert {r["entry"] for r in rows} >= {"go-straight", "sharp-turn-right", "do-nothing"}
    out = tmp_path / "track"
    args = ["track", "shark", "--memory", str(paper), "--targets", "2,0.5;4,2", "--out", str(out)]
    assert main([*args, "--time-limit", "3", "--no-video"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    rep = Repertoire.load(paper)
    # the entries played (a fin-righting variant is named "entry+roll-left")
    assert summary["plan"] and all(p["entry"].split("+")[0] in rep.names for p in summary["plan"])
    assert summary["simulated_s"] >= 3.0 - 1e-9


def test_resuming_with_the_other_pipeline_is_refused(paper, capsys):
    before = (paper / "repertoire.json").read_text()
    assert main(["repertoire", "train", "shark", "--out", str(paper), "--resume"]) == 2
    err = capsys.readouterr().err
    assert "learned by --pipeline paper" in err and "config.toml" in err
    assert (paper / "repertoire.json").read_text() == before  # nothing was overwritten


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--pipeline", "paper", "--threshold", "0"], "--threshold must be in (0, 1]"),
        (["--pipeline", "paper", "--threshold", "1.5"], "--threshold must be in (0, 1]"),
        (["--pipeline", "paper", "--threshold", "nan"], "--threshold must be in (0, 1]"),
        (["--threshold", "-0.2"], "--threshold must be in (0, 1]"),
        (["--pipeline", "paper", "--optimizer", "cmaes"], "learns with anneal or simplex"),
        (["--pipeline", "paper", "--optimizer", "sgd"], "--optimizer must be one of"),
        (["--optimizer", "sgd"], "--optimizer must be one of"),
        (["--pipeline", "fft"], "--pipeline must be one of periodic, paper"),
    ],
)
def test_bad_pipeline_threshold_or_optimizer_exit_2(extra, message, tmp_path, capsys):
    out = tmp_path / "memory"
    assert main(["repertoire", "train", "shark", "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert not out.exists()  # refused before anything was learned or written


def test_the_fft_finds_the_stroke_in_nodal_values_and_says_what_it_kept():
    """A time-domain controller whose nodal values are a 5 Hz stroke plus a weaker 1 Hz sway:
    one mode per actuator is the stroke, at its amplitude, and the metadata counts it."""
    from zoetic.behavior.pipelines import paper_abstraction
    from zoetic.control import time_domain

    shark = load_animal("shark")
    task = load_task("swim-straight")
    m = stroke_nodes(shark.wave_frequency, task.horizon)
    t = np.linspace(0.0, task.horizon, m)
    lag = np.arange(shark.n_actuators)[:, None] * 0.1
    values = 0.5 + 0.4 * np.cos(2 * np.pi * (5.0 * t - lag)) + 0.05 * np.cos(2 * np.pi * t)
    ctrl = time_domain(shark, m, task.horizon, values)
    ab, info = paper_abstraction(shark, ctrl, task, 1, 0.3, "anneal")
    assert np.allclose(ab.controller.freq[:, 0], 5.0) and np.allclose(ab.controller.amp, 0.4)
    assert info["modes_kept"] == shark.n_actuators and info["rule"] == "1 strongest"
    assert info["frequencies_hz"] == [5.0] and info["learned_nodes"] == m
    both = paper_abstraction(shark, ctrl, task, "auto", 0.1, "anneal")[1]
    assert both["modes_kept"] == 2 * shark.n_actuators and both["frequencies_hz"] == [1.0, 5.0]
