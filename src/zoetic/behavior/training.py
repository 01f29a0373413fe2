"""Basic training (section 3 of the muscle paper): learn, abstract and keep a repertoire.

For each entry of the plan, a time-domain controller is learned for its task (in a run
directory of its own, resumable), abstracted by FFT into its primary modes, checked against
the original in the same simulation, and added to the repertoire; right turns are the left
ones with left and right actuator signals swapped. The repertoire directory is written after
every entry, so an interrupted training keeps what it finished and picks up where it stopped.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from zoetic.behavior.repertoire import Repertoire
from zoetic.bodies import Body, load_animal
from zoetic.control import Controller, load_controller
from zoetic.control.abstract import AbstractController, SequenceController
from zoetic.errors import RunDirError, ZoeticError
from zoetic.io import read_json, read_toml, write_json
from zoetic.learn.abstraction import Abstraction, abstract, compare, mirror_abstract
from zoetic.tasks import Task, load_task

# (entry name, task per medium kind): the paper's basic training, in order
PLAN = (
    ("go-straight", {"ground": "crawl-straight", "water": "swim-straight"}),
    ("sharp-turn-left", {"ground": "sharp-turn-left", "water": "quick-turn-left"}),
    ("wide-turn-left", {"ground": "wide-turn-left", "water": "wide-turn-left"}),
)
REST_SECONDS = 1.0


@dataclass(frozen=True)
class Entry:
    """One entry to learn: its repertoire name and the task that teaches it."""

    name: str
    task: Task


def plan_for(body: Body) -> list[Entry]:
    """Return the entries the basic training learns for this animal (tasks that allow it)."""
    kind = "ground" if body.medium == "ground" else "water"
    out = []
    for name, tasks in PLAN:
        task = load_task(tasks[kind])
        if body.name in task.animals:
            out.append(Entry(name, task))
    if not out:
        raise ZoeticError(f"no basic-training task lists the {body.name}")
    return out


def mirrored_name(name: str) -> str | None:
    """Return the right-hand name of a left-hand entry ("turn-left" -> "turn-right")."""
    return name.replace("left", "right") if "left" in name else None


def rest_abstraction(body: Body) -> AbstractController:
    """Return the do-nothing entry: all muscles relaxed, fins level, no modes."""
    a = len(body.actuator_names)
    empty = np.zeros((a, 0))
    level = np.nan_to_num(body.wave_held)
    return AbstractController(body.name, tuple(body.actuator_names), level, empty, empty,
                              empty, REST_SECONDS)  # fmt: skip


def abstraction_report(
    body: Body, original: Controller, ab: Abstraction, task: Task
) -> dict[str, object]:
    """Return the JSON-able numbers of an abstraction: modes kept and what it keeps of the task."""
    cmp = compare(body, original, ab.controller, task)
    return {
        "task": task.name,
        "rule": ab.rule,
        "modes_per_actuator": ab.modes_per_actuator().tolist(),
        "frequencies_hz": sorted(
            {round(float(f), 4) for f in ab.controller.freq[ab.controller.amp > 0]}
        ),  # fmt: skip
        **cmp.to_dict(),
    }


def train_repertoire(
    animal: str | Path,
    out: str | Path,
    budget: int = 3000,
    seed: int = 0,
    optimizer: str = "cmaes",
    modes: str | int = "auto",
    threshold: float = 0.3,
    nodes: int | None = None,
    on_entry: Callable[[str, object], None] | None = None,
    progress: Callable[[object], None] | None = None,
) -> Repertoire:
    """Learn, abstract and save the basic repertoire of ``animal`` into ``out``; return it.

    nodes: controller nodes per actuator (default: each task's). on_entry(name, run) is called
    before each entry is learned; progress(run) during learning.
    """
    from zoetic.learn.run import LearnConfig, Run

    body = load_animal(animal)
    out = Path(out)
    rep = Repertoire(body.name, tuple(body.actuator_names))
    rep.add("do-nothing", rest_abstraction(body), REST_SECONDS, source="all muscles relaxed")
    rep.save(out)
    for k, entry in enumerate(plan_for(body)):
        run_dir = out / "runs" / entry.name
        if (run_dir / "config.toml").exists():
            run = Run.resume(run_dir)
        else:
            config = LearnConfig(animal=str(animal), task=entry.task.name, optimizer=optimizer,
                                 budget=budget, seed=seed + k, nodes=nodes)  # fmt: skip
            run = Run.create(run_dir, config)
        if on_entry:
            on_entry(entry.name, run)
        run.learn(progress=progress)
        original = run.best_controller()
        ab = abstract(original, modes, threshold)
        info = abstraction_report(body, original, ab, entry.task)
        rep.add(entry.name, ab.controller, entry.task.horizon, source=f"runs/{entry.name}",
                **info)  # fmt: skip
        right = mirrored_name(entry.name)
        if right:
            rep.add(right, mirror_abstract(ab.controller, body.actuator_mirror),
                    entry.task.horizon, source=f"mirror of {entry.name}")  # fmt: skip
        rep.save(out)
    return rep


def abstract_source(path: str | Path, task: str | None = None) -> tuple[Body, Controller, Task]:
    """Return (body, controller, task) from a run directory or a controller file.

    A run directory brings its animal and task (config.toml); a controller file brings its
    animal, and the task defaults to going straight in the animal's medium.
    """
    path = Path(path)
    if path.is_dir():
        cfg_path = path / "config.toml"
        if not (path / "controller.json").exists() or not cfg_path.exists():
            raise RunDirError(f"{path}: no controller.json and config.toml, so not a learning run")
        doc = read_toml(cfg_path, what="run configuration")
        try:
            animal, task_name = str(doc["run"]["animal"]), str(doc["run"]["task"])
        except (KeyError, TypeError) as exc:
            raise RunDirError(f"{cfg_path}: malformed ({exc})") from None
        body = load_animal(animal)
        ctrl = load_controller(path / "controller.json", body)
        return body, ctrl, load_task(task or task_name)
    if not path.exists():
        raise RunDirError(f"{path}: no such run directory or controller file")
    d = read_json(path, what="controller file")
    if not isinstance(d, dict) or "animal" not in d:
        raise RunDirError(f"{path}: a controller file names its animal; this one does not")
    body = load_animal(str(d["animal"]))
    ctrl = load_controller(path, body)
    default = "crawl-straight" if body.medium == "ground" else "swim-straight"
    return body, ctrl, load_task(task or default)


def abstract_files(
    source: str | Path,
    out: str | Path,
    modes: str | int = "auto",
    threshold: float = 0.3,
    task: str | None = None,
) -> dict[str, object]:
    """Abstract a learned controller; write abstract.json and abstract.png; return a summary."""
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


def parse_sequence(text: str, rep: Repertoire) -> list[tuple[str, float]]:
    """Return [(entry, seconds)] from "name:seconds,name,..." (seconds default to the entry's)."""
    items = []
    for part in [p.strip() for p in text.split(",") if p.strip()]:
        name, _, sec = part.partition(":")
        name = name.strip()
        if name not in rep.controllers:
            raise ZoeticError(
                f"sequence item {part!r}: no entry {name!r} in the repertoire "
                f"(it has: {', '.join(rep.names)})"
            )
        try:
            seconds = float(sec) if sec.strip() else rep.durations[name]
        except ValueError:
            raise ZoeticError(f"sequence item {part!r}: seconds must be a number") from None
        if not np.isfinite(seconds) or seconds <= 0:
            raise ZoeticError(f"sequence item {part!r}: seconds must be positive")
        items.append((name, seconds))
    if not items:
        raise ZoeticError("an empty sequence: give entries like 'go-straight:4,sharp-turn-left'")
    return items


def build_sequence(rep: Repertoire, items: list[tuple[str, float]], overlap: float = 0.05):
    """Return the SequenceController playing repertoire entries in turn, cross-faded."""
    parts = tuple((rep.controllers[name], seconds) for name, seconds in items)
    return SequenceController(rep.animal, tuple(rep.actuators), parts, overlap)


def _by_strength(freq: np.ndarray, amp: np.ndarray) -> list[float]:
    """Return the frequencies (Hz) present, strongest first (amplitude summed over actuators)."""
    total: dict[float, float] = {}
    for f, a in zip(np.ravel(freq), np.ravel(np.abs(amp)), strict=True):
        if a > 0:
            total[round(float(f), 3)] = total.get(round(float(f), 3), 0.0) + float(a)
    return sorted(total, key=lambda f: -total[f])


def show_repertoire(directory: str | Path, plot: bool = True) -> list[dict[str, object]]:
    """Return one row per entry (modes, frequencies, what it does from rest); plot it too.

    Each entry is played from rest for its duration; forward (m along the start heading) and
    turn (degrees, left positive) say what it does; frequencies_hz come strongest first.
    Writes repertoire.png into the directory (paths: each entry played three times over).
    """
    from zoetic.learn.abstraction import measure

    directory = Path(directory)
    rep = Repertoire.load(directory)
    body = load_animal(rep.animal)
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
