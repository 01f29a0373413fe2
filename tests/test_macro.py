"""Macro controllers: plans become cross-faded sequences, scores are right on known paths, both
searches are reproducible, stay in bounds and improve, a fish's plans are judged as it swims
them with its righting reflex, and the command writes a run whose controller replays it."""

from __future__ import annotations

import json

import numpy as np
import pytest

from zoetic.behavior.handmade import handmade_repertoire
from zoetic.behavior.macro import (
    MacroProblem,
    PlanAnnealing,
    PlanGenetic,
    ReachTask,
    path_scores,
    search,
)
from zoetic.behavior.targets import TrackingError
from zoetic.behavior.tracking import TrackConfig
from zoetic.bodies import load_animal
from zoetic.cli import main
from zoetic.control import load_controller
from zoetic.control.abstract import SequenceController
from zoetic.control.measure import locomotion
from zoetic.control.rollout import rollout
from zoetic.physics.world import World
from zoetic.record import read_record

# a short task: a goal ahead and to the left, past a small disc on the straight line to it
TASK = ReachTask(goal=(1.8, 0.8), obstacles=((0.9, 0.3, 0.3),), horizon=6.0)


@pytest.fixture(scope="module")
def problem():
    shark = load_animal("shark")
    return MacroProblem(shark, handmade_repertoire(shark), TASK, segments=3)


def test_plan_is_a_cross_faded_sequence(problem):
    e, d = np.array([1, 2, 0]), np.array([2.0, 1.0, 4.0])
    seq = problem.sequence(e, d)
    assert isinstance(seq, SequenceController) and seq.overlap == 0.05
    assert np.allclose(seq.starts(), [0.0, 1.9, 2.85])
    assert [c for c, _ in seq.items] == [problem.ctrls[i] for i in e]


def test_path_scores_on_known_paths():
    t = np.linspace(0.0, 4.0, 41)  # 0.1 s apart, along x at 1 m/s
    com = np.stack([np.column_stack([t, 0 * t]), np.column_stack([0 * t, t])])
    task = ReachTask(goal=(3.0, 0.0), obstacles=((1.0, 0.0, 0.5),), horizon=4.0, time_weight=0.0)
    s = path_scores(com, 0.1, task, radius=0.5)
    assert s["closest"] == pytest.approx([0.0, 3.0])
    assert s["final"] == pytest.approx([1.0, 5.0])
    assert s["inside"] == pytest.approx([1.0, 0.0], abs=0.11)  # x in (0.5, 1.5)
    assert s["reach"][0] == pytest.approx(2.6) and np.isnan(s["reach"][1])
    assert s["cost"] == pytest.approx(s["final"] + s["inside"])


def test_batch_evaluation_matches_one_at_a_time(problem):
    e, d = problem.random(np.random.default_rng(1), 4)
    batch = problem.evaluate(e, d)["cost"]
    single = [problem.evaluate(e[i : i + 1], d[i : i + 1])["cost"][0] for i in range(4)]
    assert np.allclose(batch, single, atol=1e-4)


@pytest.mark.parametrize("method", ["anneal", "ga"])
def test_search_improves_is_reproducible_and_stays_in_bounds(problem, method):
    options = {"chains": 8} if method == "anneal" else {"popsize": 12}
    a = search(problem, method, budget=96, seed=3, **options)
    b = search(problem, method, budget=96, seed=3, **options)
    assert a.entries.tolist() == b.entries.tolist() and np.allclose(a.durations, b.durations)
    best = [f for _, f in a.history]
    assert all(x >= y for x, y in zip(best, best[1:], strict=False))  # best never gets worse
    assert best[-1] < best[0]
    assert a.scores["cost"] == pytest.approx(best[-1], abs=1e-6)
    assert a.evaluations >= 96
    assert ((problem.lower <= a.durations) & (a.durations <= problem.upper)).all()
    assert set(a.names) <= set(problem.names)


def test_failed_plans_never_become_best(problem):
    opt = PlanGenetic(problem, seed=0, popsize=6)
    e, d = opt.ask()
    opt.tell(e, d, np.array([np.nan, np.inf, 5.0, 4.0, np.nan, 6.0]))
    assert opt.best_f == 4.0 and opt.best[0].tolist() == e[3].tolist()
    sa = PlanAnnealing(problem, seed=0, chains=4)
    e, d = sa.ask()
    sa.tell(e, d, np.array([1.0, 2.0, 3.0, 4.0]))
    e2, d2 = sa.ask()
    sa.tell(e2, d2, np.full(4, np.nan))
    assert np.array_equal(sa.e, e) and sa.best_f == 1.0  # no failed move was accepted
    for _ in range(3):
        e3, d3 = opt.ask()
        assert e3.min() >= 0 and e3.max() < problem.entries
        assert ((problem.lower <= d3) & (d3 <= problem.upper)).all()
        opt.tell(e3, d3, np.arange(len(e3), dtype=float))


def test_problem_rejects_bad_set_ups(problem):
    shark, rep = problem.body, handmade_repertoire(problem.body)
    with pytest.raises(TrackingError, match="no entries"):
        MacroProblem(shark, rep, TASK, allowed=("jump",))
    with pytest.raises(TrackingError, match="durations"):
        MacroProblem(shark, rep, TASK, durations=(2.0, 1.0))
    with pytest.raises(TrackingError, match="unknown search method"):
        search(problem, "tabu", budget=1)


def test_macro_command_writes_its_run(tmp_path, capsys):
    shark = load_animal("shark")
    memory = tmp_path / "memory"
    handmade_repertoire(shark).save(memory)
    out = tmp_path / "m1"
    args = [
        "macro",
        "shark",
        "--memory",
        str(memory),
        "--goal",
        "1.8,0.8",
        "--obstacle",
        "0.9,0.3,0.3",
        "--horizon",
        "5",
        "--segments",
        "3",
        "--budget",
        "48",
        "--out",
        str(out),
        "--fps",
        "10",
    ]
    assert main([*args, "--method", "anneal"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["method"] == "anneal" and len(summary["plan"]) == 3
    assert summary["obstacles_xzr"] == [[0.9, 0.3, 0.3]]
    assert {"cost", "final_m", "closest_m", "inside_obstacle_s", "history"} <= set(summary)
    # searched and played with the righting reflex (by default): one window a second
    assert summary["righting"]["windows"] == 5 and summary["replay_drift_m"] < 1e-6
    assert {"worst_roll_deg", "worst_pitch_deg", "turn_deg", "depth_change_m"} <= set(summary)
    # the controller written, played from rest, swims the recorded path
    ctrl = load_controller(out / "controller.json", shark)
    assert isinstance(ctrl, SequenceController)
    rec = read_record(out)
    t, pos = _played(shark, ctrl, float(rec.times[-1]))
    assert np.allclose(t, rec.times, atol=1e-6)
    assert np.abs(pos - rec.animals[0].positions).max() < 1e-4  # m (the record is float32)
    assert (out / "path.png").stat().st_size > 5000 and (out / "video.mp4").exists()
    text = capsys.readouterr().out
    assert "final distance" in text and "a righting variant played in" in text
    # --no-righting: searched and played as planned, the controller the plan itself
    off = out.parent / "off"
    plain = [*args[:-4], "--out", str(off), "--no-video", "--no-righting"]
    assert main(plain) == 0 and "righting reflex: off" in capsys.readouterr().out
    summary = json.loads((off / "summary.json").read_text())
    assert summary["righting"] == {} and summary["replay_drift_m"] < 1e-6
    items = load_controller(off / "controller.json", shark).items
    rep = handmade_repertoire(shark)
    planned = [rep.controllers[p["entry"]].to_dict() for p in summary["plan"]]
    assert [c.to_dict() for c, _ in items] == planned
    assert main([*args, "--method", "simplex", "--no-video"]) == 2  # out holds a run
    assert "--force" in capsys.readouterr().err
    args[args.index("--out") + 1] = str(out.parent / "another")
    assert main([*args, "--method", "simplex", "--no-video"]) == 2
    assert "unknown search method" in capsys.readouterr().err
    assert main([*args[:8], "--obstacle", "1,1,-1", "--no-video"]) == 2
    assert "radii must be positive" in capsys.readouterr().err


def test_plan_annealing_runs_on_the_one_annealing_of_learn(problem):
    from zoetic.learning.optimizers import Annealing

    sa = PlanAnnealing(problem, seed=0, chains=4)
    assert isinstance(sa.sa, Annealing) and sa.sa.relative
    e, d = sa.ask()
    sa.tell(e, d, np.array([2.0, 4.0, 6.0, 8.0]))
    assert sa.sa.scale == 5.0  # temperatures in units of the chains' mean starting cost
    assert np.array_equal(sa.sa.x[:, : problem.segments], e)


def _played(body, seq, seconds: float):
    """The controller played from rest in a World: times (R,) and positions (R, N, 3)."""
    steps = int(round(seconds / body.dt))
    ro = rollout(World([body]), seq.table(steps, body.dt)[None], seconds, seconds, record_every=4)
    tr = ro.trajectory(0)
    return tr.times, tr.positions[0]


def test_a_fish_is_judged_as_it_swims_upright(problem):
    shark, rep = problem.body, handmade_repertoire(problem.body)
    task = ReachTask(goal=(6.0, 3.0), horizon=13.0)
    righted = MacroProblem(shark, rep, task, segments=3, righting=TrackConfig())
    plain = MacroProblem(shark, rep, task, segments=3)
    # go straight, turn left, go straight: as planned the shark rolls past 30 degrees
    e = np.array([[1, 2, 1], [1, 4, 7]])
    d = np.array([[4.0, 3.0, 6.0], [2.2, 3.1, 1.6]])
    assert np.allclose(righted.played(d[1]) * 0.95, [2.0, 3.0, 2.0])  # whole 1 s windows
    assert np.allclose(righted.sequence(e[1], d[1]).starts(), [0.0, 2.0, 5.0])
    before, after = plain.evaluate(e[:1], d[:1]), righted.evaluate(e, d)
    assert before["roll"][0] > 30.0 and after["roll"][0] < 30.0
    # the worst roll past 30 degrees costs 5 m a radian, on top of the reach and depth terms
    b = {k: float(v[0]) for k, v in before.items()}
    t_cost = b["reach"] if np.isfinite(b["reach"]) else task.horizon
    reach = b["final"] + task.time_weight * t_cost + task.depth_weight * max(b["depth"] - 0.5, 0)
    assert b["cost"] == pytest.approx(reach + 5.0 * np.radians(b["roll"] - 30.0))
    # side by side in one World as one at a time; the played path is the one judged
    one = righted.evaluate(e[1:], d[1:])
    assert after["cost"][1] == pytest.approx(one["cost"][0], abs=1e-4)
    played = righted.righted(e[:1], d[:1]).result(0)
    motion = locomotion(shark, played.positions, played.times)
    assert motion["worst_roll_deg"] == pytest.approx(after["roll"][0], abs=0.1)
    assert 0 < played.summary()["windows_righted"] < 13
    # its recorded controller, played from rest, swims that path
    t, pos = _played(shark, played.sequence, float(played.times[-1]))
    n = min(len(t), len(played.times))
    assert np.allclose(t[:n], played.times[:n])
    assert np.nanmax(np.abs(pos[:n] - played.positions[:n])) < 1e-6  # m
    # the search over righted plans is seeded: the same plan and cost twice
    a, b = (search(righted, "ga", budget=16, seed=1, popsize=8) for _ in range(2))
    assert a.entries.tolist() == b.entries.tolist() and a.scores["cost"] == b.scores["cost"]
    assert a.scores["cost"] == pytest.approx(a.history[-1][1], abs=1e-4)


def test_search_evaluates_plans_with_blas_on_one_thread(problem, monkeypatch):
    """A plan search's batches run with BLAS held to one thread (its idle threads spin against
    the kernel's on the same cores), and the limit is lifted when the search ends."""
    from threadpoolctl import threadpool_info, threadpool_limits

    def blas_threads() -> set[int]:
        return {i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}

    seen: list[set[int]] = []
    real = type(problem).evaluate

    def evaluate(self, e, d, *args, **kw):
        seen.append(blas_threads())
        return real(self, e, d, *args, **kw)

    monkeypatch.setattr(type(problem), "evaluate", evaluate)
    with threadpool_limits(limits=2, user_api="blas"):  # as on 2 cores, even on one
        search(problem, "ga", budget=16, seed=1, popsize=8)
        assert seen and all(s == {1} for s in seen)
        assert blas_threads() == {2}
