"""Run directories and the files a user gets from the commands (simulate, learn, abstract,
repertoire show): where the library's results meet the disk and the pictures."""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np

from zoetic.bodies import Body, load_animal
from zoetic.control import Controller, controller_from_spec
from zoetic.errors import BlowUpError, SimulationError
from zoetic.io import atomic_write_bytes, check_memory, check_steps, make_dir
from zoetic.learning.checks import (  # noqa: F401 - the run checks, for the commands
    MAX_BUDGET,
    check_learn_config,
    check_learn_size,
    check_learnable,
    check_run_dir,
)
from zoetic.physics import Medium, Trajectory, get_medium
from zoetic.physics.simulate import check_dt, good_dt


def record_stride(dt: float, rate_hz: float = 100.0) -> int:
    """Return how many steps apart to record so that positions come at about ``rate_hz``."""
    return max(1, int(round(1.0 / (rate_hz * dt))))


def save_trajectory(path: Path, traj: Trajectory, index: int = 0, **meta: str) -> Path:
    """Write times (T,) and positions (T, nodes, 3) of one candidate to an .npz file.

    ``meta`` strings (animal, medium, controller JSON) let viewers rebuild the scene.
    """
    buf = io.BytesIO()
    extra = {k: np.array(str(v)) for k, v in meta.items()}
    np.savez_compressed(buf, times=traj.times, positions=traj.positions[index], **extra)
    return atomic_write_bytes(path, buf.getvalue())


def run_controller(
    body: Body, ctrl: Controller, seconds: float, medium: Medium, dt: float
) -> Trajectory:
    """Return the trajectory of one body driven by one controller for ``seconds``.

    It runs as a closed-loop rollout of a one-animal World under the controller as an
    open-loop policy: the same kernel and numbers as ``physics.simulate``. A blow-up (which
    the step check should have prevented) is a BlowUpError (exit code 3) naming the step, the
    animal and a time step that works.
    """
    from zoetic.control.policy import OpenLoopPolicy
    from zoetic.control.rollout import rollout
    from zoetic.physics.world import World

    world = World([body], medium=medium, dt=dt)
    stride = record_stride(dt)
    traj = rollout(world, OpenLoopPolicy(ctrl), seconds, seconds, stride).trajectory(0)
    steps = int(round(seconds / dt))
    if traj.failed[0] or not np.isfinite(traj.positions[0]).all():
        step = int(traj.failed_step[0]) if traj.failed[0] else steps
        raise BlowUpError(
            f"the simulation of the {body.name} ({body.source}) blew up at step {step} "
            f"(t = {step * dt:.3f} s) with dt = {dt:g} s in {medium.name}; "
            f"try --dt {good_dt(body, medium) / 2:.3g}"
        )
    return traj


def check_simulation(body: Body, ctrl: Controller, seconds: float, dt: float,
                     where_dt: str) -> int:  # fmt: skip
    """Return the number of steps, refusing a run too long or too big for memory."""
    steps = check_steps(seconds, dt, where_dt, SimulationError)
    n_rec = steps // record_stride(dt) + 1
    per_step = body.n_actuators * 24 + 8 * int(getattr(ctrl, "nodes", 8) or 8)
    check_memory(steps * per_step + n_rec * body.n_nodes * 3 * 12,
                 f"simulating {seconds:g} s of the {body.name} at dt = {dt:g} s",
                 SimulationError)  # fmt: skip
    return steps


def write_media(body: Body, traj: Trajectory, medium: Medium, out: Path, video: bool, fps: int):
    """Write path.png (and video.mp4) for the first candidate of a trajectory."""
    from zoetic.viz.plots import plot_path

    files = {"path": plot_path(traj.com(body)[0], out / "path.png", title=body.name)}
    if video:
        from zoetic.viz.render3d import render_video

        files["video"] = render_video(
            body, traj.positions[0], traj.times, medium, out / "video.mp4", fps=fps
        )
    return files


def simulate_run(
    animal: str,
    controller: str,
    seconds: float,
    out: Path,
    medium: str | None = None,
    dt: float | None = None,
    video: bool = True,
    fps: int = 30,
) -> dict:
    """Simulate, write trajectory.npz, path.png and video.mp4 into ``out``; return a summary."""
    body = load_animal(animal)
    ctrl = controller_from_spec(controller, body)
    med = get_medium(medium or body.medium)
    where_dt = body.source if dt is None else "--dt"
    dt = check_dt(body, float(body.dt if dt is None else dt), med, where_dt)
    check_simulation(body, ctrl, seconds, dt, "--seconds")
    out = Path(out)
    make_dir(out)
    traj = run_controller(body, ctrl, seconds, med, dt)
    where = str(Path(animal).resolve()) if Path(animal).is_file() else animal
    meta = {"animal": where, "medium": med.name, "controller": json.dumps(ctrl.to_dict())}
    save_trajectory(out / "trajectory.npz", traj, **meta)
    files = write_media(body, traj, med, out, video, fps)
    com = traj.com(body)[0]
    travelled = float(np.linalg.norm(com[-1, [0, 2]] - com[0, [0, 2]]))
    if not np.isfinite(travelled):  # never report nan as a result
        raise BlowUpError(f"the simulation of the {body.name} ({body.source}) produced NaN")
    return {
        "animal": body.name,
        "medium": med.name,
        "seconds": seconds,
        "distance_m": round(travelled, 3),
        "speed_m_s": round(travelled / seconds, 3),
        "trajectory": str(out / "trajectory.npz"),
        **{k: str(v) for k, v in files.items()},
    }


def finish_run(run, video: bool = True, fps: int = 30) -> dict:
    """Write learning.png, controller.png and video.mp4 of a finished learning run.

    The summary says how many candidates failed (blew up); a run in which every candidate
    failed is a BlowUpError, not a result.
    """
    from zoetic.viz.learning import plot_controller, plot_learning

    failed = int(np.count_nonzero(~np.isfinite(np.asarray(run.log.E, float))))
    if run.log.E and failed == len(run.log.E):
        raise BlowUpError(
            f"{run.out}: every one of the {failed} candidates evaluated blew up, so there is "
            "no result; check the animal file (its springs, masses and dt) or give its task "
            "a shorter horizon"
        )
    setup = run.setup
    body, task, obj = setup.objective.body, setup.task, setup.objective
    out = Path(run.out)
    ctrl = run.best_controller()
    files = {
        "learning": plot_learning(
            {setup.config.optimizer: np.array(run.log.E)}, out / "learning.png",
            title=f"{body.name} {task.name}: E against evaluations",
        ),
    }  # fmt: skip
    t = np.linspace(0.0, task.horizon, 400)
    files["controller"] = plot_controller(
        t, ctrl.sample(t), body.actuator_names, body.actuator_side, out / "controller.png",
        title=f"learned {setup.config.controller}-domain controller",
    )  # fmt: skip
    ev = obj.evaluate(setup.optimizer.best_x[None])
    traj = obj.simulate(setup.optimizer.best_x[None])
    com = traj.com(body)[0]
    if video:
        from zoetic.viz.render3d import render_video

        files["video"] = render_video(body, traj.positions[0], traj.times, obj.medium,
                                      out / "video.mp4", fps=fps)  # fmt: skip
    travelled = float(np.linalg.norm(com[-1, [0, 2]] - com[0, [0, 2]]))
    return {
        "evaluations": run.evaluations,
        "failed_candidates": failed,
        "best_E": round(float(ev.E[0]), 4),
        "distance_m": round(travelled, 3),
        "run": str(out),
        **{k: str(v) for k, v in files.items()},
    }


MARKER = ".zoetic-demo"


def clear_demo(out: Path) -> None:
    """Remove what an earlier ``zoetic demo`` wrote into ``out``, and nothing else.

    The demo lists the files it created in ``out/.zoetic-demo``; only those are removed. A
    directory that holds a run but no such list (a run made another way) is refused.
    """
    from zoetic.errors import RunDirError

    out = Path(out)
    marker = out / MARKER
    if marker.is_file():
        for name in marker.read_text().split("\n"):
            if name and "/" not in name and name not in (".", ".."):
                (out / name).unlink(missing_ok=True)
        marker.unlink()
    elif (out / "checkpoint.npz").exists() or (out / "config.toml").exists():
        raise RunDirError(
            f"{out} holds a run that zoetic demo did not make; choose another --out, or "
            f"continue it with zoetic learn --resume {out}"
        )


def mark_demo(out: Path, before: set[str]) -> None:
    """Record in ``out/.zoetic-demo`` the files the demo created (not those in ``before``)."""
    made = sorted(p.name for p in Path(out).iterdir() if p.is_file() and p.name not in before)
    text = "\n".join(n for n in made if n != MARKER) + "\n"
    atomic_write_bytes(Path(out) / MARKER, text.encode())


def abstract_files(
    source: str | Path,
    out: str | Path,
    modes: str | int = "auto",
    threshold: float = 0.3,
    task: str | None = None,
) -> dict[str, object]:
    """Abstract a learned controller; write abstract.json and abstract.png; return a summary."""
    from zoetic.behavior.training import abstract_source, abstraction_report
    from zoetic.io import write_json
    from zoetic.learning.abstraction import abstract
    from zoetic.viz.abstraction import plot_abstraction

    body, ctrl, task_obj = abstract_source(source, task)
    ab = abstract(ctrl, modes, threshold)
    info = abstraction_report(body, ctrl, ab, task_obj)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "abstract.json", ab.controller.to_dict() | {"abstraction": info})
    duration = float(getattr(ctrl, "duration", task_obj.horizon))
    t = np.linspace(0.0, duration, 400)
    spec = ab.spectrum
    plot_abstraction(
        t, ctrl.sample(t), ab.controller.sample(t), tuple(body.actuator_names), spec.freq,
        spec.amp, spec.phase, ab.kept, out / "abstract.png",
        title=f"{body.name}: {task_obj.name}, {ab.rule}, kept {info['kept']:.0%} of "
        f"{info['measure']}",
    )  # fmt: skip
    return info | {"file": str(out / "abstract.json"), "figure": str(out / "abstract.png")}


def _by_strength(freq: np.ndarray, amp: np.ndarray) -> list[float]:
    """Return the frequencies (Hz) present, strongest first (amplitude summed over actuators)."""
    total: dict[float, float] = {}
    for f, a in zip(np.ravel(freq), np.ravel(np.abs(amp)), strict=True):
        if a > 0:
            total[round(float(f), 3)] = total.get(round(float(f), 3), 0.0) + float(a)
    return sorted(total, key=lambda f: -total[f])


def repertoire_body(directory: str | Path, animal: str) -> Body:
    """Return the body a repertoire is for: a zoo animal, or the file its training runs used."""
    from zoetic.errors import BodyError
    from zoetic.io import read_toml

    try:
        return load_animal(animal)
    except BodyError:
        for config in sorted(Path(directory).glob("runs/*/config.toml")):
            source = read_toml(config, what="run configuration").get("run", {}).get("animal")
            if source and Path(source).exists():
                body = load_animal(source)
                if body.name == animal:
                    return body
        raise


def show_repertoire(directory: str | Path, plot: bool = True) -> list[dict[str, object]]:
    """Return one row per entry (modes, frequencies, what it does from rest); plot it too.

    Each entry is played from rest for its duration; forward (m along the start heading) and
    turn (degrees, left positive) say what it does; frequencies_hz come strongest first.
    Writes repertoire.png into the directory (paths: each entry played three times over).
    """
    from zoetic.behavior.repertoire import Repertoire
    from zoetic.learning.abstraction import measure

    directory = Path(directory)
    rep = Repertoire.load(directory)
    body = repertoire_body(directory, rep.animal)
    rep = Repertoire.load(directory, body)
    rows, signals, paths = [], {}, {}
    for name, ctrl in rep.controllers.items():
        seconds = rep.durations[name]
        m = measure(body, ctrl, seconds)
        amp = np.asarray(getattr(ctrl, "amp", np.zeros((0, 0))))
        freq = np.asarray(getattr(ctrl, "freq", np.zeros((0, 0))))
        rows.append({
            "entry": name, "kind": ctrl.kind, "seconds": round(seconds, 3),
            "modes": int(np.count_nonzero(amp)),
            "frequencies_hz": _by_strength(freq, amp),
            "forward_m": round(m["forward"], 3),
            "turn_deg": round(float(np.degrees(m["heading_change"])), 1),
            "source": rep.info.get(name, {}).get("source", ""),
        })  # fmt: skip
        t = np.linspace(0.0, seconds, 300)
        signals[name] = (t, ctrl.sample(t))
        paths[name] = measure(body, ctrl, 3 * seconds)["com"]  # played three times over
    if plot:
        from zoetic.viz.abstraction import plot_repertoire

        plot_repertoire(signals, paths, tuple(body.actuator_names), directory / "repertoire.png",
                        title=f"{rep.animal} repertoire ({len(rep.names)} entries)")  # fmt: skip
    return rows
