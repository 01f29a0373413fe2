"""Parameterised turns: a radius (or turning rate) between the learned turns, by blending
go-straight and the turns of a repertoire."""

from __future__ import annotations

import json

import numpy as np
import pytest

from zoetic.behavior.handmade import handmade_repertoire
from zoetic.behavior.parametric import (
    TURN,
    TURN_SECONDS,
    Nodes,
    check_reached,
    gait_motion,
    nodes_for,
    play_at,
    turn_of_radius,
)
from zoetic.behavior.promises import entry_motion
from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.training import plan_for
from zoetic.bodies import load_animal
from zoetic.cli import main
from zoetic.errors import ZoeticError
from zoetic.tasks import load_task


@pytest.fixture(scope="module")
def shark():
    return load_animal("shark")


@pytest.fixture(scope="module")
def rep(shark):
    """The hand-made repertoire: go-straight and the sharp and wide turns (one side's wave
    weakened, the other's biased)."""
    return handmade_repertoire(shark)


@pytest.fixture(scope="module")
def nodes(shark, rep):
    return nodes_for(shark, rep, TURN)


def curvature(shark, ctrls) -> np.ndarray:
    return gait_motion(shark, ctrls, TURN_SECONDS)["curvature"]


def test_turn_nodes_run_from_straight_to_the_sharpest_turn(shark, rep, nodes):
    assert nodes.names == ("go-straight", "wide-turn-left", "sharp-turn-left")
    own = nodes.table()
    np.testing.assert_allclose(
        list(own.values()), curvature(shark, [rep.controllers[n] for n in nodes.names])
    )
    assert abs(own["go-straight"]) < 0.02 < own["wide-turn-left"] < own["sharp-turn-left"]
    k = nodes.curves["curvature"]
    assert np.all(np.diff(k, axis=1) > 0)  # the blends turn tighter as the weight grows
    assert nodes.curves["roll"].max() < 90.0  # and none swims on its back


def test_the_curvature_is_the_promise_arc(shark, rep):
    """1 / curvature is the radius a turn task's promise judges from rest over its horizon
    (promises.entry_motion, the judge of "radius_bl")."""
    ctrl = rep.controllers["wide-turn-left"]
    judged = entry_motion(shark, ctrl, load_task("wide-turn-left"))[0]  # from rest, over 4 s
    assert 1.0 / curvature(shark, [ctrl])[0] == pytest.approx(judged["radius_bl"], rel=1e-3)


def test_a_radius_at_a_calibrated_blend_replays_that_blend(shark, rep, nodes):
    """At each inner calibrated weight the blend asked for is that weight's, and measured
    again it turns on the calibrated radius: a weight read off the wrong node or gap would
    turn on another."""
    k = nodes.curves["curvature"]
    for gap, j in ((0, 3), (1, 5)):
        radius = 1.0 / float(k[gap, j])
        ctrl, how = turn_of_radius(rep, nodes, radius)
        assert (how["from"], how["to"]) == nodes.names[gap : gap + 2]
        assert how["weight"] == pytest.approx(j / 8, abs=1e-4)
        assert 1.0 / curvature(shark, [ctrl])[0] == pytest.approx(radius, rel=1e-3)


def test_radii_between_the_turns_turn_near_the_radius_asked(shark, rep, nodes):
    k = nodes.table()
    tight, wide = 1.0 / k["sharp-turn-left"], 1.0 / k["wide-turn-left"]
    asked = np.geomspace(wide, tight, 5)[1:-1]
    got = 1.0 / curvature(shark, [turn_of_radius(rep, nodes, r)[0] for r in asked])
    assert np.all((tight < got) & (got < wide))  # between the two turns it blends
    assert np.all(np.diff(got) < 0)  # tighter when asked tighter
    np.testing.assert_allclose(got, asked, rtol=0.1)  # and near the radius asked


def test_a_turn_rate_is_read_off_the_same_blends(shark, rep, nodes):
    """The first calibrated blend that turns faster than every blend before it is the one a
    turning rate of its own is read off (the rate need not rise with the weight everywhere:
    the first crossing is taken)."""
    rates = nodes.curves["turn_rate"]
    chain = [(g, j) for g in range(len(rates)) for j in range(1, rates.shape[1] - 1)]
    record = [
        (g, j) for g, j in chain if rates[g, j] > max(rates[:g].max(initial=-np.inf), *rates[g, :j])
    ]
    g, j = record[0]
    ctrl, how = play_at(rep, nodes, float(rates[g, j]), "turn_rate")
    assert how["from"] == nodes.names[g] and how["weight"] == pytest.approx(j / 8, abs=1e-4)
    got = gait_motion(shark, [ctrl], TURN_SECONDS)["turn_rate"][0]
    assert got == pytest.approx(rates[g, j], rel=1e-3)


def test_a_radius_outside_the_learned_turns_is_refused(rep, nodes):
    tightest = 1.0 / nodes.table()["sharp-turn-left"]
    for radius in (tightest / 2, 0.0, -1.0, float("nan")):
        with pytest.raises(ZoeticError, match="upright blends reach"):
            turn_of_radius(rep, nodes, radius)
    with pytest.raises(ZoeticError, match="upright blends reach"):
        play_at(rep, nodes, 1e3, "turn_rate")
    few = Repertoire(rep.animal, rep.actuators)
    few.add("sharp-turn-left", rep.controllers["sharp-turn-left"], 3.0)
    with pytest.raises(ZoeticError, match="--radii"):
        Nodes.measure(load_animal("shark"), few, TURN)


def test_the_radius_plan_is_asked_for(shark):
    names = [e.name for e in plan_for(shark, speeds=True, radii=True)]
    assert names[: len(plan_for(shark, speeds=True))] == [
        e.name for e in plan_for(shark, speeds=True)
    ]  # the other entries and their seeds kept
    assert names[-1] == "medium-turn-left"
    assert "medium-turn-left" not in [e.name for e in plan_for(load_animal("snake"), radii=True)]


def test_repertoire_blend_writes_a_turn_of_the_radius(tmp_path, shark, rep, nodes, capsys):
    rep.save(tmp_path / "memory")
    k = nodes.table()
    radius = 2.0 / (k["wide-turn-left"] + k["sharp-turn-left"])
    out = tmp_path / "turn.json"
    args = ["repertoire", "blend", str(tmp_path / "memory"), "--radius", f"{radius}"]
    assert main([*args, "--out", str(out), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert (got["from"], got["to"]) == ("wide-turn-left", "sharp-turn-left") and out.is_file()
    assert got["measured_radius_bl"] == pytest.approx(radius, rel=0.1)
    assert got["error_pct"] == pytest.approx(100 * (got["measured_radius_bl"] / radius - 1), 0.05)
    assert got["turn_rate_deg_s"] > 0 and got["side"] == "left"
    assert main([*args, "--right", "--out", str(tmp_path / "r.json"), "--json"]) == 0
    right = json.loads(capsys.readouterr().out)
    assert right["turn_rate_deg_s"] == pytest.approx(-got["turn_rate_deg_s"], rel=0.05)
    assert main([*args[:-1], "0.01", "--out", str(tmp_path / "x.json")]) == 2
    assert "upright blends reach" in capsys.readouterr().err
    assert main([*args, "--speed", "0.3", "--out", str(tmp_path / "y.json")]) == 2
    assert "give one of" in capsys.readouterr().err


def made_nodes(curvature, roll, mid_curvature, mid_roll) -> Nodes:
    """Nodes of two entries whose calibrated blends are given, not measured."""
    curves = {"curvature": np.array([curvature], float), "roll": np.array([roll], float)}
    mids = {"curvature": np.array([mid_curvature], float), "roll": np.array([mid_roll], float)}
    return Nodes(TURN, ("go-straight", "wide-turn-left"), np.zeros(1), curves, mids)


def test_a_weight_is_read_only_off_upright_segments_that_are_nearly_lines():
    w = np.linspace(0.0, 1.0, 9)
    line = made_nodes(w, np.zeros(9), (w[:-1] + w[1:]) / 2, np.zeros(8))
    assert line.neighbours(0.3) == (0, pytest.approx(0.3))
    rolled = np.zeros(9)
    rolled[3] = 45.0  # the blend at 0.375 rolls past UPRIGHT: the segments either side go
    tipped = made_nodes(w, rolled, (w[:-1] + w[1:]) / 2, np.zeros(8))
    assert tipped.neighbours(0.3) is None and tipped.neighbours(0.2) == (0, pytest.approx(0.2))
    assert tipped.spans() == [(0.0, 0.25), (0.5, 1.0)]
    kinked = (w[:-1] + w[1:]) / 2
    kinked[4] = 0.9  # halfway between 0.5 and 0.625 the blend turns as tight as at 0.9
    bent = made_nodes(w, np.zeros(9), kinked, np.zeros(8))
    assert bent.neighbours(0.55) is None and bent.neighbours(0.45) == (0, pytest.approx(0.45))
    assert bent.neighbours(0.0) == (0, 0.0) and bent.neighbours(1.0) == (0, 1.0)  # the entries


def test_a_blend_that_misses_or_rolls_is_refused():
    check_reached("radius", 2.0, 2.1, "body lengths", 10.0)  # 5 % off, upright: kept
    for measured, roll in ((2.5, 10.0), (None, 10.0), (-2.0, 10.0), (2.0, 40.0)):
        with pytest.raises(ZoeticError, match="change abruptly"):
            check_reached("radius", 2.0, measured, "body lengths", roll)
