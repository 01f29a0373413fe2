"""``zoetic bench all``: the table is assembled from the benchmarks' own JSON (a fixture kept
from their --quick runs), each figure beside its same-run baseline, the paper's figure and the
previous figure; and every benchmark has a --quick form."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import typer

from zoetic.bench.figures import FIGURES, PAPERS
from zoetic.bench.summary import BENCHES, CPU_ONLY, run_all, save_reference, table_rows
from zoetic.cli import _register, app, main

QUICK = Path(__file__).parent / "data" / "bench_quick_results.json"


@pytest.fixture(scope="module")
def kept() -> dict:
    """What ``zoetic bench all --quick`` kept: every benchmark's JSON line, as it printed it."""
    return json.loads(QUICK.read_text())


def _bench_commands() -> dict:
    _register()
    return typer.main.get_command(app).commands["bench"].commands


def test_every_bench_command_has_a_quick_form():
    commands = _bench_commands()
    assert {"simulate", "learn", "aquarium", "jax", "stunts", "all"} <= set(commands)
    lacking = [
        name
        for name, cmd in commands.items()
        if not any("--quick" in p.opts and p.is_flag for p in cmd.params)
    ]
    assert lacking == []


def test_the_table_runs_every_bench_command():
    run = {b.argv[0] for b in BENCHES}
    assert run == set(_bench_commands()) - {"all"}  # a new bench command joins the table


def test_the_fixture_holds_every_bench_of_the_table(kept):
    assert kept["mode"] == "quick"
    assert set(kept["benches"]) == {b.key for b in BENCHES}


def _rows(rows: list[dict], key: str) -> list[dict]:
    return [r for r in rows if r["key"] == key]


def test_side_by_side_figures_are_divided_by_the_same_runs_baseline(kept):
    b = kept["benches"]
    rows = table_rows(b, "quick")
    (kernel,) = _rows(rows, "simulate.batched")
    sim = b["simulate"]
    assert kernel["value"] == sim["sim_seconds_per_second_batched"]
    assert kernel["reference"] == sim["numpy_reference_sim_seconds_per_second"]
    assert kernel["ratio"] == pytest.approx(kernel["value"] / kernel["reference"])
    assert kernel["source"] == "NumPy reference, this run"
    # a time: the reference over this run (times faster), here annealing over CMA-ES
    learn = b["learn"] | {"anneal_seconds": 12.0, "cmaes_seconds_to_match_anneal": 1.5}
    (cmaes,) = _rows(table_rows(b | {"learn": learn}, "quick"), "learn.cmaes")
    assert (cmaes["value"], cmaes["reference"], cmaes["ratio"]) == (1.5, 12.0, 8.0)
    # an optimizer that never matched annealing: its row stays, with no figure and no ratio
    learn = learn | {"cmaes_seconds_to_match_anneal": None}
    (cmaes,) = _rows(table_rows(b | {"learn": learn}, "quick"), "learn.cmaes")
    assert cmaes["value"] is None and cmaes["ratio"] is None
    (skin,) = _rows(rows, "render.skin")
    assert skin["ratio"] == pytest.approx(
        b["render"]["lattice_ms_per_frame"] / b["render"]["skin_ms_per_frame"]
    )
    (tank,) = _rows(rows, "aquarium.realtime")
    assert tank["reference"] == b["aquarium"]["physics_only_realtime_factor"]
    readme = [r for r in rows if r["key"].startswith("readme.")]
    assert len(readme) == len(b["readme"]["commands"]) > 0


def test_papers_figures_are_rates_at_any_size_and_times_only_at_full_size(kept):
    b = kept["benches"]
    quick, full = table_rows(b, "quick"), table_rows(b, "full")
    frames = [r for r in _rows(quick, "aquarium.frames") if r["reference"] == 4.0]
    assert len(frames) == 1 and frames[0]["source"] == PAPERS["tank"].source
    assert "4 frames/sec" in PAPERS["tank"].quote
    assert frames[0]["value"] == pytest.approx(b["aquarium"]["realtime_factor"] / 0.05)
    (san,) = _rows(quick, "san.search")
    assert san["reference"] == pytest.approx(1200 / 21600)  # 001: 6 hours for 200 walkers
    assert _rows(quick, "learn.anneal")[0]["reference"] is None  # 300 evaluations: no paper
    (anneal,) = _rows(full, "learn.anneal")
    assert anneal["reference"] == PAPERS["anneal"].value == 3600.0
    assert anneal["ratio"] == pytest.approx(3600.0 / b["learn"]["anneal_seconds"])


def test_counts_have_no_ratio_and_a_cpu_host_says_no_gpu(kept):
    rows = table_rows(kept["benches"], "quick")
    (reached,) = _rows(rows, "track.reached")
    assert "/" in reached["value"] and reached["ratio"] is None
    (gpu,) = _rows(rows, "jax.gpu")
    assert gpu["value"] == "no GPU" and gpu["ratio"] is None
    (cpu,) = _rows(rows, "jax.cpu")
    assert cpu["value"] == kept["benches"]["jax"]["jax"]["sim_seconds_per_second_batched"]
    on_gpu = {"jax": {"backend": "gpu", "sim_seconds_per_second_batched": 9e5}}
    on_cpu = {"jax": {"backend": "cpu", "sim_seconds_per_second_batched": 2e3}}
    both = kept["benches"] | {"jax": on_gpu, "jax-cpu": on_cpu}
    rows = table_rows(both, "quick")
    assert [r["value"] for r in _rows(rows, "jax.gpu") + _rows(rows, "jax.cpu")] == [9e5, 2e3]


def test_a_saved_reference_is_the_next_tables_previous_figure(kept, tmp_path):
    b = kept["benches"]
    ref = tmp_path / "reference.json"
    stamp = {"host": "cpu x2", "date": "2026-01-01", "commit": "abc1234"}
    saved = save_reference(ref, table_rows(b, "quick"), "quick", stamp)
    assert (
        saved["quick"]["simulate.batched"]["value"]
        == b["simulate"]["sim_seconds_per_second_batched"]
    )
    faster = json.loads(json.dumps(b))
    faster["simulate"]["sim_seconds_per_second_batched"] *= 2
    rows = _rows(table_rows(faster, "quick", saved), "simulate.batched")
    previous = [r for r in rows if r["source"].startswith("previous")]
    assert len(previous) == 1 and "cpu x2, 2026-01-01, abc1234" in previous[0]["source"]
    assert previous[0]["ratio"] == pytest.approx(2.0)
    assert not _rows(table_rows(faster, "full", saved), "simulate.batched")[-1][
        "source"
    ].startswith("previous")  # a quick figure is never the previous one of a full run


def test_run_all_runs_each_bench_once_and_jax_again_on_the_cpu_beside_a_gpu():
    calls = []

    def runner(argv, quick, env=None):
        calls.append((argv, quick, env))
        gpu = argv == ("jax",) and env is None
        return {"jax": {"backend": "gpu"}} if gpu else {"ok": 1}

    got, timings = run_all(True, ("simulate", "jax"), runner=runner)
    assert set(got) == set(timings) == {"simulate", "jax", "jax-cpu"}
    assert calls == [
        (("simulate",), True, None),
        (("jax",), True, None),
        (("jax",), True, CPU_ONLY),
    ]


def test_bench_all_prints_the_table_of_a_kept_run_and_names_failures(kept, tmp_path, capsys):
    broken = json.loads(json.dumps(kept))
    broken["benches"]["ray"] = {"error": "exit 1: no module named ray"}
    path = tmp_path / "results.json"
    path.write_text(json.dumps(broken))
    ref = tmp_path / "ref.json"
    argv = ["bench", "all", "--from", str(path), "--reference", str(ref)]
    assert main([*argv, "--save-reference"]) == 0
    first = capsys.readouterr().out
    assert "shark batched, all cores" in first and "NumPy reference" in first
    assert PAPERS["san"].quote in first  # the paper quoted under the table it is cited in
    assert "bench ray failed: exit 1: no module named ray" in first
    assert main([*argv, "--json"]) == 0
    table = json.loads(capsys.readouterr().out)
    assert table["mode"] == "quick"
    prev = [r for r in table["rows"] if r["source"].startswith("previous")]
    assert prev and all(r["ratio"] == pytest.approx(1.0) for r in prev if r["ratio"])
    assert {f.key for f in FIGURES} >= {r["key"] for r in prev if "." in r["key"]} - {
        r["key"] for r in prev if r["key"].startswith("readme.")
    }
    assert main(["bench", "all", "--only", "simulat"]) == 2
    assert "no such benchmark" in capsys.readouterr().err


def test_the_kept_reference_names_only_figures_of_the_table():
    kept = json.loads((Path(__file__).parents[1] / "bench" / "reference.json").read_text())
    known = {f.key for f in FIGURES}
    for mode, figures in kept.items():
        assert mode in ("quick", "full")
        for key, fig in figures.items():
            assert key in known or key.startswith("readme."), key
            assert {"value", "host", "date", "commit"} <= set(fig), key


def test_bad_results_and_reference_files_are_one_message_naming_them(kept, tmp_path, capsys):
    path = tmp_path / "results.json"
    path.write_text(json.dumps([1, 2]))
    assert main(["bench", "all", "--from", str(path)]) == 2
    assert "results.json: not the results of zoetic bench all" in capsys.readouterr().err
    path.write_text(json.dumps(kept))
    ref = tmp_path / "ref.json"
    ref.write_text(json.dumps({"full": {"simulate.batched": {"value": 1.0}}}))
    assert main(["bench", "all", "--from", str(path), "--reference", str(ref)]) == 2
    err = capsys.readouterr().err
    assert "ref.json: full.simulate.batched: needs value, host, date and commit" in err
    assert "Traceback" not in err


def test_the_quick_readme_bench_runs_each_block_up_to_its_first_long_command():
    from zoetic.bench.readme import QUICK_BLOCK_S, Block, commands_within

    lines = [
        "zoetic animals",
        "zoetic pursue  # [~11 s]",
        "zoetic demo  # [~2 min]",
        "zoetic tasks",
    ]
    text = "\n".join(lines)
    commands = Block("sh", text, "S", False, 1).commands()
    kept = commands_within(commands, QUICK_BLOCK_S)
    assert [c.argv[1] for c in kept] == ["animals", "pursue"]  # later ones may need demo's run
    assert commands_within(commands, None) == commands
