"""Stunts: trick files parse strictly; their style terms react to scripted motions (a body
lifted out of the water, a somersault in the air, a ball struck from below, a bar passed);
``zoetic stunt`` with a tiny budget writes its files and its macro.json replays the same."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from zoetic.behavior.stunt_problem import StuntProblem
from zoetic.behavior.stunts import measures, object_markers
from zoetic.behavior.tricks import list_tricks, load_trick, parse_trick
from zoetic.bodies import load_animal
from zoetic.cli import main
from zoetic.errors import TaskError
from zoetic.physics.objects import Ball, Cylinder
from zoetic.tasks import fits
from zoetic.tasks.terms import TERMS, BodyFrame, Signals, TermParams


def _lifted(body, heights, angles=None) -> np.ndarray:
    """Return (1, R, N, 3): the rest pose with its centre of mass at each height (x = z = 0),
    turned nose-up about +z by each angle (rad)."""
    w = body.mass / body.total_mass
    rel = body.rest_pos - w @ body.rest_pos
    out = []
    for k, y in enumerate(heights):
        a = 0.0 if angles is None else angles[k]
        c, s = math.cos(a), math.sin(a)
        rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        out.append(rel @ rot.T + [0.0, y, 0.0])
    return np.array(out)[None]


def _signals(body, pos, dt=0.05, contacts=None, balls=None) -> Signals:
    r = pos.shape[1]
    return Signals(
        np,
        BodyFrame.of(body),
        pos,
        np.zeros((1, r, body.n_actuators)),
        np.arange(r) * dt,
        0.0,
        r * dt,
        contacts,
        balls,
    )


def _term(name, s, target=0.0, goal=(0.0, 0.0, 0.0)) -> float:
    return float(TERMS[name].fn(np, s, TermParams(target, goal))[0])


def test_every_built_in_trick_parses_and_fits_the_dolphin(dolphin):
    assert set(list_tricks()) >= {"leap", "hurdle", "somersault", "ball-nose", "ball-tail"}
    for name in list_tricks():
        trick = load_trick(name)
        assert trick.task.horizon > 0 and fits(trick.task, dolphin), name
        assert trick.durations[0] < trick.durations[1]
    hurdle, ball = load_trick("hurdle"), load_trick("ball-nose")
    bar = hurdle.objects[0]
    assert isinstance(bar, Cylinder) and bar.axis == "z"
    from zoetic.behavior.tracking import body_length

    # 0.3 body lengths up (the bar's top: its centre plus its radius)
    assert bar.center[1] + bar.radius == pytest.approx(0.3 * body_length(dolphin), abs=0.02)
    assert {type(o) for o in ball.objects} == {Ball, Cylinder}
    assert not fits(load_trick("leap").task, load_animal("shark"))  # no surface to leave


def test_trick_files_are_strict():
    base = {"name": "t", "horizon": 1.0, "terms": [{"kind": "apex_above_surface"}]}
    with pytest.raises(TaskError, match=r"my\.toml: trick: unknown key"):
        parse_trick(base | {"trick": {"segmants": 3}}, "my.toml")
    with pytest.raises(TaskError, match=r"my\.toml: objects\[0\]: unknown key"):
        parse_trick(base | {"objects": [{"kind": "ball", "radius": 0.2, "colour": 1}]}, "my.toml")
    with pytest.raises(TaskError, match="durations"):
        parse_trick(base | {"trick": {"durations": [2.0, 1.0]}}, "my.toml")
    with pytest.raises(TaskError, match="kind = ball, box or cylinder"):
        parse_trick(base | {"objects": [{"kind": "hoop"}]}, "my.toml")
    t = parse_trick(base | {"objects": [{"kind": "ball", "radius": 0.2}]}, "my.toml")
    assert t.objects == (Ball(radius=0.2),)


def test_a_body_lifted_out_of_the_water_scores_height_clearance_and_air_time(dolphin):
    under = _signals(dolphin, _lifted(dolphin, np.linspace(-2.0, -1.0, 21)))
    flight = np.concatenate([np.linspace(-1.0, 1.0, 11), np.linspace(1.0, -1.0, 11)])
    leap = _signals(dolphin, _lifted(dolphin, flight))
    assert _term("apex_above_surface", under) == pytest.approx(-1.0, abs=1e-9)
    assert _term("apex_above_surface", leap) == pytest.approx(1.0, abs=1e-9)
    assert _term("clear_fraction", under) == 0.0 and _term("clear_fraction", leap) == 1.0
    assert _term("air_time", under) == 0.0
    # half a body height (0.12 m) clears the surface: every record with com above ~0.13 m
    airborne = np.mean(flight > 0.2)
    assert airborne - 0.1 < _term("air_time", leap) < airborne + 0.1
    assert _term("flight_rotation", leap) == pytest.approx(0.0, abs=1e-9)


def test_a_somersault_in_the_air_counts_its_rotation_and_not_the_one_under_water(dolphin):
    n = 41
    spin = np.linspace(0.0, 2 * np.pi, n)
    air = _signals(dolphin, _lifted(dolphin, np.full(n, 2.0), spin))
    water = _signals(dolphin, _lifted(dolphin, np.full(n, -2.0), spin))
    assert _term("flight_rotation", air) == pytest.approx(2 * np.pi, rel=1e-6)
    assert _term("flight_rotation", water) == 0.0
    # nose up by 0.5 rad at the end: pitch change and the apex pitch see it
    up = _signals(dolphin, _lifted(dolphin, np.linspace(-2, -1, 5), np.linspace(0, 0.5, 5)))
    assert _term("pitch_change", up, target=0.5) == pytest.approx(0.0, abs=1e-9)
    assert _term("apex_pitch", up) == pytest.approx(0.25, rel=1e-6)


def test_bar_crossing_height_is_read_where_the_body_passes_the_bar(dolphin):
    pos = _lifted(dolphin, np.array([-1.0, 0.0, 0.6, 0.0, -1.0]))
    pos = pos + np.array([0.0, 1.0, 2.0, 3.0, 4.0])[None, :, None, None] * [1.0, 0.0, 0.0]
    s = _signals(dolphin, pos)
    assert _term("bar_crossing_height", s, goal=(2.0, 0.31, 0.0)) == pytest.approx(0.29)
    assert _term("bar_crossing_height", s, goal=(4.0, 0.31, 0.0)) == pytest.approx(-1.31)
    # a leap that ends at its apex 1 m before the bar scores its shortfall, not its height
    short = _signals(dolphin, pos[:, :3])
    assert _term("bar_crossing_height", short, goal=(2.0, 0.31, 0.0)) == pytest.approx(0.29)
    assert _term("bar_crossing_height", short, goal=(3.0, 0.31, 0.0)) == pytest.approx(-1.0)
    counts = _signals(dolphin, pos, contacts=np.array([[0.0, 2.0, 3.0, 0.0, 0.0]]))
    assert _term("contact_count", counts) == 5.0 and _term("contact_count", s) == 0.0


def test_a_ball_struck_from_below_rises_and_the_terms_see_contact(dolphin, beat_repertoire):
    """The dolphin nose-up under a floating ball: shot upward it strikes the ball (contacts,
    the ball rises); at rest beside it, the ball stays."""
    doc = {
        "name": "strike",
        "horizon": 0.6,
        "record_hz": 50.0,
        "requires": ["surface"],
        "start": {
            "position": [0.0, 0.0, 0.0],
            "pitch": math.pi / 2,
            "depth": 0.87 * float(np.ptp(dolphin.rest_pos[:, 0])),  # nose under the ball
            "speed": 4.0,
        },
        "objects": [{"kind": "ball", "radius": 0.2, "mass": 0.3, "position": [0.0, 0.2, 0.0]}],
        "terms": [
            {"kind": "ball_rise", "weight": -1.0},
            {"kind": "contact_count"},
            {"kind": "ball_head_distance"},
        ],
    }
    struck = StuntProblem(dolphin, beat_repertoire, parse_trick(doc, "strike"))
    rec = struck.record(np.zeros((1, 1), int), np.ones((1, 1)))
    got = struck.scores(rec)
    still_doc = doc | {"start": doc["start"] | {"speed": 0.0}}
    still = StuntProblem(dolphin, beat_repertoire, parse_trick(still_doc, "still"))
    rest = still.scores(still.record(np.zeros((1, 1), int), np.ones((1, 1))))
    assert got["contact_count"][0] > 0 and rest["contact_count"][0] == 0
    assert got["ball_rise"][0] > 0.04 and abs(rest["ball_rise"][0]) < 0.01
    assert got["ball_head_distance"][0] < rest["ball_head_distance"][0]
    m = measures(struck, rec)
    assert m["ball_rise_m"] == pytest.approx(got["ball_rise"][0], abs=1e-3)
    assert m["contacts"] == int(got["contact_count"][0])
    mk = object_markers(struck.trick.objects, rec.balls[0])
    assert mk.shape == (rec.balls.shape[1], 1, 3) and np.allclose(mk[:, 0], rec.balls[0, :, 0])


def test_stunt_cli_writes_its_files_and_the_macro_replays(
    tmp_path, capsys, dolphin, beat_repertoire
):
    memory = tmp_path / "memory"
    beat_repertoire.save(memory)
    trick = tmp_path / "short-leap.toml"
    trick.write_text(
        'name = "short-leap"\nrequires = ["surface"]\nhorizon = 0.5\nrecord_hz = 20.0\n'
        "[start]\ndepth = 0.6\nspeed = 1.0\npitch = 0.6\n"
        "[trick]\nsegments = 2\ndurations = [0.1, 0.4]\n"
        "[trick.jitter]\ndepth = 0.05\nheading = 2.0\n"
        '[[terms]]\nkind = "apex_above_surface"\nweight = -1.0\n'
    )
    out = tmp_path / "leap"
    code = main(
        [
            "stunt",
            "dolphin",
            "--memory",
            str(memory),
            "--trick",
            str(trick),
            "--budget",
            "6",
            "--out",
            str(out),
            "--fps",
            "8",
        ]
    )
    assert code == 0
    said = " ".join(capsys.readouterr().out.split())  # before the search: what it will cost
    # robust: the 6 simulations are 2 plans, each from 3 starts; checked from 6 more
    assert "dolphin short-leap: 2 plans by anneal, each a 0.5 s simulation from 3 starts" in said
    assert "stops early" not in said  # the trick file does not ask to stop once met
    assert "targets met from 6 of 6 perturbed starts (start 0.05 m deeper" in said
    for f in ("macro.json", "summary.json", "score.png", "video.mp4"):
        assert (out / f).stat().st_size > 0, f
    s = json.loads((out / "summary.json").read_text())
    assert s["evaluations"] == 2 and len(s["plan"]) == 2
    assert s["perturbed_starts"] == 6 and s["jitter"] == {"depth": 0.05, "heading": 2.0, "pitch": 0}
    assert s["E"] == pytest.approx(-s["apex_above_surface_m"], abs=1e-3)
    assert s["seconds"] == pytest.approx(0.5)
    code = main(
        [
            "simulate",
            "dolphin",
            "--controller",
            str(out / "macro.json"),
            "--out",
            str(tmp_path / "replay"),
            "--no-video",
        ]
    )
    assert code == 0
    from zoetic.record import read_record

    replayed = read_record(tmp_path / "replay")
    times, pos = replayed.times, replayed.animals[0].positions
    assert times[-1] == pytest.approx(0.5)  # the stunt's own duration by default
    com_y = pos[..., 1] @ (dolphin.mass / dolphin.total_mass)
    assert com_y.max() == pytest.approx(s["apex_above_surface_m"], abs=2e-3)
    code = main(
        [
            "stunt",
            "dolphin",
            "--memory",
            str(memory),
            "--trick",
            "backflop",
            "--budget",
            "2",
            "--out",
            str(tmp_path / "no"),
        ]
    )
    assert code == 2 and not (tmp_path / "no").exists()
    assert "unknown trick 'backflop'" in capsys.readouterr().err.replace("\n", " ")


def test_a_tiny_stunt_search_improves_on_its_first_plans(dolphin, beat_repertoire):
    doc = {
        "name": "up",
        "horizon": 0.5,
        "record_hz": 20.0,
        "requires": ["surface"],
        "start": {"depth": 0.6, "pitch": 0.6, "speed": 1.0},
        "trick": {"segments": 2, "durations": [0.1, 0.4]},
        "terms": [{"kind": "apex_above_surface", "weight": -1.0}],
    }
    from zoetic.behavior.macro import search

    problem = StuntProblem(dolphin, beat_repertoire, parse_trick(doc, "up"))
    result = search(problem, "anneal", 12, 0, chains=4)
    assert [n for n, _ in result.history] == [4, 8, 12]
    assert result.scores["cost"] == pytest.approx(result.history[-1][1])  # replays its best
    others = problem.evaluate(*problem.random(np.random.default_rng(1), 4))["cost"]
    assert result.scores["cost"] <= np.median(others)


def test_final_height_is_zero_only_once_the_whole_body_is_back_in_the_water(dolphin):
    """A leap still in the air at the end pays its highest node's height; one whose nose alone
    has re-entered still pays; one wholly back under water pays nothing."""
    top = float(
        np.max(dolphin.rest_pos[:, 1]) - dolphin.mass @ dolphin.rest_pos[:, 1] / dolphin.total_mass
    )
    for end, want in ((1.0, 1.0 + top), (-0.1, top - 0.1), (-1.0, 0.0)):
        s = _signals(dolphin, _lifted(dolphin, np.array([-2.0, 1.5, end])))
        assert _term("final_height", s) == pytest.approx(want, abs=1e-9)


def test_stunt_cli_says_a_search_may_stop_early_when_its_trick_asks(
    tmp_path, capsys, beat_repertoire
):
    memory = tmp_path / "memory"
    beat_repertoire.save(memory)
    trick = tmp_path / "stop-leap.toml"
    trick.write_text(
        'name = "stop-leap"\nrequires = ["surface"]\nhorizon = 0.3\nrecord_hz = 20.0\n'
        "[start]\ndepth = 0.6\nspeed = 1.0\npitch = 0.6\n"
        "[trick]\nsegments = 1\ndurations = [0.1, 0.3]\nstop_when_met = true\n"
        '[[terms]]\nkind = "apex_above_surface"\nweight = -1.0\n'
    )
    args = ["stunt", "dolphin", "--memory", str(memory), "--trick", str(trick), "--budget", "2"]
    assert main([*args, "--out", str(tmp_path / "s"), "--no-video"]) == 0
    said = " ".join(capsys.readouterr().out.split())
    assert "it stops early once a plan meets the targets from every moved start" in said
