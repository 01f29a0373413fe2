"""The righting reflex of feed-forward plans: a sequence that rolls past 30 degrees as given
stays within them with the fins righting it, still turning as far; the recorded controller
replays the righted run; ``--no-righting`` plays the plan unchanged; path.png is drawn once."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.behavior.handmade import handmade_repertoire
from zoetic.behavior.training import build_sequence, parse_sequence
from zoetic.behavior.upright import has_righting, right_plan
from zoetic.bodies import load_animal
from zoetic.cli import main
from zoetic.control import load_controller
from zoetic.control.measure import locomotion
from zoetic.control.rollout import rollout
from zoetic.physics.world import World

# go straight, turn left, go straight: the hand-made shark rolls 48 degrees as planned, and
# turns 59 (righted: 14 degrees of roll at most, 53 of turn)
ENTRIES = "go-straight:4,sharp-turn-left:3,go-straight:6"


@pytest.fixture(scope="module")
def shark():
    return load_animal("shark")


@pytest.fixture(scope="module")
def plan(shark):
    rep = handmade_repertoire(shark)
    items = parse_sequence(ENTRIES, rep)
    return [n for n, _ in items], build_sequence(rep, items)


def _played(body, seq, seconds: float):
    """The controller played from rest in a World: times (R,) and positions (R, N, 3)."""
    steps = int(round(seconds / body.dt))
    ro = rollout(World([body]), seq.table(steps, body.dt)[None], seconds, seconds, record_every=4)
    tr = ro.trajectory(0)
    return tr.times, tr.positions[0]


def test_the_fins_keep_a_rolling_sequence_upright_and_it_still_turns(shark, plan):
    names, seq = plan
    assert has_righting(shark, seq, 0.3)
    t, pos = _played(shark, seq, seq.duration)
    before = locomotion(shark, pos, t)
    assert before["worst_roll_deg"] > 30.0  # as planned, the turn's roll grows
    result = right_plan(shark, names, seq)
    after = result.motion
    assert after["worst_roll_deg"] < 30.0, after
    assert abs(after["depth_change_m"]) < 1.0
    assert after["turn_deg"] > 0.85 * before["turn_deg"] > 45.0  # the turn still happens
    # the planned entries play in order; the fins right some windows, not all
    base = [n.split("+")[0] for n in result.evaluations]
    assert [b for k, b in enumerate(base) if k == 0 or b != base[k - 1]] == names
    assert 0 < result.summary()["windows_righted"] < len(result.evaluations)
    # the recorded controller, played from rest, swims the righted path
    t2, pos2 = _played(shark, result.sequence, float(result.times[-1]))
    n = min(len(t2), len(result.times))
    assert np.allclose(t2[:n], result.times[:n])
    assert np.nanmax(np.abs(pos2[:n] - result.positions[:n])) < 1e-6  # m


def test_a_resumed_abstraction_carries_the_stroke_on(shark):
    ctrl = handmade_repertoire(shark).controllers["sharp-turn-left"]
    t = np.linspace(0.0, 2.0, 50)
    assert np.allclose(ctrl.resumed(0.37).raw(t), ctrl.raw(t + 0.37))


@pytest.mark.slow
def test_the_sequence_command_rights_by_default_and_not_when_told(tmp_path, shark, capsys):
    import zoetic.viz.plots
    import zoetic.viz.tracking

    handmade_repertoire(shark).save(tmp_path / "m")
    args = ["sequence", "shark", "--memory", str(tmp_path / "m"), "--entries", ENTRIES]
    args += ["--no-video"]
    drawn = []
    plan_plot = zoetic.viz.tracking.plot_plan
    with pytest.MonkeyPatch.context() as mp:  # path.png is drawn once, with its side view
        mp.setattr(zoetic.viz.plots, "plot_path", lambda *a, **k: drawn.append("top"))
        mp.setattr(
            zoetic.viz.tracking,
            "plot_plan",
            lambda *a, **k: drawn.append("top+side") or plan_plot(*a, **k),
        )
        assert main([*args, "--out", str(tmp_path / "on")]) == 0
    assert drawn == ["top+side"]
    text = capsys.readouterr().out
    assert "a righting variant played in" in text and "net turn" in text
    roll = float(text.split("worst roll ")[1].split(" deg")[0])
    assert roll < 30.0
    on = load_controller(tmp_path / "on" / "sequence.json", shark)
    assert any(
        not np.array_equal(c.offset, seq_c.offset)
        for c, _ in on.items
        for seq_c in [handmade_repertoire(shark).controllers["go-straight"]]
    )
    assert main([*args, "--out", str(tmp_path / "off"), "--no-righting"]) == 0
    text = capsys.readouterr().out
    assert "off (--no-righting)" in text
    assert float(text.split("worst roll ")[1].split(" deg")[0]) > 30.0
    off = load_controller(tmp_path / "off" / "sequence.json", shark)
    rep = handmade_repertoire(shark)
    planned = build_sequence(rep, parse_sequence(ENTRIES, rep))
    assert off.to_dict() == planned.to_dict()  # unchanged: the plan as given
