"""The command line through its real entry point: outputs, exit codes, clear errors."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from zoetic.bodies import load_animal
from zoetic.cli import main
from zoetic.control import save_controller, time_domain


def test_animals_lists_the_zoo(capsys):
    assert main(["animals"]) == 0
    out = capsys.readouterr().out
    for name in ("snake", "shark", "ray", "dolphin"):
        assert name in out
    assert "91" in out and "190" in out  # springs of the shark and the snake


def test_simulate_writes_record_video_and_path(tmp_path):
    from zoetic.record import read_record

    out = tmp_path / "first"
    code = main(["simulate", "shark", "--controller", "wave", "--seconds", "2", "--out", str(out)])
    assert code == 0
    rec = read_record(out)
    times, pos = rec.times, rec.animals[0].positions
    assert rec.kind == "simulate" and rec.animals[0].species == "shark"
    assert pos.shape == (len(times), 23, 3) and pos.dtype == np.float32
    assert rec.animals[0].activations.shape == (len(times), len(rec.animals[0].actuators))
    assert times[0] == 0.0 and times[-1] == pytest.approx(2.0)
    assert pos[-1, :, 0].mean() > pos[0, :, 0].mean() + 0.2  # it swam forward
    assert (out / "path.png").stat().st_size > 1000
    import imageio.v3 as iio

    frames = iio.imread(out / "video.mp4")
    assert frames.shape[0] >= 55 and frames.shape[-1] == 3


def test_simulate_rest_and_controller_file(tmp_path):
    body = load_animal("snake")
    ctrl = time_domain(body, 5, 1.0, np.full((body.n_actuators, 5), 0.3))
    save_controller(ctrl, tmp_path / "c.json")
    for spec in ("rest", str(tmp_path / "c.json")):
        out = tmp_path / spec.replace("/", "_")
        args = ["simulate", "snake", "--controller", spec, "--seconds", "1", "--out", str(out)]
        assert main([*args, "--no-video"]) == 0
        assert (out / "record.npz").exists()


def test_controller_for_another_animal_is_refused(tmp_path, capsys):
    shark = load_animal("shark")
    save_controller(time_domain(shark, 5, 1.0), tmp_path / "shark.json")
    code = main(
        [
            "simulate",
            "snake",
            "--controller",
            str(tmp_path / "shark.json"),
            "--out",
            str(tmp_path / "x"),
            "--no-video",
        ]
    )
    assert code == 2
    err = capsys.readouterr().err
    assert "shark.json" in err and "for the 'shark', not the 'snake'" in err


def test_bad_animal_file_exits_2_and_names_the_problem(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(
        'name = "blob"\nmedium = "water"\n[[nodes]]\npos = [0, 0, 0]\nmass = 1.0\n'
        "[[nodes]]\npos = [1, 0, 0]\nmass = -2.0\n"
    )
    assert main(["simulate", str(bad), "--out", str(tmp_path / "x"), "--no-video"]) == 2
    err = capsys.readouterr().err
    assert "bad.toml" in err and "mass must be positive" in err
    assert "Traceback" not in err


def test_unknown_animal_and_bad_controller_spec(tmp_path, capsys):
    assert main(["simulate", "unicorn", "--out", str(tmp_path / "x")]) == 2
    assert "unknown animal 'unicorn'" in capsys.readouterr().err
    assert main(["simulate", "shark", "--controller", "wiggle", "--out", str(tmp_path)]) == 2
    assert "not a controller file" in capsys.readouterr().err


def test_usage_errors_exit_2_without_a_traceback(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "zoetic", "simulate", "shark", "--bogus"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2
    assert "No such option: --bogus" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_console_script_runs_and_bench_prints_json(tmp_path):
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "zoetic",
            "bench",
            "simulate",
            "--json",
            "--seconds",
            "0.5",
            "--batch",
            "16",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout)
    for key in (
        "animal",
        "dt",
        "sim_seconds_per_second_single",
        "sim_seconds_per_second_batched",
        "numpy_reference_sim_seconds_per_second",
        "speedup_vs_numpy",
        "cores",
        "closed_loop_overhead",
        "closed_loop_overhead_wall",
        "closed_loop_over_simulate_wall",
    ):
        assert key in result
    assert result["speedup_vs_numpy"] > 1
    assert result["closed_loop_overhead"] > 0.5


def test_every_benchmark_is_a_bench_subcommand(capsys):
    assert main(["bench", "--help"]) == 0
    out = capsys.readouterr().out
    for name in (
        "simulate",
        "jax",
        "learn",
        "skills",
        "san",
        "ray",
        "gym",
        "vision",
        "aquarium",
        "stunts",
    ):
        assert f" {name} " in out, name


def test_learn_cli_and_tasks(tmp_path, capsys):
    assert main(["tasks"]) == 0
    listing = capsys.readouterr().out
    assert "swim-straight" in listing and "from rest and cruising" in listing
    out = tmp_path / "run"
    code = main(
        [
            "learn",
            "shark",
            "--optimizer",
            "cmaes",
            "--budget",
            "40",
            "--popsize",
            "8",
            "--out",
            str(out),
            "--no-video",
        ]
    )
    assert code == 0
    for name in (
        "config.toml",
        "controller.json",
        "history.csv",
        "learning.png",
        "controller.png",
        "checkpoint.npz",
        "record.npz",
    ):
        assert (out / name).exists(), name
    from zoetic.record import read_record

    rec = read_record(out)  # the best controller's run, as the viewer shows it
    assert rec.kind == "learn" and rec.numbers["task"] == "swim-straight"
    assert rec.times[-1] > 0 and rec.animals[0].activations is not None
    # the learned controller plays back through simulate
    assert (
        main(
            [
                "simulate",
                "shark",
                "--controller",
                str(out / "controller.json"),
                "--seconds",
                "1",
                "--out",
                str(tmp_path / "play"),
                "--no-video",
            ]
        )
        == 0
    )
    # a finished run refuses to be overwritten, and resumes as a no-op
    assert main(["learn", "shark", "--out", str(out), "--budget", "40"]) == 2
    assert main(["learn", "--resume", str(out), "--no-video"]) == 0


def test_cli_lets_the_kernels_threads_sleep_unless_told_otherwise(monkeypatch, capsys):
    """The command line asks OpenMP (the kernel's thread pool) to sleep between calls rather
    than spin, before any kernel runs; a policy already in the environment is kept."""
    monkeypatch.delenv("OMP_WAIT_POLICY", raising=False)
    assert main(["animals"]) == 0
    assert os.environ["OMP_WAIT_POLICY"] == "PASSIVE"
    monkeypatch.setenv("OMP_WAIT_POLICY", "ACTIVE")
    assert main(["animals"]) == 0
    assert os.environ["OMP_WAIT_POLICY"] == "ACTIVE"


@pytest.mark.parametrize(("argv", "frozen"), [("None", True), ("['animals']", False)])
def test_the_command_lines_process_exits_without_collecting_its_survivors(argv, frozen):
    """The process's own command line (main reads sys.argv) collects its young objects less
    often and freezes the objects still alive at exit, after the other exit handlers, so
    that shutdown does not walk them for cycles; main called by a program with its
    arguments leaves its collector alone."""
    code = (
        "import atexit, gc, sys\n"
        "atexit.register(lambda: print('frozen', gc.get_freeze_count() > 0))\n"
        "from zoetic.cli import COMMAND_GC_THRESHOLD, main\n"
        "sys.argv = ['zoetic', 'animals']\n"
        "code = main(" + argv + ")\n"
        "print('raised', gc.get_threshold()[0] == COMMAND_GC_THRESHOLD > 700)\n"
        "sys.exit(code)\n"
    )
    run = [sys.executable, "-c", code]
    out = subprocess.run(run, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert "shark" in out.stdout
    assert out.stdout.split()[-4:] == ["raised", str(frozen), "frozen", str(frozen)]
