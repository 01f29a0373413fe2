"""A repertoire: named controllers an animal has learned, kept in a directory it can reload.

Layout: ``repertoire.json`` ({"animal", "actuators", "entries": [{"name", "file", "duration",
...info}]}) beside one controller JSON file per entry.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

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
            entries.append({"name": name, "file": file, "duration": self.durations[name],
                            **self.info.get(name, {})})  # fmt: skip
        index = {"animal": self.animal, "actuators": list(self.actuators), "entries": entries}
        return write_json(directory / INDEX, index)

    @classmethod
    def load(cls, directory: str | Path, body: Body | None = None) -> Repertoire:
        """Return the repertoire in ``directory``, checked against ``body`` if given."""
        directory = Path(directory)
        index_path = directory / INDEX
        if not index_path.exists():
            raise RunDirError(f"{directory}: no {INDEX}, so not a zoetic repertoire")
        try:
            index = read_json(index_path, what="repertoire index")
            rep = cls(str(index["animal"]), tuple(index["actuators"]))
            for k, entry in enumerate(index["entries"]):
                name, file = str(entry["name"]), str(entry["file"])
                path = directory / file
                try:
                    ctrl = from_dict(read_json(path, what="controller file"), where=str(path))
                except ZoeticError as exc:
                    raise ControllerError(f"{index_path}: entries[{k}] ({name}): {exc}") from None
                info = {k2: v for k2, v in entry.items() if k2 not in ("name", "file", "duration")}
                rep.add(name, ctrl, float(entry["duration"]), **info)
        except (KeyError, TypeError, ValueError) as exc:
            raise RunDirError(f"{index_path}: malformed repertoire ({exc})") from None
        if body is not None:
            for name, ctrl in rep.controllers.items():
                check_fits(ctrl, body, f"{directory / (name + '.json')}")
        return rep
