"""Run directories: the simulate and learn runs' records (``zoetic.record``), the checks of a
learning run's configuration, size and directory, the demo's files, a repertoire's body.
Pictures (plots, videos) are drawn at the edge (``viz.media``) and handed in by the command
line as ``media``; nothing here draws."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from zoetic.bodies import Body, load_animal
from zoetic.control import Controller, controller_from_spec
from zoetic.control.measure import measure_record
from zoetic.errors import BlowUpError, SimulationError
from zoetic.io import atomic_write_bytes, check_memory, check_steps, make_dir
from zoetic.learning.checks import (  # noqa: F401 - the run checks, for the commands
    MAX_BUDGET,
    check_learn_config,
    check_learn_size,
    check_learnable,
    check_run_dir,
)
from zoetic.outdir import DEMO_MARKER
from zoetic.physics import Medium, Trajectory, get_medium
from zoetic.physics.simulate import check_dt, good_dt
from zoetic.record import Animal, Record, write_record

Media = Callable[..., dict]  # writes a run's pictures (plots, video); returns {name: path}


def record_stride(dt: float, rate_hz: float = 100.0) -> int:
    """Return how many steps apart to record so that positions come at about ``rate_hz``."""
    return max(1, int(round(1.0 / (rate_hz * dt))))


def animal_record(
    body: Body,
    positions: np.ndarray,
    times: np.ndarray,
    ctrl=None,
    name: str | None = None,
    color=None,
) -> Animal:
    """Return the run record's entry of one animal: its surface, its node positions (T, N, 3)
    at ``times`` (T,) s, and (with ``ctrl``) the activations its controller gave then."""
    acts = None
    if ctrl is not None:
        acts = np.clip(np.asarray(ctrl.sample(np.asarray(times, float)), np.float32), 0.0, 1.0)
    return Animal(
        name or body.name,
        body.name,
        np.asarray(body.faces, np.int32),
        np.asarray(positions, np.float32),
        np.asarray(body.mass, np.float32),
        color,
        tuple(body.actuator_names),
        acts,
    )


def write_run_record(out: Path, rec: Record, bodies: Sequence[Body]) -> tuple[Path, Record]:
    """Write a run's record with every animal's motion added (speed, depth or height, heading,
    pitch, roll: ``control.measure``), ``bodies[i]`` being the Body of ``rec.animals[i]``;
    return the file and the record written. Every command that records animals writes here."""
    rec = measure_record(rec, bodies)
    return write_record(out, rec), rec


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


def check_simulation(body: Body, ctrl: Controller, seconds: float, dt: float, where_dt: str) -> int:
    """Return the number of steps, refusing a run too long or too big for memory."""
    steps = check_steps(seconds, dt, where_dt, SimulationError)
    n_rec = steps // record_stride(dt) + 1
    per_step = body.n_actuators * 24 + 8 * int(getattr(ctrl, "nodes", 8) or 8)
    check_memory(
        steps * per_step + n_rec * body.n_nodes * 3 * 12,
        f"simulating {seconds:g} s of the {body.name} at dt = {dt:g} s",
        SimulationError,
    )
    return steps


def simulate_run(
    animal: str,
    controller: str,
    seconds: float,
    out: Path,
    medium: str | None = None,
    dt: float | None = None,
    media: Media | None = None,
) -> dict:
    """Simulate; write the run record (record.npz) into ``out``, and what ``media`` draws of
    it (``media(body, record, out)`` returns the files it wrote); return a summary."""
    body = load_animal(animal)
    ctrl = controller_from_spec(controller, body)
    med = get_medium(medium or body.medium)
    where_dt = body.source if dt is None else "--dt"
    dt = check_dt(body, float(body.dt if dt is None else dt), med, where_dt)
    check_simulation(body, ctrl, seconds, dt, "--seconds")
    out = Path(out)
    make_dir(out)
    traj = run_controller(body, ctrl, seconds, med, dt)
    rec = Record(
        "simulate",
        f"{body.name} ({out.name})",
        med.name,
        traj.times,
        (animal_record(body, traj.positions[0], traj.times, ctrl),),
    )
    path, rec = write_run_record(out, rec, [body])
    files = media(body, rec, out) if media is not None else {}
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
        "record": str(path),
        **{k: str(v) for k, v in files.items()},
    }


def search_history(E) -> dict:
    """Return a search's progress for its record: E of each candidate evaluated, in order
    (inf where one blew up), and the best E found by then."""
    e = np.asarray(E, float).reshape(-1)
    e = np.where(np.isfinite(e), e, np.inf)
    return {"E": e, "best_E": np.minimum.accumulate(e)} if len(e) else {}


def finish_run(run, media: Media | None = None) -> dict:
    """Write the run record of a finished learning run's best controller (record.npz), and
    what ``media`` draws of it (``media(run, record)`` returns the files it wrote).

    The summary says how many candidates failed (blew up); a run in which every candidate
    failed is a BlowUpError, not a result.
    """
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
    ev = obj.evaluate(setup.optimizer.best_x[None])
    traj = obj.simulate(setup.optimizer.best_x[None])
    best_E = round(float(ev.E[0]), 4)
    rec = Record(
        "learn",
        f"{body.name} learn ({out.name})",
        obj.medium.name,
        traj.times,
        (animal_record(body, traj.positions[0], traj.times, run.best_controller()),),
        numbers={"best_E": best_E, "task": task.name},
        history=search_history(run.log.E),
    )
    _, rec = write_run_record(out, rec, [body])
    files = media(run, rec) if media is not None else {}
    com = traj.com(body)[0]
    travelled = float(np.linalg.norm(com[-1, [0, 2]] - com[0, [0, 2]]))
    return {
        "evaluations": run.evaluations,
        "failed_candidates": failed,
        "best_E": best_E,
        "distance_m": round(travelled, 3),
        "run": str(out),
        **{k: str(v) for k, v in files.items()},
    }


MARKER = DEMO_MARKER


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


def repertoire_body(directory: str | Path, animal: str) -> Body:
    """Return the body a repertoire is for: the body its training runs stored (so an animal
    file that shares a zoo animal's name is judged as itself), else a zoo animal, else the
    file its training runs name."""
    from zoetic.errors import BodyError
    from zoetic.io import read_toml
    from zoetic.learning.stored_body import ANIMAL_FILE, load_body

    for stored in sorted(Path(directory).glob(f"runs/*/{ANIMAL_FILE}")):
        body = load_body(stored)
        if body.name == animal:
            return body
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
