"""An entry that breaks a promise of its task is learned again from a derived seed; one that
keeps them is not (behavior.restarts)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from zoetic.behavior import restarts
from zoetic.behavior.repertoire import INDEX, Repertoire
from zoetic.behavior.training import (
    Entry,
    learned_entry,
    plan_for,
    rest_abstraction,
    train_repertoire,
)
from zoetic.bodies import load_animal
from zoetic.cli import main
from zoetic.control import wave_controller
from zoetic.learning.run import Run
from zoetic.tasks import load_task

BROKEN = "wide-turn-left"  # the entry the fake judge finds broken on its first try


@pytest.fixture(scope="module")
def shark():
    return load_animal("shark")


def _verdict(task, met: bool) -> dict:
    """A judge_entry verdict of ``task``: every promise kept, or every one missed by far."""
    out = [{"promise": p.text(), "worst": 1e6, "start": "rest", "met": met} for p in task.promises]
    return {"task": task.name, "met": met, "promises": out}


def _fake_judge(monkeypatch, broken_tries: int) -> list[str]:
    """Judge every entry as keeping its promises except ``BROKEN``'s first ``broken_tries``
    tries; return the list of tasks judged, in order."""
    judged: list[str] = []

    def judge(body, ctrl, task):
        judged.append(task.name)
        return _verdict(task, task.name != BROKEN or judged.count(BROKEN) > broken_tries)

    monkeypatch.setattr(restarts, "judge_entry", judge)
    return judged


def _index(out) -> dict:
    return {e["name"]: e for e in json.loads((out / INDEX).read_text())["entries"]}


def test_a_broken_promise_restarts_its_entry_and_a_kept_one_does_not(tmp_path, monkeypatch, capsys):
    judged = _fake_judge(monkeypatch, broken_tries=1)
    train_repertoire("shark", tmp_path, budget=12, seed=3)
    runs = sorted(p.name for p in (tmp_path / "runs").iterdir())
    assert [r for r in runs if ".restart" in r] == [f"{BROKEN}.restart1"]  # kept at once
    assert judged.count(BROKEN) == 2
    entries = _index(tmp_path)
    record = entries[BROKEN]["restarts"]
    assert entries[BROKEN]["source"] == record["kept"] == f"runs/{BROKEN}.restart1"
    k = [e.name for e in plan_for(load_animal("shark"))].index(BROKEN)
    assert [t["seed"] for t in record["tries"]] == [3 + k, restarts.restart_seed(3 + k, 1)]
    assert [t["met"] for t in record["tries"]] == [False, True]
    assert "does not do what task" in record["because"]
    assert all("restarts" not in e for n, e in entries.items() if n != BROKEN)
    # the entry is the restart's abstraction (as saved, to 6 digits), not the first try's;
    # its mirror follows it
    assert entries["wide-turn-right"]["source"] == f"mirror of {BROKEN}"
    rep = Repertoire.load(tmp_path)
    shark = load_animal("shark")
    for name, same in ((BROKEN, False), (f"{BROKEN}.restart1", True)):
        ab, _ = learned_entry(
            shark, _entry(BROKEN), Run.resume(tmp_path / "runs" / name), "periodic", "auto", 0.3
        )
        assert (
            np.allclose(
                _table(ab.controller, shark), _table(rep.controllers[BROKEN], shark), atol=1e-5
            )
            == same
        )
    # repertoire show says which entry was learned again, why, and which try it keeps
    assert main(["repertoire", "show", str(tmp_path)]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert f"{BROKEN}: learned again: entry '{BROKEN}' does not do what task" in text
    assert f"kept: runs/{BROKEN}.restart1" in text and "keeps every promise" in text


def _entry(name: str) -> Entry:
    return next(e for e in plan_for(load_animal("shark")) if e.name == name)


def _table(ctrl, body) -> np.ndarray:
    return ctrl.table(200, body.dt)


def test_restarts_stop_at_their_number_and_resume_to_the_same_repertoire(tmp_path, monkeypatch):
    judged = _fake_judge(monkeypatch, broken_tries=99)
    train_repertoire("shark", tmp_path, budget=12, seed=0)
    restarted = sorted(p.name for p in (tmp_path / "runs").iterdir() if ".restart" in p.name)
    assert restarted == [f"{BROKEN}.restart{n}" for n in range(1, restarts.RESTARTS + 1)]
    assert judged.count(BROKEN) == 1 + restarts.RESTARTS
    before = (tmp_path / INDEX).read_bytes()
    record = _index(tmp_path)[BROKEN]["restarts"]
    assert [t["met"] for t in record["tries"]] == [False] * (1 + restarts.RESTARTS)
    # every try misses as far: the first, which broke least first, is kept
    assert record["kept"] == f"runs/{BROKEN}"
    # a run of restarts cut short (its checkpoint gone: learned from scratch again, from the
    # same seed) and the training run again: the same repertoire, bit for bit
    last = tmp_path / "runs" / f"{BROKEN}.restart{restarts.RESTARTS}"
    (last / "checkpoint.npz").unlink()
    train_repertoire("shark", tmp_path, budget=12, seed=0)
    assert (tmp_path / INDEX).read_bytes() == before


def test_the_try_that_breaks_least_is_kept(shark):
    task = load_task("quick-turn-left")
    entry = Entry("sharp-turn-left", task)

    def tried(turn: float, roll: float, n: int):
        values = {"turn_deg": turn, "roll_deg": roll, "climb_m": 0.0, "radius_bl": 1.0}
        promises = []
        for p in task.promises:
            v = values[p.quantity]
            promises.append(
                {"promise": p.text(), "worst": v, "start": "rest", "met": p.low <= v <= p.high}
            )
        verdict = {"task": task.name, "met": all(o["met"] for o in promises), "promises": promises}
        return (object(), {"source": f"runs/try{n}"}), verdict, n

    # 89.8 degrees of turn (one promise, just missed) beats a roll of 180 (one, far) and two
    assert (
        restarts._choose(entry, [tried(80.0, 179.8, 0), tried(89.8, 0.0, 1)])[1]["source"]
        == "runs/try1"
    )
    assert (
        restarts._choose(entry, [tried(89.8, 0.0, 0), tried(80.0, 0.0, 1)])[1]["source"]
        == "runs/try0"
    )
    # a restart that keeps every promise wins over the first try, however close that came
    _, info = restarts._choose(entry, [tried(89.99, 0.0, 0), tried(120.0, 5.0, 1)])
    assert info["source"] == info["restarts"]["kept"] == "runs/try1"
    assert info["restarts"]["tries"][0]["broken"] == ["turn_deg >= 90"]


def test_a_climb_longer_than_the_straight_swims_straight_line_is_beyond_reach(shark):
    up = load_task("swim-up")
    # an animal that does not swim cannot rise 0.5 m from rest
    reason = restarts.beyond_reach(shark, up, rest_abstraction(shark))
    assert reason is not None and "from rest" in reason and "climb_m" in reason
    # the shark's wave swims about 0.37 m/s: 3 s of it is path enough for a 0.5 m rise
    assert restarts.beyond_reach(shark, up, wave_controller(shark)) is None
    # a promise that asks no rise or sink (|climb| <= 0.3 m) is never beyond reach
    level = load_task("quick-turn-left")
    assert restarts.beyond_reach(shark, level, rest_abstraction(shark)) is None


def test_restart_seeds_differ_from_the_entry_seeds_and_each_other():
    seeds = {restarts.restart_seed(s, a) for s in range(10) for a in (1, 2)}
    assert len(seeds) == 20 and not seeds & set(range(20))
    assert restarts.restart_seed(4, 1) == restarts.restart_seed(4, 1)
    assert all(0 <= s < 2**63 for s in seeds) and np.all(np.isfinite(list(seeds)))


@pytest.mark.parametrize("straight_kept", [True, False])
def test_only_a_straight_swim_that_keeps_its_promises_bounds_the_climbs(
    tmp_path, monkeypatch, straight_kept
):
    broken = {"swim-up"} | (set() if straight_kept else {_entry("go-straight").task.name})
    monkeypatch.setattr(restarts, "RESTARTS", 0)
    monkeypatch.setattr(restarts, "judge_entry", lambda b, c, t: _verdict(t, t.name not in broken))
    bounds: dict[str, object] = {}

    def reach(body, task, straight):
        bounds[task.name] = straight
        return None

    monkeypatch.setattr(restarts, "beyond_reach", reach)
    train_repertoire("shark", tmp_path, budget=12, seed=3)
    assert "swim-up" in bounds
    assert (bounds["swim-up"] is not None) == straight_kept
