"""The Ray evaluator: same history as in-process, bit for bit, even when a worker is killed."""

from __future__ import annotations

import csv
import os
import signal
from pathlib import Path

import numpy as np
import pytest
import ray

from zoetic.cli import main
from zoetic.learning.evaluate import BatchEvaluator, make_evaluator
from zoetic.learning.ray_eval import RayEvaluator
from zoetic.learning.run import LearnConfig, Run

# every test here starts a Ray cluster (seconds each): the slow tier
pytestmark = pytest.mark.slow

CONFIG = dict(
    animal="snake", task="crawl-straight", optimizer="cmaes", budget=30, popsize=10, seed=5, nodes=4
)


@pytest.fixture(scope="module")
def local_ray():
    ray.init(
        num_cpus=2,
        object_store_memory=80 * 1024**2,
        include_dashboard=False,
        log_to_driver=False,
        configure_logging=False,
    )
    yield ray.get_runtime_context().gcs_address
    ray.shutdown()


def _history(evaluator, out: Path) -> tuple[np.ndarray, np.ndarray]:
    """Learn to the budget with ``evaluator``; return every candidate and its E, in order."""
    run = Run.create(out, LearnConfig(**CONFIG))
    while run.evaluations < run.setup.config.budget and run.step(evaluator):
        pass
    return np.array(run.log.X), np.array(run.log.E)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    return _history(BatchEvaluator(), tmp_path_factory.mktemp("batch"))


def test_same_history_as_in_process_bit_for_bit(local_ray, reference, tmp_path):
    ev = make_evaluator("ray", workers=2)
    try:
        X, E = _history(ev, tmp_path)
    finally:
        ev.close()
    assert len(E) == CONFIG["budget"]
    assert np.array_equal(X, reference[0]) and np.array_equal(E, reference[1])
    assert ray.is_initialized()  # a Ray the evaluator did not start is left running


def test_a_worker_killed_mid_run_loses_no_evaluation(local_ray, reference, tmp_path):
    killed: list[int] = []
    calls = {"n": 0}

    def kill_during_second_generation(ev: RayEvaluator) -> None:
        calls["n"] += 1
        if calls["n"] == 2:  # its sub-batches are in flight
            pid = ev.pids()[0]
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)

    ev = RayEvaluator(actors=2, on_submit=kill_during_second_generation)
    try:
        X, E = _history(ev, tmp_path)
        survivors = ev.pids()
    finally:
        ev.close()
    assert killed and killed[0] not in survivors and len(survivors) == 2  # restarted
    assert np.array_equal(X, reference[0]) and np.array_equal(E, reference[1])


def test_learn_cli_with_a_ray_address(local_ray, reference, tmp_path):
    c = CONFIG
    args = [
        "learn",
        c["animal"],
        "--task",
        c["task"],
        "--optimizer",
        c["optimizer"],
        "--budget",
        str(c["budget"]),
        "--popsize",
        str(c["popsize"]),
        "--nodes",
        str(c["nodes"]),
        "--seed",
        str(c["seed"]),
        "--no-video",
        "--out",
        str(tmp_path),
        "--evaluator",
        "ray",
        "--ray-address",
        local_ray,
    ]
    assert main(args) == 0
    with (tmp_path / "history.csv").open() as fh:
        assert [row["E"] for row in csv.DictReader(fh)] == [f"{e:.6g}" for e in reference[1]]
    assert 'evaluator = "ray"' in (tmp_path / "config.toml").read_text()


def test_repertoire_training_learns_on_ray(local_ray, tmp_path):
    from zoetic.behavior.training import train_repertoire

    class Stop(Exception):
        pass

    def progress(run) -> None:
        raise Stop  # one generation of one entry is enough to see where it was evaluated

    with pytest.raises(Stop):
        train_repertoire("snake", tmp_path, budget=10, nodes=4, progress=progress, evaluator="ray")
    learned = [p.parent for p in (tmp_path / "runs").glob("*/history.csv")]
    assert len(learned) == 1  # learned alone (a Ray run shares no rollouts), stopped after one
    assert 'evaluator = "ray"' in (learned[0] / "config.toml").read_text()
    assert len((learned[0] / "history.csv").read_text().splitlines()) > 10  # one CMA-ES generation


def test_san_search_on_ray_matches_the_process_pool(local_ray):
    from zoetic.san import load_creature
    from zoetic.san.search import search

    cart = load_creature("cart")
    here = search(cart, trials=6, seed=3, seconds=0.5, workers=1)
    on_ray = search(cart, trials=6, seed=3, seconds=0.5, workers=2, evaluator="ray")
    assert np.array_equal(here.metrics, on_ray.metrics)
    assert np.array_equal(here.distances, on_ray.distances) and np.ptp(here.distances) > 0


def test_macro_search_on_ray_matches_in_process(local_ray):
    from zoetic.behavior.handmade import handmade_repertoire
    from zoetic.behavior.macro import MacroProblem, ReachTask, search
    from zoetic.bodies import load_animal

    shark = load_animal("shark")
    task = ReachTask(goal=(1.8, 0.8), obstacles=((0.9, 0.3, 0.3),), horizon=2.0)
    problem = MacroProblem(shark, handmade_repertoire(shark), task, segments=3)
    here = search(problem, "ga", budget=16, seed=1, popsize=8)
    on_ray = search(problem, "ga", budget=16, seed=1, popsize=8, evaluator="ray")
    assert here.history == on_ray.history and np.array_equal(here.entries, on_ray.entries)
    assert np.array_equal(here.durations, on_ray.durations)


def test_stunt_search_on_ray_matches_in_process(local_ray, tmp_path, monkeypatch):
    """A tiny stunt (a dolphin's short leap, two annealing steps of 16 plans): ``zoetic stunt
    --evaluator ray --ray-address`` finds the same plans, step by step, as discover in process."""
    import json

    from zoetic.behavior.repertoire import Repertoire
    from zoetic.behavior.stunts import discover, load_trick, macro_document
    from zoetic.behavior.training import rest_abstraction
    from zoetic.bodies import load_animal
    from zoetic.control.abstract import AbstractController
    from zoetic.learning.ray_eval import RayPool

    dolphin = load_animal("dolphin")
    a = dolphin.n_actuators
    beat = AbstractController(
        dolphin.name,
        tuple(dolphin.actuator_names),
        np.full(a, 0.5),
        np.full((a, 1), 2.0),
        np.full((a, 1), 0.5),
        -np.pi * np.arange(a)[:, None] / 4,
        1.0,
    )
    rep = Repertoire(dolphin.name, tuple(dolphin.actuator_names))
    rep.add("do-nothing", rest_abstraction(dolphin), 1.0)
    rep.add("beat", beat, 1.0)
    rep.save(tmp_path / "memory")
    (tmp_path / "hop.toml").write_text(
        'name = "hop"\nrequires = ["surface"]\nhorizon = 0.3\nrecord_hz = 20.0\n'
        "[start]\ndepth = 0.3\npitch = 0.6\nspeed = 1.5\n"
        "[trick]\nsegments = 2\ndurations = [0.1, 0.3]\n"
        '[[terms]]\nkind = "apex_above_surface"\nweight = -1.0\n'
    )
    here = discover(dolphin, rep, load_trick(tmp_path / "hop.toml"), "anneal", budget=32, seed=1)
    batches: list[int] = []
    ray_map = RayPool.map

    def counted(pool, job, items, on_part=None):
        batches.append(len(items))
        return ray_map(pool, job, items, on_part)

    monkeypatch.setattr(RayPool, "map", counted)
    out = tmp_path / "ray"
    code = main(
        [
            "stunt",
            "dolphin",
            "--memory",
            str(tmp_path / "memory"),
            "--trick",
            str(tmp_path / "hop.toml"),
            "--budget",
            "32",
            "--seed",
            "1",
            "--no-video",
            "--out",
            str(out),
            "--evaluator",
            "ray",
            "--ray-address",
            local_ray,
        ]
    )
    assert code == 0 and batches == [16, 16]  # both steps' plans went to the Ray actors
    s = json.loads((out / "summary.json").read_text())
    assert [n for n, _ in here.result.history] == [16, 32]
    assert here.result.history[1][1] < here.result.history[0][1] - 1e-4  # the 2nd step is better
    assert s["history"] == [[n, round(f, 5)] for n, f in here.result.history]
    plan = json.loads((out / "macro.json").read_text())["controller"]
    assert plan == macro_document(here.problem, here.result.sequence, "")["controller"]


def _free_ports(n: int) -> list[int]:
    """Return ``n`` distinct TCP ports that are free on the loopback address now."""
    import socket

    socks = [socket.socket() for _ in range(n)]
    for s in socks:
        s.bind(("127.0.0.1", 0))
    ports = [s.getsockname()[1] for s in socks]
    for s in socks:
        s.close()
    return ports


def _alive_nodes(ray_bin: str, address: str, env: dict) -> int:
    import subprocess

    out = subprocess.run(
        [ray_bin, "status", f"--address={address}"], env=env, capture_output=True, text=True
    )
    active = out.stdout.split("Active:")[-1].split("Pending:")[0]
    return active.count("node_") if out.returncode == 0 else 0


@pytest.fixture(scope="module")
def two_node_cluster():
    """A head and a worker node on 127.0.0.1, each with one CPU, its own temp dir and ports, and
    token authentication on (a token of this test's own, not ~/.ray/auth_token). Yields the
    address and the environment a driver needs; the fixture kills both nodes' process groups."""
    import secrets
    import shutil
    import subprocess
    import sys
    import tempfile
    import time

    ray_bin = str(Path(sys.executable).with_name("ray"))
    base = Path(tempfile.mkdtemp(prefix="zray", dir="/tmp"))  # short: Ray's socket paths
    src = str(Path(__file__).resolve().parents[1] / "src")
    env = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"}
    env.update(
        RAY_AUTH_MODE="token",
        RAY_AUTH_TOKEN=secrets.token_hex(32),
        PYTHONPATH=os.pathsep.join([src, env.get("PYTHONPATH", "")]),
    )
    gcs, dash, *agents = _free_ports(4)
    address = f"127.0.0.1:{gcs}"
    common = ["--num-cpus=1", "--node-ip-address=127.0.0.1", "--disable-usage-stats"]
    head = ["--head", f"--port={gcs}", "--include-dashboard=false", f"--dashboard-port={dash}"]
    groups: list[int] = []
    try:
        for i, args in enumerate([head, [f"--address={address}"]]):
            cmd = [ray_bin, "start", *args, *common, f"--temp-dir={base / str(i)}"]
            cmd.append(f"--dashboard-agent-listen-port={agents[i]}")
            proc = subprocess.Popen(
                cmd,
                env=env,
                start_new_session=True,
                stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT,
                text=True,
            )
            groups.append(proc.pid)  # its daemons stay in the group it leads
            log = proc.communicate(timeout=180)[0]
            assert proc.returncode == 0, log[-3000:]
        deadline = time.monotonic() + 90
        while _alive_nodes(ray_bin, address, env) < 2:
            assert time.monotonic() < deadline, "the worker node never joined the head"
            time.sleep(2)
        yield address, env
    finally:
        for sig in (signal.SIGTERM, signal.SIGKILL):
            for pgid in groups:
                try:
                    os.killpg(pgid, sig)
                except ProcessLookupError:
                    pass
            time.sleep(3)
        shutil.rmtree(base, ignore_errors=True)


def _learn_on(address: str, env: dict, out: Path):
    """``zoetic learn CONFIG --evaluator ray --ray-address address`` in a fresh process."""
    import subprocess
    import sys

    c = CONFIG
    args = [sys.executable, "-m", "zoetic", "learn", c["animal"], "--task", c["task"]]
    args += ["--optimizer", c["optimizer"], "--budget", str(c["budget"])]
    args += ["--popsize", str(c["popsize"]), "--nodes", str(c["nodes"]), "--seed", str(c["seed"])]
    args += ["--no-video", "--out", str(out), "--evaluator", "ray", "--ray-address", address]
    return subprocess.run(args, env=env, capture_output=True, text=True, timeout=600)


def test_a_two_node_cluster_with_token_auth_gives_the_in_process_history(
    two_node_cluster, reference, tmp_path
):
    address, env = two_node_cluster
    done = _learn_on(address, env, tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    with (tmp_path / "history.csv").open() as fh:
        assert [row["E"] for row in csv.DictReader(fh)] == [f"{e:.6g}" for e in reference[1]]


def test_a_driver_without_the_token_is_told_so(two_node_cluster, tmp_path):
    address, env = two_node_cluster
    done = _learn_on(address, {**env, "RAY_AUTH_MODE": "disabled"}, tmp_path)
    assert done.returncode == 2
    said = " ".join(done.stderr.split())  # the console wraps long lines
    assert "refused this driver's authentication token" in said
    assert "RAY_AUTH_MODE=token" in said and "cannot reach" not in said
