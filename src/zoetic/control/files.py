"""Controller files: a controller as a dict (``Controller.to_dict``) and back, checked strictly,
and the JSON files that hold them."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from zoetic import io as rd
from zoetic.bodies import Body
from zoetic.control.abstract import AbstractController, SequenceController
from zoetic.control.controllers import (
    ConstantController,
    Controller,
    FrequencyDomainController,
    MirroredController,
    TimeDomainController,
    WaveController,
)
from zoetic.errors import ControllerError, naming
from zoetic.io import read_json, write_json

# keys each controller type's file holds (besides type, animal, actuators and metadata)
CONTROLLER_KEYS = {
    "constant": ("values",),
    "wave": ("frequency", "amplitude", "offset", "phases", "hold"),
    "time": ("duration", "values", "interp"),
    "frequency": ("omega", "phase", "amplitudes"),
    "mirrored": ("inner", "mirror"),
    "abstract": ("offset", "freq", "amp", "phase", "period"),
    "sequence": ("items", "overlap"),
}
METADATA_KEYS = ("info", "abstraction")


def _check_controller(d: dict, where: str, depth: int = 0) -> None:
    """Check a controller dict strictly before it is built: keys, types, sizes, indices."""
    E = ControllerError
    if not isinstance(d, dict):
        raise E(f"{where}: a controller is a JSON object, got {rd.abbrev(d)}")
    if depth > 8:
        raise E(f"{where}: controllers nested more than 8 deep; is the file damaged?")
    kind = d.get("type")
    if not isinstance(kind, str) or kind not in CONTROLLER_KEYS:
        raise E(
            f"{where}: unknown controller type {rd.abbrev(kind, 40)}"
            f"{rd.suggest(str(kind), CONTROLLER_KEYS)} (one of {', '.join(CONTROLLER_KEYS)})"
        )
    at = f"{where} ({kind})"
    rd.check_keys(d, ("type", "animal", "actuators", *CONTROLLER_KEYS[kind], *METADATA_KEYS), at, E)
    for key in ("animal", "actuators", *CONTROLLER_KEYS[kind]):
        if key not in d and key not in ("interp", "period", "overlap", "hold"):
            raise E(f"{at}: missing {key!r}")
    rd.string(d["animal"], f"{at}: animal", E)
    acts = d["actuators"]
    if not isinstance(acts, list) or not all(isinstance(a, str) and a for a in acts):
        raise E(f"{at}: actuators must be a list of names, got {rd.abbrev(acts)}")
    n = len(acts)
    if n > rd.LIMITS.actuators:
        raise E(f"{at}: {n} actuators (at most {rd.LIMITS.actuators})")
    if len(set(acts)) != n:
        raise E(f"{at}: actuators repeat a name: {rd.abbrev(acts)}")
    m_max = rd.LIMITS.controller_nodes
    if kind == "constant":
        rd.numbers(d["values"], f"{at}: values", E, size=n)
    elif kind == "wave":
        rd.number(d["frequency"], f"{at}: frequency", E, lo=0.0, hi=1e4)
        rd.number(d["amplitude"], f"{at}: amplitude", E)
        rd.number(d["offset"], f"{at}: offset", E)
        rd.numbers(d["phases"], f"{at}: phases", E, size=n)
        hold = d.get("hold", {})
        if not isinstance(hold, dict):
            raise E(f"{at}: hold must be an object of actuator: value, got {rd.abbrev(hold)}")
        for name, value in hold.items():
            rd.number(value, f"{at}: hold.{name}", E, lo=0.0, hi=1.0)
    elif kind == "time":
        rd.number(d["duration"], f"{at}: duration", E, hi=rd.LIMITS.seconds, positive=True)
        rd.matrix(d["values"], f"{at}: values", E, rows=n, limit=n * m_max)
        rd.string(d.get("interp", "linear"), f"{at}: interp", E, ("linear", "bspline"))
    elif kind == "frequency":
        om = rd.numbers(d["omega"], f"{at}: omega", E, limit=m_max)
        rd.numbers(d["phase"], f"{at}: phase", E, size=len(om))
        rd.matrix(d["amplitudes"], f"{at}: amplitudes", E, rows=n, cols=len(om))
    elif kind == "mirrored":
        mirror = d["mirror"]
        if not isinstance(mirror, list) or len(mirror) != n:
            raise E(f"{at}: mirror must list {n} actuator indices, got {rd.abbrev(mirror)}")
        for i, m in enumerate(mirror):
            rd.integer(m, f"{at}: mirror[{i}]", E, 0, n - 1)
        _check_controller(d["inner"], f"{where}: inner", depth + 1)
    elif kind == "abstract":
        rd.numbers(d["offset"], f"{at}: offset", E, size=n)
        for key in ("freq", "amp", "phase"):
            rd.matrix(d[key], f"{at}: {key}", E, rows=n, limit=n * m_max)
        rd.number(d.get("period", 1.0), f"{at}: period", E, positive=True)
    elif kind == "sequence":
        items = d["items"]
        if not isinstance(items, list) or not 1 <= len(items) <= rd.LIMITS.links:
            raise E(f"{at}: items must be a list of 1 to {rd.LIMITS.links} entries")
        total = 0.0
        for i, it in enumerate(items):
            t = rd.Table(it, f"{at}: items[{i}]", E)
            total += t.number("duration", hi=rd.LIMITS.seconds, positive=True)
            _check_controller(t.raw("controller"), f"{where}: items[{i}]", depth + 1)
            t.finish()
        if total > rd.LIMITS.seconds:
            raise E(f"{at}: the items last {total:g} s in all (at most {rd.LIMITS.seconds:g})")
        rd.number(d.get("overlap", 0.05), f"{at}: overlap", E, lo=0.0, hi=0.49)


def from_dict(d: dict, where: str = "controller") -> Controller:
    """Return the controller described by a dict written by Controller.to_dict.

    The dict is checked strictly first (unknown keys, types, finite values, shapes, sizes
    and mirror indices), so every error names ``where`` and the entry.
    """
    _check_controller(d, where)
    try:
        kind = d["type"]
        common = (str(d["animal"]), tuple(str(a) for a in d["actuators"]))
        if kind == "constant":
            return ConstantController(*common, tuple(float(v) for v in d["values"]))
        if kind == "wave":
            unknown = set(d.get("hold", {})) - set(common[1])
            if unknown:
                raise ControllerError(f"hold names unknown actuators {sorted(unknown)}")
            return WaveController(
                *common,
                float(d["frequency"]),
                float(d["amplitude"]),
                float(d["offset"]),
                tuple(float(p) for p in d["phases"]),
                tuple((str(k), float(v)) for k, v in d.get("hold", {}).items()),
            )
        if kind == "time":
            return TimeDomainController(
                *common,
                float(d["duration"]),
                np.array(d["values"], float),
                d.get("interp", "linear"),
            )
        if kind == "frequency":
            return FrequencyDomainController(
                *common,
                np.array(d["omega"], float),
                np.array(d["phase"], float),
                np.array(d["amplitudes"], float),
            )
        if kind == "mirrored":
            inner = from_dict(d["inner"], where)
            return MirroredController(*common, inner, tuple(int(m) for m in d["mirror"]))
        if kind == "abstract":
            return AbstractController(
                *common,
                np.array(d["offset"], float),
                np.array(d["freq"], float),
                np.array(d["amp"], float),
                np.array(d["phase"], float),
                float(d.get("period", 1.0)),
            )
        items = tuple((from_dict(it["controller"]), float(it["duration"])) for it in d["items"])
        return SequenceController(*common, items, float(d.get("overlap", 0.05)))
    except ControllerError as exc:
        raise naming(where, exc) from None
    except (KeyError, TypeError, ValueError) as exc:
        raise ControllerError(
            f"{where}: malformed controller ({type(exc).__name__}: {rd.abbrev(str(exc), 120)})"
        ) from None


def check_fits(ctrl: Controller, body: Body, where: str = "controller") -> Controller:
    """Return ctrl if it was made for this body's animal and actuators; else ControllerError."""
    if ctrl.animal != body.name:
        raise ControllerError(
            f"{where}: this controller is for the {ctrl.animal!r}, not the {body.name!r}"
        )
    if tuple(ctrl.actuators) != tuple(body.actuator_names):
        raise ControllerError(
            f"{where}: actuators {list(ctrl.actuators)} do not match the {body.name}'s "
            f"{list(body.actuator_names)}"
        )
    return ctrl


def save_controller(ctrl: Controller, path: str | Path) -> Path:
    """Write the controller as JSON (atomically); returns the path."""
    return write_json(path, ctrl.to_dict())


def load_controller(path: str | Path, body: Body | None = None) -> Controller:
    """Return the controller in a JSON file, checked against ``body`` when one is given."""
    d = read_json(path, what="controller file", error=ControllerError)
    if not isinstance(d, dict):
        raise ControllerError(f"{path}: a controller file holds a JSON object")
    ctrl = from_dict(d, where=str(path))
    return check_fits(ctrl, body, str(path)) if body is not None else ctrl
