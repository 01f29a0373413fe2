"""Greedy target tracking: the hand-made repertoire turns, tracking reaches a short course, the
recorded sequence replays the path, and the command gives clear errors for bad repertoires."""

from __future__ import annotations

import json

import numpy as np
import pytest

from zoetic.behavior.handmade import handmade_repertoire
from zoetic.behavior.targets import TrackingError, parse_points, parse_targets
from zoetic.behavior.tracking import (
    RESTART,
    TrackConfig,
    cost_to_go,
    replay,
    track,
)
from zoetic.bodies import load_animal
from zoetic.cli import main
from zoetic.control import load_controller
from zoetic.control.abstract import SequenceController
from zoetic.control.loop import Schedule, drive
from zoetic.learning.objective import heading_angles
from zoetic.physics import simulate
from zoetic.physics.world import World

COURSE = np.array([[1.5, 0.3], [3.5, 1.5]])


@pytest.fixture(scope="module")
def shark():
    return load_animal("shark")


@pytest.fixture(scope="module")
def memory(tmp_path_factory, shark):
    """A repertoire directory of the six hand-made entries."""
    directory = tmp_path_factory.mktemp("memory") / "shark"
    handmade_repertoire(shark).save(directory)
    return directory


def test_handmade_entries_turn_the_way_their_names_say(shark):
    rep = handmade_repertoire(shark)
    steps = int(8.0 / shark.dt)
    tables = np.stack([rep.controllers[n].table(steps, shark.dt) for n in rep.names])
    traj = simulate(shark, tables, record_every=10)
    turn = dict(
        zip(rep.names, np.degrees(heading_angles(shark, traj.positions)[:, -1]), strict=True)
    )
    moved = dict(
        zip(rep.names, np.linalg.norm(np.ptp(traj.com(shark), axis=1), axis=-1), strict=True)
    )
    # go-straight veers a little (a heading wobble of the 5 Hz wave), turns turn far more
    assert moved["do-nothing"] < 1e-6 and abs(turn["go-straight"]) < 12
    assert moved["go-straight"] > 1.5  # m in 8 s
    for side, sign in (("left", 1), ("right", -1)):
        assert sign * turn[f"sharp-turn-{side}"] > 25
        assert sign * turn[f"wide-turn-{side}"] > 12
        assert turn[f"sharp-turn-{side}"] * sign > turn[f"wide-turn-{side}"] * sign


def test_tracking_reaches_every_target_and_replays(shark):
    rep = handmade_repertoire(shark)
    result = track(shark, rep, COURSE, TrackConfig(time_limit=30.0))
    assert np.isfinite(result.reached).all(), result.summary()
    assert np.all(np.diff(result.reached) > 0)
    assert result.realtime_factor > 1.0  # faster than real time, even on a slow test machine
    assert len(result.evaluations) == pytest.approx(result.sim_time, abs=1)  # every ~1 s
    # the recorded cross-faded sequence, played from rest, gives the same continuous path
    again = replay(shark, result)
    assert np.abs(again.positions[0] - result.positions).max() < 1e-3
    jumps = np.linalg.norm(np.diff(result.com, axis=0), axis=-1)
    assert jumps.max() < 0.05  # m between records 20 ms apart: no teleporting at switches
    idx = result.start_indices
    assert idx[0] == 0 and np.all(np.diff(idx) > 0)
    assert isinstance(result.sequence, SequenceController)
    # an entry follows itself only where the tracker restarted it after holding it RESTART s
    for i, (a, b) in enumerate(zip(result.names, result.names[1:], strict=False)):
        assert a != b or result.starts[i + 1] - result.starts[i] >= RESTART - 1e-9


def test_the_driver_asks_the_planner_for_each_window_and_cuts_the_last(shark):
    """The tracker's windows vary: ``Schedule.plan`` gives each control period its steps."""
    world = World([shark])
    asked, seen = [], []

    def plan(w: World) -> int:
        asked.append(w.step_count)
        return 7 if len(asked) % 2 else 4

    def decide(w: World, period) -> list[np.ndarray]:
        seen.append((period.start, period.steps))
        return [np.zeros((1, shark.n_actuators))]

    n = drive(world, decide, 20 * shark.dt, Schedule(1.0, plan=plan))
    assert seen == [(0, 7), (7, 4), (11, 7), (18, 2)] and n == 4
    assert asked == [0, 7, 11, 18] and world.step_count == 20


def test_tracking_is_deterministic_and_pure_distance_gain_stalls_behind(shark):
    rep = handmade_repertoire(shark)
    a = track(shark, rep, COURSE, TrackConfig(time_limit=12.0))
    b = track(shark, rep, COURSE, TrackConfig(time_limit=12.0))
    assert np.array_equal(a.positions, b.positions) and a.names == b.names
    # the literal reading (gain = distance drop only) keeps still when the target is behind
    behind = track(shark, rep, [[-3.0, 0.0]], TrackConfig(time_limit=5.0, turn_radius=0.0))
    assert set(behind.evaluations) == {"do-nothing"}


def test_bad_inputs_raise_tracking_errors(shark):
    rep = handmade_repertoire(shark)
    with pytest.raises(TrackingError, match="no entries"):
        track(shark, rep, COURSE, TrackConfig(allowed=("fly",)))
    with pytest.raises(TrackingError, match="at least one target"):
        track(shark, rep, np.zeros((0, 2)))
    with pytest.raises(TrackingError, match="2 comma-separated"):
        parse_points("1,2;3", 2, "--targets")
    with pytest.raises(TrackingError, match="numbers expected"):
        parse_points("1,a", 2, "--targets")
    assert parse_points("1,2; 3,-4.5;", 2, "x").tolist() == [[1, 2], [3, -4.5]]
    # targets: x,z at the start depth, or x,y,z with y above it
    assert parse_targets("1,2;3,-1,4").tolist() == [[1, 0, 2], [3, -1, 4]]
    with pytest.raises(TrackingError, match="'x,z' or 'x,y,z'"):
        parse_targets("1,2,3,4")


def test_a_target_passed_over_in_the_plane_but_far_below_is_not_reached(shark):
    """Reaching is judged in 3D: swimming over a target 3 m down does not reach it."""
    rep = handmade_repertoire(shark)  # no entry of it changes depth by metres
    below = track(shark, rep, [[1.5, -3.0, 0.0]], TrackConfig(time_limit=8.0))
    level = track(shark, rep, [[1.5, 0.0, 0.0]], TrackConfig(time_limit=8.0))
    xz = np.linalg.norm(below.com[:, [0, 2]] - below.targets[0, [0, 2]], axis=1)
    assert xz.min() < below.radius  # it passed within the radius in the horizontal plane
    assert np.isnan(below.reached[0]) and below.summary()["reached"] == 0
    assert np.isfinite(level.reached[0])  # the same point at the start depth is reached
    assert below.targets[0, 1] == pytest.approx(level.targets[0, 1] - 3.0)
    s = below.summary()
    assert abs(s["depth_change_m"]) < 1.0 and s["worst_roll_deg"] >= 0.0


def test_track_command_writes_its_run(tmp_path, memory, capsys, shark):
    out = tmp_path / "t1"
    targets = ";".join(f"{x},{z}" for x, z in COURSE)
    code = main(
        [
            "track",
            "shark",
            "--memory",
            str(memory),
            "--targets",
            targets,
            "--out",
            str(out),
            "--time-limit",
            "30",
            "--fps",
            "10",
        ]
    )
    assert code == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "reached 2/2" in text and "real time" in text and "worst roll" in text
    summary = json.loads((out / "summary.json").read_text())
    assert summary["reached"] == 2 and summary["realtime_factor"] > 1
    assert {"depth_change_m", "depth_span_m", "worst_roll_deg", "worst_pitch_deg"} <= set(summary)
    assert summary["replay_drift_m"] < 1e-3
    assert isinstance(load_controller(out / "controller.json", shark), SequenceController)
    assert (out / "path.png").stat().st_size > 5000
    import imageio.v3 as iio

    frames = iio.imread(out / "video.mp4")
    assert frames.shape[0] >= 10 * summary["simulated_s"] - 1


def _run_expect_error(capsys, memory, animal="shark", targets="1,0") -> str:
    code = main(
        [
            "track",
            animal,
            "--memory",
            str(memory),
            "--targets",
            targets,
            "--no-video",
            "--time-limit",
            "1",
            "--out",
            str(memory.parent / "out"),
        ]
    )
    assert code == 2
    return capsys.readouterr().err.replace("\n", "")


def test_broken_or_mismatched_repertoires_get_clear_errors(tmp_path, shark, capsys):
    empty = tmp_path / "empty"
    empty.mkdir()
    assert "no repertoire.json" in _run_expect_error(capsys, empty)

    broken = tmp_path / "broken"
    handmade_repertoire(shark).save(broken)
    (broken / "go-straight.json").write_text("{not json")
    err = _run_expect_error(capsys, broken)
    assert "go-straight.json" in err and "JSON" in err

    missing = tmp_path / "missing"
    handmade_repertoire(shark).save(missing)
    (missing / "wide-turn-left.json").unlink()
    assert "wide-turn-left.json" in _run_expect_error(capsys, missing)

    index = tmp_path / "index"
    handmade_repertoire(shark).save(index)
    (index / "repertoire.json").write_text(json.dumps({"animal": "shark", "entries": []}))
    assert "repertoire.json: missing 'actuators'" in _run_expect_error(capsys, index)

    other = tmp_path / "snake"
    handmade_repertoire(load_animal("snake")).save(other)
    err = _run_expect_error(capsys, other)
    assert "snake" in err and "shark" in err

    assert "numbers expected" in _run_expect_error(capsys, other, targets="a,b")


@pytest.mark.slow
def test_default_tracking_holds_depth_and_stays_upright(tmp_path, shark):
    """The default repertoire, tracked over level courses with the first target behind and a
    zigzag starting to the right, keeps the shark within half a metre of its start depth,
    and over those and a 3D course that dives while turning, within 30 degrees of upright
    (without the fins' righting the dive rolled 64 degrees)."""
    from zoetic.behavior.repertoire import Repertoire
    from zoetic.behavior.training import train_repertoire

    train_repertoire("shark", tmp_path / "memory")
    rep = Repertoire.load(tmp_path / "memory", shark)
    for course in ("-3,0;-3,3", "2,-2;4,0;6,-2;8,0", "3,-1,0;5,-2,2;4,-2,5"):
        r = track(shark, rep, parse_targets(course), TrackConfig(time_limit=60.0))
        s = r.summary()
        assert s["reached"] == s["targets"], (course, s)
        lo, hi = s["depth_span_m"]
        if course.count(",") == 2 * course.count(";") + 2:  # 3D: down 2 m, no deeper than 2.5
            assert -2.5 <= lo and hi <= 0.5, (course, s)
        else:
            assert -0.5 <= lo and hi <= 0.5, (course, s)
        assert s["worst_roll_deg"] <= 30.0, (course, s)


def test_roll_gathering_pace_costs_more_than_a_roll_that_settles(shark):
    """Two windows end at the same 10 degree roll; the one still rolling at 40 deg/s is
    judged where that roll leads (past the roll that costs nothing), the settled one not."""
    record_dt = 0.02
    t = np.arange(51) * record_dt
    rolling = 10.0 + 40.0 * (t - t[-1])  # -30 -> 10 deg, still at 40 deg/s
    settled = np.minimum(10.0, 40.0 * t)  # up to 10 deg, then level
    roll = np.stack([np.clip(rolling, -8, None), settled])
    pitch = np.zeros_like(roll)
    rest = np.repeat(shark.rest_pos[None, None], 51, axis=1)
    positions = np.repeat(rest, 2, axis=0)
    goal = shark.rest_pos.T @ (shark.mass / shark.total_mass) + [3.0, 0.0, 0.0]
    cost = cost_to_go(shark, positions, goal, 0.0, record_dt, TrackConfig(), (roll, pitch))
    assert cost[0] > cost[1] + 0.1  # m
    flat = TrackConfig(roll_lookahead=0.0)
    same = cost_to_go(shark, positions, goal, 0.0, record_dt, flat, (roll, pitch))
    assert same[0] == pytest.approx(same[1])


def test_fin_righting_variants_roll_the_shark_either_way(shark):
    """Each entry gets two variants with the pectoral fins tilted apart; swimming, they roll
    the shark opposite ways, as their names say (roll > 0: the back toward the right)."""
    from zoetic.behavior.repertoire import Repertoire
    from zoetic.behavior.tracking import righting_entries
    from zoetic.control.measure import motion_scalars
    from zoetic.physics import get_medium

    rep = handmade_repertoire(shark)
    assert isinstance(rep, Repertoire)
    names, ctrls = righting_entries(
        shark, ["go-straight"], [rep.controllers["go-straight"]], TrackConfig().fin_tilt
    )
    assert names == ["go-straight", "go-straight+roll-left", "go-straight+roll-right"]
    steps = int(4.0 / shark.dt)
    traj = simulate(shark, np.stack([c.table(steps, shark.dt) for c in ctrls]), record_every=10)
    roll = motion_scalars(shark, traj.positions, traj.times, get_medium(shark.medium))["roll"]
    assert roll[1, -1] < roll[0, -1] - 10 and roll[2, -1] > roll[0, -1] + 10  # deg
    # the muscles play as before: only the fins' offsets differ
    table = [c.table(10, shark.dt) for c in ctrls]
    muscles = np.array(shark.actuator_kind) == "muscle"
    assert np.array_equal(table[1][:, muscles], table[0][:, muscles])
    none = righting_entries(shark, ["go-straight"], [rep.controllers["go-straight"]], 0.0)
    assert none[0] == ["go-straight"]
