"""The hurdle's style (section 3.2: "at the apex ... horizontal ... face downward upon
reentry") and the leap's balance: the terms read the pitch at the apex and where the head
re-enters the water; a trick's own [trick.targets] bound its measures and ``targets_met``
requires them."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from zoetic.behavior.stunts import TARGET_TRICKS, targets_met
from zoetic.behavior.tricks import load_trick, parse_trick
from zoetic.errors import TaskError
from zoetic.tasks.terms import TERMS, BodyFrame, Signals, TermParams

ARC = np.concatenate([np.linspace(-1.0, 1.0, 11), np.linspace(0.9, -1.0, 20)])  # com y, m


def _flight(body, heights, angles) -> Signals:
    """Signals of the rest pose carried along ``heights`` (centre of mass y, m; the surface at
    0) and turned nose-up about +z by ``angles`` (rad), one record each 0.05 s."""
    w = body.mass / body.total_mass
    rel = body.rest_pos - w @ body.rest_pos
    pos = []
    for y, a in zip(heights, angles, strict=True):
        c, s = math.cos(a), math.sin(a)
        rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        pos.append(rel @ rot.T + [0.0, y, 0.0])
    r = len(pos)
    frame = BodyFrame.of(body)
    acts = np.zeros((1, r, body.n_actuators))
    return Signals(np, frame, np.array(pos)[None], acts, np.arange(r) * 0.05, 0.0, r * 0.05)


def _term(name, s, target=0.0) -> float:
    return float(TERMS[name].fn(np, s, TermParams(target))[0])


def test_a_level_apex_scores_better_than_a_pitched_one(dolphin):
    level = _flight(dolphin, ARC, np.zeros(ARC.size))
    pitched = _flight(dolphin, ARC, np.full(ARC.size, 0.4))
    # turning from nose up to nose down through the flight, level only where it peaks
    turning = _flight(dolphin, ARC, np.linspace(0.6, -0.9, ARC.size))
    assert _term("apex_pitch", level) == pytest.approx(0.0, abs=1e-9)
    assert _term("apex_pitch", pitched) == pytest.approx(0.16, rel=1e-3)
    apex = int(np.argmax(ARC))
    assert int(turning.apex_record[0]) == apex
    assert _term("apex_pitch", turning) == pytest.approx(
        np.linspace(0.6, -0.9, ARC.size)[apex] ** 2
    )


def test_a_nose_down_reentry_is_detected_and_a_flat_one_costs(dolphin):
    down = np.linspace(0.5, -0.9, ARC.size)
    dive = _flight(dolphin, ARC, down)
    flat = _flight(dolphin, ARC, np.zeros(ARC.size))
    assert dive.reentered[0] == 1.0 and flat.reentered[0] == 1.0
    i = int(dive.reentry_record[0])
    # the first record after the apex with the head under the surface
    assert i > int(np.argmax(ARC)) and dive.head[0, i, 1] < 0.0 <= dive.head[0, i - 1, 1]
    assert dive.body_pitch[0, i] == pytest.approx(down[i], abs=1e-6)
    assert down[i] < -0.3
    assert _term("entry_pitch", dive, target=-0.3) == 0.0  # nose down past -17 deg
    assert _term("entry_pitch", flat, target=-0.3) == pytest.approx(0.3**2, rel=1e-6)
    # still in the air at the end: no re-entry, the term reads the last record
    up = _flight(dolphin, ARC[:16], down[:16])
    assert up.reentered[0] == 0.0 and int(up.reentry_record[0]) == 15
    # never out of the water: no re-entry either
    under = _flight(dolphin, ARC - 3.0, down)
    assert under.reentered[0] == 0.0


def test_the_hurdle_and_the_leap_require_their_style_targets():
    hurdle = load_trick("hurdle")
    kinds = {t.kind for t in hurdle.task.terms}
    assert {"apex_pitch", "entry_pitch", "bar_crossing_height"} <= kinds
    bounds = {k: (lo, hi) for k, lo, hi in hurdle.targets}
    assert bounds["apex_pitch_deg"][0] < 0.0 < bounds["apex_pitch_deg"][1]
    assert bounds["entry_pitch_deg"][1] < 0.0  # nose down
    over = {"most_nodes_out_of_water": 1.0, "bar_crossed": True, "hurdle_touched": False}
    good = over | {"apex_pitch_deg": 3.0, "entry_pitch_deg": -40.0}
    assert all(targets_met("hurdle", good, hurdle).values())
    flags = targets_met("hurdle", over | {"apex_pitch_deg": 35.0, "entry_pitch_deg": 5.0}, hurdle)
    assert not flags["apex_pitch_deg"] and not flags["entry_pitch_deg"] and flags["over_bar"]
    # no re-entry by the end: no nose-down re-entry
    assert not targets_met(
        "hurdle", over | {"apex_pitch_deg": 0.0, "entry_pitch_deg": None}, hurdle
    )["entry_pitch_deg"]
    leap = load_trick("leap")
    assert "roll_rotation_in_air_deg" in {k for k, _, _ in leap.targets}
    flight = {"most_nodes_out_of_water": 1.0, "air_time_s": 1.0, "apex_body_lengths": 1.0}
    flight |= {"final_height_m": 0.0, "entry_pitch_deg": -45.0}
    assert not targets_met("leap", flight | {"roll_rotation_in_air_deg": 384.0}, leap)[
        "roll_rotation_in_air_deg"
    ]


def test_trick_targets_are_strict():
    base = {"name": "t", "horizon": 1.0, "terms": [{"kind": "apex_above_surface"}]}
    t = parse_trick(base | {"trick": {"targets": {"apex_pitch_deg": [-10, 10]}}}, "my.toml")
    assert t.targets == (("apex_pitch_deg", -10.0, 10.0),)
    assert t.to_dict()["targets"] == {"apex_pitch_deg": [-10.0, 10.0]}
    for bad in ([10, -10], [1], "low", [True, 2]):
        with pytest.raises(TaskError, match=r"my\.toml: trick\.targets: 'x'"):
            parse_trick(base | {"trick": {"targets": {"x": bad}}}, "my.toml")


def test_the_leap_requires_a_reentry_by_the_end(dolphin):
    leap = load_trick("leap")
    assert {"final_height", "entry_pitch"} <= {t.kind for t in leap.task.terms}
    bounds = {k: (lo, hi) for k, lo, hi in leap.targets}
    assert bounds["final_height_m"] == (0.0, 0.0)
    assert bounds["entry_pitch_deg"][1] < 0.0  # head first, nose down
    flight = {
        "most_nodes_out_of_water": 1.0,
        "air_time_s": 1.0,
        "apex_body_lengths": 1.0,
        "roll_rotation_in_air_deg": 10.0,
        "entry_pitch_deg": -45.0,
    }
    assert all(targets_met("leap", flight | {"final_height_m": 0.0}, leap).values())
    # a flight the horizon cuts while the body is still out of the water is not a whole leap
    cut = targets_met("leap", flight | {"final_height_m": 0.93}, leap)
    assert not cut["final_height_m"] and cut["air_time"] and cut["apex"]
    # back in after turning nose over tail: the head goes in with the body pointing up
    flipped = targets_met("leap", flight | {"final_height_m": 0.0, "entry_pitch_deg": 73.0}, leap)
    assert not flipped["entry_pitch_deg"] and flipped["final_height_m"]
    # the term costs the height still out at the end, nothing once the body is back in
    down = np.linspace(0.5, -0.9, ARC.size)
    landed = _flight(dolphin, ARC, down)
    rising = _flight(dolphin, ARC[:11], down[:11])  # the record ends at the apex, 1 m up
    assert _term("final_height", landed) == 0.0
    assert _term("final_height", rising) > 1.0  # the centre of mass 1 m up, the nose higher


def test_a_target_on_no_measure_is_refused_by_name():
    """A target whose key no stunt measures could never be met: targets_met names it and the
    measures there are, instead of calling the stunt a failure."""
    base = {"name": "t", "horizon": 1.0, "terms": [{"kind": "apex_above_surface"}]}
    t = parse_trick(base | {"trick": {"targets": {"apex_pich_deg": [-10, 10]}}}, "my.toml")
    with pytest.raises(TaskError, match=r"'apex_pich_deg' is not a measure.*apex_pitch_deg"):
        targets_met("t", {"apex_pitch_deg": 2.0, "air_time_s": 1.0}, t)


def test_every_built_in_target_is_a_measure_the_stunts_report():
    """Each built-in trick's [trick.targets] keys are among the measures its committed Plate 5
    summary reports (``measures``), so none is a target no stunt can meet."""
    root = Path(__file__).resolve().parents[1] / "docs" / "figures" / "plate5"
    for name in TARGET_TRICKS:
        trick = load_trick(name)
        reported = json.loads((root / name / "summary.json").read_text())
        for key, _, _ in trick.targets:
            assert key in reported, f"{name}: target {key} is not in its summary"
