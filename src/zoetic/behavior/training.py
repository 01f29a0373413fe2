"""Basic training (section 3 of the muscle paper): learn, abstract and keep a repertoire.

For each entry of the plan, a controller is learned for its task (in a run directory of its
own, resumable), by one of two pipelines (``behavior.pipelines``):

- "periodic" (the default): a constant plus two harmonics of the animal's stroke frequency per
  actuator (``learning.run.LearnConfig.controller``), learned by CMA-ES. Its "abstraction" is
  no FFT: the controller already is a few sinusoids, so the harmonics weaker than the
  threshold times each actuator's strongest are dropped as they are (equal frequencies added
  as phasors), and when that breaks a promise the learned controller keeps, a lower threshold
  is tried (``FALLBACK_THRESHOLDS``).
- "paper" (``pipeline="paper"``): the paper's own path, a time-domain controller of M nodal
  values per actuator learned from scratch by simulated annealing or the simplex method, then
  abstracted by the FFT of its nodal values at the threshold given.

The abstraction is checked against the original in the same simulation and added to the
repertoire; right turns are the left ones with left and right actuator signals swapped. The
entries are learned together (``learning.together``: entries whose rollouts last as long share
one batched simulation a generation), each in its own run directory checkpointed as it goes,
so an interrupted training picks up where every entry stopped; the repertoire directory is
written after each entry is abstracted. An entry that breaks a promise of its task is learned
again from derived seeds (``behavior.restarts``).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np

from zoetic.behavior.pipelines import (
    check_resumed,
    check_training,
    entry_config,
    paper_abstraction,
)
from zoetic.behavior.promises import judge_entry
from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.restarts import keep_promises
from zoetic.bodies import Body, load_animal
from zoetic.control import Controller, load_controller
from zoetic.control.abstract import AbstractController, SequenceController
from zoetic.errors import RunDirError, ZoeticError
from zoetic.io import read_json, read_toml, suggest
from zoetic.learning.abstraction import Abstraction, abstract, compare, mirror_abstract
from zoetic.learning.blas import one_blas_thread
from zoetic.tasks import Task, capabilities, fits, load_task

# (entry name, task per medium kind): the paper's basic training, in order
PLAN = (
    ("go-straight", {"ground": "crawl-straight", "water": "swim-straight"}),
    ("sharp-turn-left", {"ground": "sharp-turn-left", "water": "quick-turn-left"}),
    ("wide-turn-left", {"ground": "wide-turn-left", "water": "wide-turn-left"}),
    # a fish in open water holds and changes its depth with these (the tracker's 3D targets)
    ("swim-up", {"water": "swim-up"}),
    ("swim-down", {"water": "swim-down"}),
)
# an animal with a water surface above it (the dolphin): the five basic motor tasks of the
# paper's section 3.2 (turn-right is the mirror of turn-left)
# Every task of both plans is learned from rest and from a start at the animal's own cruising
# speed (its [[starts]]: "rest" and "cruising", speed = "cruise"; a ground animal's cruising
# start is a crawling one): a candidate's E is the mean over the two, so an entry does what it
# promises whether it is switched on from rest or mid-swim.
SURFACE_PLAN = (
    ("move-forward", "move-forward"),
    ("turn-down", "turn-down"),
    ("turn-up", "turn-up"),
    ("turn-left", "turn-left-swimming"),
    # beside the five: a burst for the stunts, which leap and somersault on the speed they
    # reach under water; move-forward, held level and upright, swims too slowly for them
    ("sprint", "sprint"),
)
# With ``speeds``: straight swims at steady speeds (body lengths/s) below go-straight's (which
# swims as far as it can, so it is the fastest), learned after the rest of the plan (whose
# entries and seeds stay as without them); ``behavior.parametric`` blends between them
SPEED_PLAN = (("swim-slow", "swim-slow"), ("swim-medium", "swim-medium"))
# With ``radii``: a swimmer's turn of medium radius between the wide and the sharp one, learned
# last (after ``SPEED_PLAN`` when both are asked for), mirrored like them;
# ``behavior.parametric`` blends go-straight and the turns into a turn of any radius between
RADIUS_PLAN = (("medium-turn-left", "medium-turn-left"),)
REST_SECONDS = 1.0
# the "auto" abstraction's thresholds (times each actuator's strongest mode) tried in turn
# when the default one breaks a promise the learned controller keeps
FALLBACK_THRESHOLDS = (0.1, 0.01)


@dataclass(frozen=True)
class Entry:
    """One entry to learn: its repertoire name and the task that teaches it."""

    name: str
    task: Task


def plan_for(body: Body, speeds: bool = False, radii: bool = False) -> list[Entry]:
    """Return the entries the basic training learns for this animal (tasks that allow it);
    with ``speeds``, a swimmer's ``SPEED_PLAN`` too, with ``radii`` its ``RADIUS_PLAN``."""
    caps = capabilities(body)
    kind = "water" if "water" in caps else "ground"
    plan = (
        [(n, t) for n, t in SURFACE_PLAN]
        if "surface" in caps
        else [(n, t[kind]) for n, t in PLAN if kind in t]
    )
    if speeds and kind == "water":
        plan += list(SPEED_PLAN)
    if radii and kind == "water":
        plan += list(RADIUS_PLAN)
    out = []
    for name, task_name in plan:
        task = load_task(task_name)
        if fits(task, body):
            out.append(Entry(name, task))
    if not out:
        raise ZoeticError(f"no basic-training task fits the {body.name}")
    return out


def mirrored_name(name: str) -> str | None:
    """Return the right-hand name of a left-hand entry ("turn-left" -> "turn-right")."""
    return name.replace("left", "right") if "left" in name else None


def rest_abstraction(body: Body) -> AbstractController:
    """Return the do-nothing entry: all muscles relaxed, fins level, no modes."""
    a = len(body.actuator_names)
    empty = np.zeros((a, 0))
    level = np.nan_to_num(body.wave_held)
    return AbstractController(
        body.name, tuple(body.actuator_names), level, empty, empty, empty, REST_SECONDS
    )


def judge_repertoire(directory: str | Path, body: Body) -> dict[str, dict]:
    """Return the verdict (``judge_entry``) of every learned entry of the repertoire of
    ``body`` in ``directory`` whose task makes promises, by entry name; a mirrored entry
    shares its original's ("mirror_of": the original)."""
    rep = Repertoire.load(directory, body)
    out: dict[str, dict] = {}
    for name in rep.names:
        task = rep.info[name].get("task")
        if isinstance(task, str) and load_task(task).promises:
            out[name] = judge_entry(body, rep.controllers[name], load_task(task))
            right = mirrored_name(name)
            if right in rep.controllers:
                out[right] = out[name] | {"mirror_of": name}
    return out


def abstract_keeping_promises(
    body: Body, original: Controller, task: Task, modes: str | int, threshold: float
) -> Abstraction:
    """Return the abstraction of a learned controller (``abstract``); under the "auto" rule,
    when it breaks a promise of ``task`` that the learned controller keeps, the one of the
    lower ``FALLBACK_THRESHOLDS`` that keeps them all, if any: a weak mode can carry a turn
    (the ray's wide turn kept only 26-31 of its 43 degrees with the modes at least 0.3 times
    each actuator's strongest)."""
    ab = abstract(original, modes, threshold)
    if modes != "auto" or not task.promises or judge_entry(body, ab.controller, task)["met"]:
        return ab
    if not judge_entry(body, original, task)["met"]:
        return ab  # the abstraction cannot keep what the learned controller does not
    for lower in [t for t in FALLBACK_THRESHOLDS if t < threshold]:
        fuller = abstract(original, modes, lower)
        if judge_entry(body, fuller.controller, task)["met"]:
            return fuller
    return ab


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
        ),
        **cmp.to_dict(),
    }


def _plain(task: Task) -> str:
    """The task as text, less ``nodes`` (a run's own setting, kept in its config)."""
    d = {k: v for k, v in task.to_dict().items() if k != "nodes"}
    return json.dumps(d, sort_keys=True, default=str)


def check_same_task(run_dir: Path, learned: Task, now: Task) -> None:
    """Refuse to resume an entry whose task has changed since it was learned (a zoetic update
    or an edited task file): its controller would not do what the entry now promises."""
    if _plain(learned) != _plain(now):
        raise RunDirError(
            f"{run_dir / 'config.toml'}: entry learned for an earlier version of task "
            f"'{now.name}'; train into a fresh --out (or delete {run_dir}) to learn it again"
        )


def plan_digest(animal: str | Path, speeds: bool = False, radii: bool = False) -> str:
    """Return a short digest of what the basic training of ``animal`` learns: its body and
    its plan's tasks (a cache of trained repertoires keyed by it goes stale with either)."""
    body = load_animal(animal)
    h = hashlib.sha256(Path(body.source).read_bytes())
    for e in plan_for(body, speeds, radii):
        h.update(f"|{e.name}|{_plain(e.task)}".encode())
    return h.hexdigest()[:10]


def train_repertoire(
    animal: str | Path | Body,
    out: str | Path,
    budget: int = 3000,
    seed: int = 0,
    optimizer: str | None = None,
    modes: str | int = "auto",
    threshold: float = 0.3,
    nodes: int | None = None,
    on_entry: Callable[[str, object], None] | None = None,
    progress: Callable[[object], None] | None = None,
    evaluator: str = "batch",
    resume_budget: int | None = None,
    speeds: bool = False,
    radii: bool = False,
    pipeline: str = "periodic",
) -> Repertoire:
    """Learn, abstract and save the basic repertoire of ``animal`` (a zoo name, an animal
    file or a Body, learned as given) into ``out``; return it.

    optimizer: the pipeline's own when None (periodic: cmaes; paper: anneal). nodes:
    controller nodes per actuator (default: each task's; the paper pipeline's, 4 per stroke
    period). on_entry(name, run) is called for each entry before learning starts;
    progress(run) as that entry's run learns. An entry already begun in ``out`` continues to
    its stored budget, or to ``resume_budget`` evaluations when given.
    speeds: learn a swimmer's ``SPEED_PLAN`` entries too (``parametric.swim_at`` blends them);
    radii: its ``RADIUS_PLAN`` entry too (``parametric.turn_of_radius`` blends the turns).
    pipeline: "periodic" or "paper" (module doc).
    """
    from zoetic.learning.together import learn_together

    optimizer = check_training(pipeline, optimizer, threshold)
    body = animal if isinstance(animal, Body) else load_animal(animal)
    name = body.name if isinstance(animal, Body) else str(animal)
    out = Path(out)
    entries = plan_for(body, speeds, radii)
    runs = []
    for k, entry in enumerate(entries):
        settings = {"animal": name, "optimizer": optimizer, "budget": budget, "seed": seed + k}
        settings |= {"evaluator": evaluator} | entry_config(pipeline, body, entry.task, nodes)
        runs.append(
            _entry_run(out / "runs" / entry.name, entry, body, settings, resume_budget, pipeline)
        )
    rep = Repertoire(body.name, tuple(body.actuator_names))
    rep.add("do-nothing", rest_abstraction(body), REST_SECONDS, source="all muscles relaxed")
    rep.save(out)
    for entry, run in zip(entries, runs, strict=True):
        if on_entry:
            on_entry(entry.name, run)
    learn_together(runs, progress=progress)
    learned = []
    with one_blas_thread():  # abstraction and judging: small linear algebra, as learning
        for entry, run in zip(entries, runs, strict=True):
            learned.append(learned_entry(body, entry, run, pipeline, modes, threshold))
            add_entry(rep, body, entry, *learned[-1])
            rep.save(out)
    again = partial(learned_entry, body, pipeline=pipeline, modes=modes, threshold=threshold)

    def resume(run_dir: Path, entry: Entry):  # a restart run begun before an interruption
        return _entry_run(run_dir, entry, body, {}, resume_budget, pipeline)

    for entry, (ab, info) in keep_promises(
        body, entries, runs, learned, again, resume, out, on_entry, progress
    ):
        add_entry(rep, body, entry, ab, info)
        rep.save(out)
    return rep


def learned_entry(
    body: Body, entry: Entry, run, pipeline: str, modes: str | int, threshold: float
) -> tuple[Abstraction, dict]:
    """Return the abstraction of an entry's learned controller and its repertoire info (the
    paper pipeline's or the periodic one's, ``train_repertoire``), the run's own source."""
    original = run.best_controller()
    if pipeline == "paper":
        learned_by = run.setup.config.optimizer  # a resumed entry's own
        ab, info = paper_abstraction(body, original, entry.task, modes, threshold, learned_by)
    else:
        ab = abstract_keeping_promises(body, original, entry.task, modes, threshold)
        info = abstraction_report(body, original, ab, entry.task)
    return ab, {"source": f"runs/{run.out.name}"} | info


def add_entry(rep: Repertoire, body: Body, entry: Entry, ab: Abstraction, info: dict) -> None:
    """Add (or replace) a learned entry and, for a left-hand one, its mirror."""
    rep.add(entry.name, ab.controller, entry.task.horizon, **info)
    right = mirrored_name(entry.name)
    if right:
        rep.add(
            right,
            mirror_abstract(ab.controller, body.actuator_mirror),
            entry.task.horizon,
            source=f"mirror of {entry.name}",
        )


def _entry_run(
    run_dir: Path,
    entry: Entry,
    body: Body,
    settings: dict,
    resume_budget: int | None,
    pipeline: str,
):
    """Return the learning run of one entry: the one begun in ``run_dir`` (same task and
    pipeline), or a new one with ``settings`` (LearnConfig's)."""
    from zoetic.learning.run import LearnConfig, Run

    if (run_dir / "config.toml").exists():
        run = Run.resume(run_dir, resume_budget)
        check_same_task(run_dir, run.setup.task, entry.task)
        check_resumed(pipeline, run.setup.config, str(run_dir / "config.toml"))
        return run
    return Run.create(run_dir, LearnConfig(task=entry.task.name, **settings), body)


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


def parse_sequence(text: str, rep: Repertoire) -> list[tuple[str, float]]:
    """Return [(entry, seconds)] from "name:seconds,name,..." (seconds default to the entry's)."""
    items = []
    for part in [p.strip() for p in text.split(",") if p.strip()]:
        name, _, sec = part.partition(":")
        name = name.strip()
        if name not in rep.controllers:
            raise ZoeticError(
                f"sequence item {part!r}: no entry {name!r}{suggest(name, rep.names)} in the "
                "repertoire "
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
