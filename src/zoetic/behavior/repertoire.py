"""A repertoire: named controllers an animal has learned, kept in a directory it can reload.

Layout: ``repertoire.json`` ({"animal", "actuators", "entries": [{"name", "file", "duration",
...info}]}) beside one controller JSON file per entry.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from zoetic import io as rd
from zoetic.bodies import Body
from zoetic.control import Controller, check_fits, from_dict, save_controller
from zoetic.errors import ControllerError, RunDirError, ZoeticError
from zoetic.io import read_json, write_json

INDEX = "repertoire.json"


@dataclass
class Repertoire:
    """Ordered named controllers for one animal, each with its natural duration (s)."""

    animal: str
    actuators: tuple[str, ...]
    controllers: dict[str, Controller] = field(default_factory=dict)
    durations: dict[str, float] = field(default_factory=dict)
    info: dict[str, dict] = field(default_factory=dict)

    @property
    def names(self) -> list[str]:
        """The entry names, in the order they were first added."""
        return list(self.controllers)

    def add(self, name: str, ctrl: Controller, duration: float, **info) -> None:
        """Add (or replace) an entry."""
        if ctrl.animal != self.animal or tuple(ctrl.actuators) != tuple(self.actuators):
            raise ControllerError(f"entry {name!r}: controller is not for the {self.animal}")
        self.controllers[name] = ctrl
        self.durations[name] = float(duration)
        self.info[name] = dict(info)

    def save(self, directory: str | Path) -> Path:
        """Write the repertoire into ``directory``; returns the index file's path."""
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        entries = []
        for name, ctrl in self.controllers.items():
            file = f"{name}.json"
            save_controller(ctrl, directory / file)
            entries.append(
                {
                    "name": name,
                    "file": file,
                    "duration": self.durations[name],
                    **self.info.get(name, {}),
                }
            )
        index = {"animal": self.animal, "actuators": list(self.actuators), "entries": entries}
        return write_json(directory / INDEX, index)

    @classmethod
    def load(cls, directory: str | Path, body: Body | None = None) -> Repertoire:
        """Return the repertoire in ``directory``, checked against ``body`` if given.

        Strict: the index's keys, each entry's name (unique), file (a controller file in the
        directory) and duration (positive, finite, bounded) are checked, and every
        controller must be for the repertoire's animal and actuators; errors name the index
        file and the entry.
        """
        directory = Path(directory)
        index_path = directory / INDEX
        if not directory.is_dir():
            raise RunDirError(f"{directory}: no such directory, so not a zoetic repertoire")
        if not index_path.is_file():
            raise RunDirError(f"{directory}: no {INDEX}, so not a zoetic repertoire")
        index = read_json(index_path, what="repertoire index", error=RunDirError)
        top = rd.Table(index, str(index_path), RunDirError)
        animal = top.string("animal")
        acts = top.raw("actuators")
        if not isinstance(acts, list) or not all(isinstance(a, str) for a in acts):
            raise top.fail(f"actuators must be a list of names, got {rd.abbrev(acts)}")
        entries = top.tables("entries", rd.LIMITS.links)
        top.finish()
        rep = cls(animal, tuple(acts))
        for k, entry in enumerate(entries):
            t = rd.Table(entry, f"{index_path}: entries[{k}]", RunDirError)
            name = t.string("name")
            t.where = f"{index_path}: entries[{k}] ({name})"
            if name in rep.controllers:
                raise t.fail(f"duplicate entry {name!r}; remove or rename one")
            file = t.string("file")
            if Path(file).is_absolute() or ".." in Path(file).parts:
                raise t.fail(f"file {file!r} must be a file name inside {directory}")
            duration = t.number("duration", positive=True, hi=rd.LIMITS.seconds)
            path = directory / file
            try:
                d = read_json(path, what="controller file", error=ControllerError)
                ctrl = from_dict(d, where=str(path))
            except ZoeticError as exc:
                raise ControllerError(f"{t.where}: {exc}") from None
            if ctrl.animal != animal or tuple(ctrl.actuators) != tuple(acts):
                raise t.fail(
                    f"{file} is a controller for the {ctrl.animal} "
                    f"({len(ctrl.actuators)} actuators), not for this repertoire's {animal}; "
                    "remove the entry or train it again"
                )
            info = {k2: v for k2, v in entry.items() if k2 not in ("name", "file", "duration")}
            rep.add(name, ctrl, duration, **info)
        if body is not None:
            if animal != body.name:
                raise RunDirError(
                    f"{index_path}: this repertoire is for the {animal}, not the {body.name}"
                )
            for name, ctrl in rep.controllers.items():
                check_fits(ctrl, body, f"{index_path}: entry {name!r}")
        return rep
