"""Parameterised swims: a speed between two straight swims of a repertoire, by blending them."""

from __future__ import annotations

import json

import numpy as np
import pytest

from zoetic.behavior.handmade import handmade_repertoire
from zoetic.behavior.motor import blend
from zoetic.behavior.parametric import SPEED, Nodes, gait_speeds, speed_nodes, swim_at
from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.training import plan_for
from zoetic.bodies import load_animal
from zoetic.cli import main
from zoetic.control.abstract import AbstractController
from zoetic.errors import ZoeticError


def scaled(ctrl: AbstractController, k: float) -> AbstractController:
    """The gait with every mode's amplitude times k (a weaker stroke, a slower swim)."""
    return AbstractController(
        ctrl.animal, ctrl.actuators, ctrl.offset, ctrl.freq, k * ctrl.amp, ctrl.phase, ctrl.period
    )


@pytest.fixture(scope="module")
def shark():
    return load_animal("shark")


@pytest.fixture(scope="module")
def rep(shark):
    """The hand-made repertoire with slow and medium swims: go-straight's stroke weakened,
    the medium one half a stroke out of step (as two independently learned gaits can be)."""
    rep = handmade_repertoire(shark)
    straight = rep.controllers["go-straight"]
    rep.add("swim-slow", scaled(straight, 0.3), 6.0)
    rep.add("swim-medium", scaled(straight, 0.6).ahead(straight.period / 2), 6.0)
    return rep


def test_a_gait_ahead_plays_later_signals_now(rep):
    gait = rep.controllers["go-straight"]
    t = np.linspace(0.0, 1.0, 37)
    np.testing.assert_allclose(gait.ahead(0.07).raw(t), gait.raw(t + 0.07), atol=1e-9)


@pytest.fixture(scope="module")
def nodes(shark, rep):
    return speed_nodes(shark, rep)


def test_nodes_are_measured_once_per_body_and_swims(shark, rep, nodes):
    assert speed_nodes(shark, rep) is nodes
    other = Repertoire(rep.animal, rep.actuators)
    for name in ("swim-slow", "go-straight"):
        other.add(name, rep.controllers[name], 6.0)
    assert speed_nodes(shark, other).names == ("swim-slow", "go-straight")


def speeds(nodes) -> np.ndarray:
    return np.array(list(nodes.table().values()))


def test_nodes_are_the_straight_swims_slowest_first_in_step(shark, rep, nodes):
    assert nodes.names == ("swim-slow", "swim-medium", "go-straight")
    assert np.all(np.diff(speeds(nodes)) > 0) and speeds(nodes)[0] > 0.01
    # medium is half a stroke out of step with slow: blended in step, the speeds rise from
    # one entry's to the next (out of step, half and half, they would cancel to a crawl)
    curve = nodes.curves["speed"]
    assert np.all(np.diff(curve, axis=1) > 0)
    np.testing.assert_allclose(curve[:, [0, -1]], [speeds(nodes)[:-1], speeds(nodes)[1:]])
    # deg over the 6 s: straight swims stay straight
    assert np.abs(nodes.curves["turn"][:, 1:-1]).max() < 5.0
    lagged = swim_at(rep, nodes, float(curve[0, 4]))[0]
    unlagged = blend(rep.controllers["swim-slow"], rep.controllers["swim-medium"], 0.5)
    assert gait_speeds(shark, [unlagged])[0] < speeds(nodes)[0] < gait_speeds(shark, [lagged])[0]


def test_a_speed_on_a_node_plays_that_entry(rep, nodes):
    for name, speed in nodes.table().items():
        ctrl, how = swim_at(rep, nodes, speed)
        assert ctrl is rep.controllers[name]
        assert name in (how["from"], how["to"]) and how["weight"] in (0.0, 1.0)


def test_a_blended_swim_lies_between_its_neighbours_near_the_speed_asked(shark, rep, nodes):
    lo, hi = speeds(nodes)[0], speeds(nodes)[1]
    asked = [lo + f * (hi - lo) for f in (0.2, 0.5, 0.8)]
    blends = [swim_at(rep, nodes, v) for v in asked]
    assert all(how["from"] == "swim-slow" and how["to"] == "swim-medium" for _, how in blends)
    got = gait_speeds(shark, [c for c, _ in blends])
    assert np.all((lo < got) & (got < hi))  # between the two entries it blends
    assert np.all(np.diff(got) > 0)  # faster when asked faster
    assert np.all(np.abs(got - asked) < 0.25 * (hi - lo))  # and near the speed asked


def test_a_speed_outside_the_learned_swims_is_refused(rep, nodes):
    with pytest.raises(ZoeticError, match="upright blends reach"):
        swim_at(rep, nodes, float(speeds(nodes)[-1]) * 1.5)
    with pytest.raises(ZoeticError, match="--speeds"):
        Nodes.measure(load_animal("shark"), handmade_repertoire(load_animal("shark")), SPEED)


def test_the_speed_plan_is_asked_for(shark):
    names = [e.name for e in plan_for(shark, speeds=True)]
    assert names[: len(plan_for(shark))] == [e.name for e in plan_for(shark)]  # seeds kept
    assert names[-2:] == ["swim-slow", "swim-medium"]
    assert [e.name for e in plan_for(load_animal("snake"), speeds=True)][-1] != "swim-medium"


def test_repertoire_blend_writes_a_controller_that_swims_the_speed(tmp_path, rep, nodes, capsys):
    rep.save(tmp_path / "memory")
    speed = float(np.mean(speeds(nodes)[1:]))
    out = tmp_path / "swim.json"
    args = ["repertoire", "blend", str(tmp_path / "memory"), "--speed", f"{speed}"]
    assert main([*args, "--out", str(out), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert (got["from"], got["to"]) == ("swim-medium", "go-straight") and out.is_file()
    assert speeds(nodes)[1] < got["measured_m_s"] < speeds(nodes)[2]
    assert main([*args, "--out", str(out)]) == 2  # no silent overwrite
    assert "exists" in capsys.readouterr().err
    assert main([*args[:-1], "9", "--out", str(tmp_path / "x.json")]) == 2
    assert "upright blends reach" in capsys.readouterr().err


def test_blend_needs_the_speed_entries(tmp_path, shark, capsys):
    Repertoire.save(handmade_repertoire(shark), tmp_path / "m")
    assert main(["repertoire", "blend", str(tmp_path / "m"), "--speed", "0.3"]) == 2
    assert "train it with --speeds" in capsys.readouterr().err
