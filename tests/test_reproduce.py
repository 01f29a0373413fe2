"""zoetic reproduce: the claims registry is complete, committed run records match today's
files, the JSON listing parses, and a rerun records what it loaded."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from zoetic.cli import main
from zoetic.errors import ZoeticError
from zoetic.reproduce.provenance import REPO, changed_files, sha256
from zoetic.reproduce.regenerate import FIGURES, claim_row, run_experiment
from zoetic.reproduce.registry import STATUSES, Experiment, load_registry

RUNS = sorted((FIGURES / "records").glob("*.json"))


def test_registry_has_40_claims_each_with_status_and_command_or_reason():
    reg = load_registry()
    assert len(reg.claims) >= 40
    assert {c.paper for c in reg.claims} == {"gt95", "vdpf93", "trg"}
    for c in reg.claims:
        assert c.status in STATUSES, c.id
        assert c.says and c.where and c.ours and c.explanation, c.id
        if c.experiment is None:
            assert c.absent and len(c.absent) > 10, f"{c.id}: no experiment and no reason"
            continue
        command = reg.experiments[c.experiment].command
        if command[0] != "-m":
            assert (REPO / command[0]).is_file(), f"{c.id}: {command[0]} is missing"


@pytest.mark.parametrize("record", RUNS, ids=[p.stem for p in RUNS])
def test_committed_run_record_matches_todays_files(record: Path):
    """A committed figure was made from files that have since changed: rerun its claim."""
    rec = json.loads(record.read_text())
    assert rec["files"], f"{record.name}: the run recorded no animal/creature/task file"
    changed = changed_files(rec["files"])
    assert not changed, (
        f"{record.name} was made from files that changed since ({', '.join(changed)}); "
        f"rerun `zoetic reproduce <claim> --{'quick' if rec['mode'] == 'quick' else ''}`"
    )
    for rel, digest in rec["outputs"].items():
        assert sha256(REPO / rel) == digest, f"{rel} is not the figure {record.name} made"


def test_reproduce_json_parses(capsys):
    assert main(["reproduce", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    reg = load_registry()
    assert [r["id"] for r in rows] == [c.id for c in reg.claims]
    for r in rows:
        assert {"id", "paper", "status", "stale"} <= set(r)
        assert isinstance(r["stale"], bool)


def test_unknown_claim_exits_2_with_a_suggestion(capsys):
    assert main(["reproduce", "gt95-fig7a-time-convx"]) == 2
    assert "gt95-fig7a-time-convex" in capsys.readouterr().err


def test_claim_without_experiment_says_why(tmp_path, monkeypatch, capsys):
    """A claim that nothing regenerates names why (its ``absent``) and exits 2."""
    from zoetic.reproduce import registry

    text = (REPO / "src/zoetic/reproduce/claims.toml").read_text()
    start = text.index('id = "gt95-fig8-energy"')
    end = text.index("[[claims]]", start)
    absent = """id = "gt95-fig8-energy"
paper = "gt95"
where = "section 4.2"
says = "less energy expenditure"
ours = "not measured"
status = "absent"
explanation = "no experiment integrates the muscles' work"
absent = "needs a muscle-work measure"

"""
    path = tmp_path / "claims.toml"
    path.write_text(text[:start] + absent + text[end:])
    monkeypatch.setattr(registry, "REGISTRY", path)
    monkeypatch.setattr(registry.load_registry, "__defaults__", (path,))
    assert main(["reproduce", "gt95-fig8-energy"]) == 2
    assert "muscle-work" in capsys.readouterr().err


def test_bad_registry_names_file_and_claim(tmp_path):
    text = (REPO / "src/zoetic/reproduce/claims.toml").read_text()
    bad = tmp_path / "claims.toml"
    bad.write_text(text.replace('status = "partly"', 'status = "sort of"', 1))
    with pytest.raises(ZoeticError, match=r"claims.toml: claim '[\w-]+': status"):
        load_registry(bad)


def test_rerun_records_the_files_it_loaded_and_goes_stale_when_they_change(tmp_path):
    """A tiny experiment loads the shark and a task; the record names both with their hashes,
    the claim is fresh, and a record whose hash no longer matches makes it stale."""
    script = tmp_path / "tiny.py"
    script.write_text(
        "import json, os, pathlib\n"
        "from zoetic.bodies import load_animal\nfrom zoetic.tasks import load_task\n"
        "load_animal('shark'); load_task('swim-straight')\n"
        "out = pathlib.Path(os.environ['ZOETIC_FIGURES'])\n"
        "(out / 'tiny.json').write_text(json.dumps({'a': {'b': [1, 2.5]}}))\n"
    )
    exp = Experiment("tiny", (str(script),), (), (), ("tiny.json",), False, "")
    rec = run_experiment(exp, quick=True, figures=tmp_path / "figs")
    assert rec["files"]["src/zoetic/bodies/zoo/shark.toml"]["kind"] == "animal"
    assert rec["files"]["src/zoetic/tasks/swim-straight.toml"]["kind"] == "task"
    shark = REPO / "src/zoetic/bodies/zoo/shark.toml"
    assert rec["files"]["src/zoetic/bodies/zoo/shark.toml"]["sha256"] == sha256(shark)
    assert rec["numbers"]["tiny.json"] == {"a": {"b": [1, 2.5]}}
    assert rec["command"].startswith("python ")

    reg = load_registry()
    claim = reg.claims[0]
    reg.experiments["tiny"] = exp  # route the first claim to the tiny experiment
    object.__setattr__(claim, "experiment", "tiny")
    object.__setattr__(claim, "keys", ("tiny.json:a/b/1",))
    row = claim_row(reg, claim, figures=tmp_path / "figs")
    assert row["stale"] is False and row["run"]["values"] == {"tiny.json:a/b/1": 2.5}

    path = tmp_path / "figs" / "records" / "tiny.quick.json"
    doc = json.loads(path.read_text())
    doc["files"]["src/zoetic/bodies/zoo/shark.toml"]["sha256"] = "0" * 64
    path.write_text(json.dumps(doc))
    row = claim_row(reg, claim, figures=tmp_path / "figs")
    assert row["stale"] is True
    assert row["run"]["changed_inputs"] == ["src/zoetic/bodies/zoo/shark.toml"]


def test_failing_experiment_is_a_clear_error(tmp_path):
    script = tmp_path / "broken.py"
    script.write_text("raise SystemExit('no such animal: kraken')\n")
    exp = Experiment("broken", (str(script),), (), (), (), False, "")
    with pytest.raises(ZoeticError, match=r"(?s)broken: exited with 1.*kraken"):
        run_experiment(exp, quick=True, figures=tmp_path / "figs")
    assert not (tmp_path / "figs" / "records" / "broken.quick.json").exists()


@pytest.mark.slow
def test_quick_regenerate_of_a_real_claim(tmp_path):
    """fig7 at a 3 x 3 grid: the run loads the shark and reach-goal and records its numbers."""
    reg = load_registry()
    exp = reg.experiments["fig7"]
    small = Experiment(exp.name, exp.command, ("--grid", "3"), (), exp.outputs, False, "")
    rec = run_experiment(small, quick=True, figures=tmp_path)
    assert "src/zoetic/bodies/zoo/shark.toml" in rec["files"]
    assert "src/zoetic/tasks/reach-goal.toml" in rec["files"]
    assert set(rec["numbers"]["fig7.json"]) == {"time", "frequency"}


def test_rerun_past_its_timeout_is_stopped(tmp_path):
    script = tmp_path / "slow.py"
    script.write_text("import time\ntime.sleep(60)\n")
    exp = Experiment("slow", (str(script),), (), (), (), False, "")
    with pytest.raises(ZoeticError, match="slow: did not finish within 2 s"):
        run_experiment(exp, quick=True, timeout=2, figures=tmp_path / "figs")


def test_a_rerun_prints_its_own_numbers_not_the_claims_best_record(monkeypatch, capsys):
    """A quick rerun of a claim that also has a full record prints the quick run's values."""
    import zoetic.reproduce.regenerate as regenerate

    claim = load_registry().claim("gt95-sec3-paper-pipeline")
    numbers: dict = {}
    for i, key in enumerate(claim.keys):
        name, _, path = key.partition(":")
        node = numbers.setdefault(name, {})
        parts = path.split("/")
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = 1000 + i
    fake = {"mode": "quick", "wall_s": 1.0, "files": {}, "numbers": numbers}
    monkeypatch.setattr(regenerate, "run_experiment", lambda *a, **k: fake)
    assert main(["reproduce", "gt95-sec3-paper-pipeline", "--quick", "--json"]) in (0, None)
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert out["values"] == {k: 1000 + i for i, k in enumerate(claim.keys)}
