"""The pictures a run leaves in its directory (plots, videos), drawn here at the edge and
handed to the run-directory writers in ``zoetic.runs`` as ``media``: a run's path and video are
drawn from its record (``zoetic.record``), as the viewer draws it."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from zoetic.bodies import Body
from zoetic.physics import get_medium
from zoetic.record import Record


def _motion(rec: Record) -> tuple[np.ndarray, np.ndarray]:
    """Return the first animal's node positions (T, N, 3) and centre of mass (T, 3), in m."""
    a = rec.animals[0]
    pos = np.asarray(a.positions, float)
    mass = np.asarray(a.mass, float)
    return pos, np.einsum("tnk,n->tk", pos, mass / mass.sum())


def simulation_media(
    body: Body,
    rec: Record,
    out: Path,
    video: bool = True,
    fps: int = 30,
    starts: np.ndarray | None = None,
    title: str = "",
) -> dict:
    """Write path.png (and video.mp4) of a simulation's record; return their paths. ``body``
    (the record's animal) gives the video its display surface. With ``starts`` (s: when each
    entry of a sequence takes over) path.png is the top view beside the side view of the
    depth, white dots where an entry starts (a roll or a dive shows there)."""
    pos, com = _motion(rec)
    if starts is None:
        from zoetic.viz.plots import plot_path

        files = {"path": plot_path(com, out / "path.png", title=title or body.name)}
    else:
        from zoetic.viz.tracking import plot_plan

        idx = np.searchsorted(np.asarray(rec.times, float), np.asarray(starts, float) - 1e-9)
        none = np.zeros((0, 3))
        path = out / "path.png"
        files = {"path": plot_plan([com], [body.name], path, none, none, [idx], title, 0.5)}
    if video:
        from zoetic.viz.render3d import render_video

        files["video"] = render_video(
            body, pos, rec.times, get_medium(rec.medium), out / "video.mp4", fps=fps
        )
    return files


def learning_media(run, rec: Record, video: bool = True, fps: int = 30) -> dict:
    """Write learning.png, controller.png (and video.mp4 of the best controller's run, from the
    run's record) of a finished learning run; return their paths."""
    from zoetic.viz.learning import plot_controller, plot_learning

    setup = run.setup
    body, task, obj = setup.objective.body, setup.task, setup.objective
    out = Path(run.out)
    files = {
        "learning": plot_learning(
            {setup.config.optimizer: np.array(run.log.E)},
            out / "learning.png",
            title=f"{body.name} {task.name}: E against evaluations",
        ),
    }
    t = np.linspace(0.0, task.horizon, 400)
    files["controller"] = plot_controller(
        t,
        run.best_controller().sample(t),
        body.actuator_names,
        body.actuator_side,
        out / "controller.png",
        title=f"learned {setup.config.controller}-domain controller",
    )
    if video:
        from zoetic.viz.render3d import render_video

        files["video"] = render_video(
            body, _motion(rec)[0], rec.times, obj.medium, out / "video.mp4", fps=fps
        )
    return files


MIND_FISHES = 20  # the most fishes mind.png draws (one timeline each)


def mind_media(rec: Record, out: Path) -> Path:
    """Write mind.png of an aquarium's record: each fish's drives and intentions over time
    (the first ``MIND_FISHES`` fishes of a larger tank: the predators come first)."""
    from zoetic.viz.aquarium import plot_minds

    names = [a.name for a in rec.animals][:MIND_FISHES]
    per = [rec.scalars[n] for n in names]
    drives = np.stack(
        [
            np.stack([np.asarray(s[k], float) for k in ("hunger", "libido", "fear")], axis=-1)
            for s in per
        ],
        axis=1,
    )
    intentions = np.stack([np.asarray(s["intention"]).astype(int) for s in per], axis=1)
    alive = np.stack([np.asarray(s["alive"]) > 0.5 for s in per], axis=1)
    return plot_minds(
        rec.period_times,
        drives,
        intentions,
        alive,
        names,
        rec.labels["intention"],
        out / "mind.png",
    )


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
        t,
        ctrl.sample(t),
        ab.controller.sample(t),
        tuple(body.actuator_names),
        spec.freq,
        spec.amp,
        spec.phase,
        ab.kept,
        out / "abstract.png",
        title=f"{body.name}: {task_obj.name}, {ab.rule}, kept {info['kept']:.0%} of "
        f"{info['measure']}",
    )
    return info | {"file": str(out / "abstract.json"), "figure": str(out / "abstract.png")}


def _by_strength(freq: np.ndarray, amp: np.ndarray) -> list[float]:
    """Return the frequencies (Hz) present, strongest first (amplitude summed over actuators)."""
    total: dict[float, float] = {}
    for f, a in zip(np.ravel(freq), np.ravel(np.abs(amp)), strict=True):
        if a > 0:
            total[round(float(f), 3)] = total.get(round(float(f), 3), 0.0) + float(a)
    return sorted(total, key=lambda f: -total[f])


def show_repertoire(
    directory: str | Path, plot: bool = True, draw: Callable | None = None
) -> list[dict[str, object]]:
    """Return one row per entry (modes, frequencies, what it does from rest); plot it too.

    Each entry is played from rest for its duration; forward (m along the start heading) and
    turn (degrees, left positive) say what it does; frequencies_hz come strongest first.
    Writes repertoire.png into the directory (paths: each entry played three times over), by
    ``draw`` when given (called as ``plot_repertoire`` is, e.g. a ``Drawer``'s request).
    """
    from zoetic.behavior.repertoire import Repertoire
    from zoetic.learning.abstraction import measure
    from zoetic.runs import repertoire_body

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
        rows.append(
            {
                "entry": name,
                "kind": ctrl.kind,
                "seconds": round(seconds, 3),
                "modes": int(np.count_nonzero(amp)),
                "frequencies_hz": _by_strength(freq, amp),
                "forward_m": round(m["forward"], 3),
                "turn_deg": round(float(np.degrees(m["heading_change"])), 1),
                "source": rep.info.get(name, {}).get("source", ""),
            }
        )
        t = np.linspace(0.0, seconds, 300)
        signals[name] = (t, ctrl.sample(t))
        paths[name] = measure(body, ctrl, 3 * seconds)["com"]  # played three times over
    if plot:
        if draw is None:
            from zoetic.viz.abstraction import plot_repertoire as draw
        draw(
            signals,
            paths,
            tuple(body.actuator_names),
            directory / "repertoire.png",
            title=f"{rep.animal} repertoire ({len(rep.names)} entries)",
        )
    return rows
