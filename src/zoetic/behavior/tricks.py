"""Trick files: a stunt to discover as a task file with two more tables.

``[trick]`` holds ``segments`` (the number of repertoire entries in a plan) and ``durations``
[min, max] s of each; ``[[objects]]`` the world's objects (``kind`` = ``ball``, ``box`` or
``cylinder`` and that object's fields, in world metres: a hurdle's bar, a beach ball on its
post). The task's ``horizon`` is the stunt's duration, its ``[start]`` where the animal starts
(e.g. at depth, at rest) and its ``[[terms]]`` the style terms (``zoetic.tasks.terms``).

``[trick.jitter]`` (``depth`` m, ``heading`` and ``pitch`` deg) says how far the start may be
off: a found plan is checked from six starts moved by it (one amount at a time, each way), and
with ``robust = true`` in ``[trick]`` (the default once there is a jitter) the search plays
each plan from the start and from two starts moved by all of it (one deeper, turned left and
pitched up; one shallower, turned right and pitched down) and scores it by the worst of the
three, so that a plan found still works when its start is slightly off. ``stop_when_met = true``
ends the search as soon as its best plan meets the trick's targets from the start and from all
six moved starts (off by default: a trick whose style is scored beyond its targets, such as
the leap's height or the bellyflop's splash, uses the whole budget).

``[trick.targets]`` adds targets of the trick's own to the built-in ones: each key a number
the stunt's measures report (``behavior.stunt_measures.measures``, e.g. ``apex_pitch_deg``),
each value its [min, max]; a stunt meets it when the measure is reported and within them (the
hurdle's level apex and nose-down re-entry, the leap's balance in flight).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

from zoetic.errors import TaskError, ZoeticError
from zoetic.io import read_toml, suggest
from zoetic.physics.objects import Ball, Box, Cylinder
from zoetic.tasks import TASK_DIR, Task, parse_task

TRICK_DIR = TASK_DIR / "tricks"
TRICK_KEYS = ("segments", "durations", "jitter", "robust", "stop_when_met", "targets")
JITTER_KEYS = ("depth", "heading", "pitch")  # m, deg, deg
OBJECTS = {"ball": Ball, "box": Box, "cylinder": Cylinder}


@dataclass(frozen=True)
class Trick:
    """A stunt to discover: the task (duration, start, style terms) and the world's objects."""

    task: Task
    objects: tuple[Ball | Box | Cylinder, ...] = ()
    segments: int = 4
    durations: tuple[float, float] = (0.3, 2.0)
    jitter: tuple[float, float, float] = (0.0, 0.0, 0.0)  # start depth m, heading, pitch deg
    robust: bool = True  # with a jitter: each plan scored by its worst of three starts
    # end the search once its best plan meets the trick's targets from the start and from
    # every perturbed start of the check (a built-in trick's targets; the rest of the budget
    # could only polish the style)
    stop_when_met: bool = False
    # the trick's own targets: (measure, min, max), of ``behavior.stunt_measures.measures``
    targets: tuple[tuple[str, float, float], ...] = ()

    @property
    def name(self) -> str:
        """Return the trick's name (its task's)."""
        return self.task.name

    def to_dict(self) -> dict:
        """Return the trick as a JSON-able dict (task, objects, plan shape)."""
        objs = [
            {"kind": k, **dataclasses.asdict(o)}
            for o in self.objects
            for k, c in OBJECTS.items()
            if type(o) is c
        ]
        return {
            "task": self.task.to_dict(),
            "objects": objs,
            "segments": self.segments,
            "durations": list(self.durations),
            "jitter": dict(zip(JITTER_KEYS, self.jitter, strict=True)),
            "robust": self.robust,
            "stop_when_met": self.stop_when_met,
            "targets": {k: [lo, hi] for k, lo, hi in self.targets},
        }


def parse_object(raw, where: str) -> Ball | Box | Cylinder:
    """Return the object an ``[[objects]]`` table describes; TaskError names what is wrong."""
    if not isinstance(raw, dict) or raw.get("kind") not in OBJECTS:
        raise TaskError(f"{where}: an object needs kind = ball, box or cylinder")
    cls = OBJECTS[raw["kind"]]
    fields = {f.name for f in dataclasses.fields(cls)}
    args = {k: v for k, v in raw.items() if k != "kind"}
    bad = sorted(set(args) - fields)
    if bad:
        raise TaskError(
            f"{where}: unknown key(s) {bad} for a {raw['kind']} (it has {sorted(fields)})"
        )
    try:
        return cls(**args)
    except (ZoeticError, TypeError, ValueError) as exc:
        raise TaskError(f"{where}: {exc}") from None


def _durations(raw_trick: dict, task: Task, source: str) -> tuple[float, float]:
    durations = raw_trick.get("durations", [0.3, min(2.0, task.horizon)])
    ok = (
        isinstance(durations, list)
        and len(durations) == 2
        and all(isinstance(d, int | float) and not isinstance(d, bool) for d in durations)
    )
    if not ok or not 0 < durations[0] < durations[1]:
        raise TaskError(
            f"{source}: trick: 'durations' must be [min, max] s with 0 < min < max, "
            f"got {durations!r}"
        )
    return float(durations[0]), float(durations[1])


def _jitter(raw_trick: dict, source: str) -> tuple[float, float, float]:
    raw = raw_trick.get("jitter", {})
    if not isinstance(raw, dict):
        raise TaskError(f"{source}: trick: 'jitter' must be a table of {list(JITTER_KEYS)}")
    bad = sorted(set(raw) - set(JITTER_KEYS))
    if bad:
        raise TaskError(
            f"{source}: trick.jitter: unknown key(s) {bad} (allowed: {list(JITTER_KEYS)})"
        )
    out = []
    for k in JITTER_KEYS:
        v = raw.get(k, 0.0)
        if isinstance(v, bool) or not isinstance(v, int | float) or not 0 <= v < 90:
            raise TaskError(
                f"{source}: trick.jitter: {k!r} must be a number >= 0 (m or deg), got {v!r}"
            )
        out.append(float(v))
    return out[0], out[1], out[2]


def _targets(raw_trick: dict, source: str) -> tuple[tuple[str, float, float], ...]:
    raw = raw_trick.get("targets", {})
    if not isinstance(raw, dict):
        raise TaskError(f"{source}: trick: 'targets' must be a table of measure = [min, max]")
    out = []
    for key, bounds in raw.items():
        ok = (
            isinstance(bounds, list)
            and len(bounds) == 2
            and all(isinstance(b, int | float) and not isinstance(b, bool) for b in bounds)
        )
        if not ok or not bounds[0] <= bounds[1]:
            raise TaskError(
                f"{source}: trick.targets: {key!r} must be [min, max] with min <= max, "
                f"got {bounds!r}"
            )
        out.append((str(key), float(bounds[0]), float(bounds[1])))
    return tuple(out)


def parse_trick(doc: dict, source: str = "<memory>") -> Trick:
    """Return the Trick a parsed TOML document describes; TaskError names what is wrong."""
    if not isinstance(doc, dict):
        raise TaskError(f"{source}: a trick file holds a table")
    doc = dict(doc)
    raw_trick = doc.pop("trick", {})
    raw_objects = doc.pop("objects", [])
    task = parse_task(doc, source)
    if not isinstance(raw_trick, dict):
        raise TaskError(f"{source}: [trick] must be a table")
    bad = sorted(set(raw_trick) - set(TRICK_KEYS))
    if bad:
        raise TaskError(f"{source}: trick: unknown key(s) {bad} (allowed: {list(TRICK_KEYS)})")
    segments = raw_trick.get("segments", 4)
    if isinstance(segments, bool) or not isinstance(segments, int) or segments < 1:
        raise TaskError(f"{source}: trick: 'segments' must be a positive integer, got {segments!r}")
    durations = _durations(raw_trick, task, source)
    if not isinstance(raw_objects, list):
        raise TaskError(f"{source}: objects must be [[objects]] tables")
    objects = tuple(parse_object(o, f"{source}: objects[{k}]") for k, o in enumerate(raw_objects))
    robust, stop = (raw_trick.get(k, d) for k, d in (("robust", True), ("stop_when_met", False)))
    for key, value in (("robust", robust), ("stop_when_met", stop)):
        if not isinstance(value, bool):
            raise TaskError(f"{source}: trick: {key!r} must be true or false, got {value!r}")
    jitter = _jitter(raw_trick, source)
    targets = _targets(raw_trick, source)
    return Trick(task, objects, int(segments), durations, jitter, robust, stop, targets)


def list_tricks() -> list[str]:
    """Return the names of the built-in tricks."""
    return sorted(p.stem for p in TRICK_DIR.glob("*.toml"))


def load_trick(name_or_path: str | Path) -> Trick:
    """Return a built-in trick by name, or the trick in a TOML file."""
    path = Path(name_or_path)
    if not (path.suffix == ".toml" or path.exists()):
        path = TRICK_DIR / f"{name_or_path}.toml"
        if not path.exists():
            hint = suggest(str(name_or_path), list_tricks())
            raise TaskError(
                f"unknown trick {str(name_or_path)!r}{hint}: choose one of "
                f"{', '.join(list_tricks())} or give a trick .toml file"
            )
    try:
        doc = read_toml(path, what="trick file")
    except ZoeticError as exc:
        raise TaskError(str(exc)) from None
    return parse_trick(doc, str(path))
