"""What drives the muscles: controllers, their files, and the built-in ones of each animal."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from zoetic.bodies import Body
from zoetic.control import abstract as _abstract  # noqa: E402,F401  (registers abstract, sequence)
from zoetic.control.controllers import (
    ConstantController,
    Controller,
    FrequencyDomainController,
    MirroredController,
    TimeDomainController,
    WaveController,
    fourier_basis,
)
from zoetic.errors import ControllerError, ZoeticError

__all__ = [
    "ConstantController",
    "Controller",
    "FrequencyDomainController",
    "MirroredController",
    "TimeDomainController",
    "WaveController",
    "check_fits",
    "controller_from_spec",
    "frequency_domain",
    "from_dict",
    "load_controller",
    "rest_controller",
    "save_controller",
    "time_domain",
    "wave_controller",
]


def rest_controller(body: Body) -> ConstantController:
    """Return the controller that keeps all muscles relaxed (fins held level)."""
    values = []
    for k, kind in enumerate(body.actuator_kind):
        if kind == "fin":
            fin = int(np.flatnonzero(body.fin_actuator == k)[0])
            lo, hi = body.fin_angle[fin]
            values.append(float(np.clip(-lo / (hi - lo), 0.0, 1.0)))
        else:
            values.append(0.0)
    return ConstantController(body.name, body.actuator_names, tuple(values))


def wave_controller(body: Body) -> WaveController:
    """Return the animal's built-in travelling wave (from its file's [wave] table)."""
    phases = body.wave_phase.copy()
    ctrl = WaveController(
        body.name,
        body.actuator_names,
        frequency=body.wave_frequency,
        amplitude=body.wave_amplitude,
        offset=body.wave_offset,
        phases=tuple(float(p) for p in phases),
        hold=tuple(
            (name, float(v))
            for name, v in zip(body.actuator_names, body.wave_held, strict=True)
            if not np.isnan(v)
        ),
    )
    return ctrl


def time_domain(body: Body, nodes: int, duration: float, values=None, interp="linear"):
    """Return a time-domain controller for the body (values default to all 0.5)."""
    vals = np.full((body.n_actuators, nodes), 0.5) if values is None else values
    return TimeDomainController(body.name, body.actuator_names, duration, vals, interp)


def frequency_domain(body: Body, nodes: int, duration: float, amplitudes=None, base=None):
    """Return a frequency-domain controller on a Fourier basis of M functions over duration
    (harmonics of 1/duration), or of harmonics of ``base`` Hz (a periodic gait)."""
    omega, phase = fourier_basis(nodes, duration, base)
    amp = np.zeros((body.n_actuators, nodes)) if amplitudes is None else amplitudes
    return FrequencyDomainController(body.name, body.actuator_names, omega, phase, amp)


def from_dict(d: dict, where: str = "controller") -> Controller:
    """Return the controller described by a dict written by Controller.to_dict."""
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
                *common, float(d["frequency"]), float(d["amplitude"]), float(d["offset"]),
                tuple(float(p) for p in d["phases"]),
                tuple((str(k), float(v)) for k, v in d.get("hold", {}).items()),
            )  # fmt: skip
        if kind == "time":
            return TimeDomainController(
                *common, float(d["duration"]), np.array(d["values"], float),
                d.get("interp", "linear"),
            )  # fmt: skip
        if kind == "frequency":
            return FrequencyDomainController(
                *common, np.array(d["omega"], float), np.array(d["phase"], float),
                np.array(d["amplitudes"], float),
            )  # fmt: skip
        if kind == "mirrored":
            inner = from_dict(d["inner"], where)
            return MirroredController(*common, inner, tuple(int(m) for m in d["mirror"]))
        from zoetic.control.registry import from_dict_extra

        return from_dict_extra(d, where)
    except ControllerError as exc:
        raise ControllerError(f"{where}: {exc}") from None
    except (KeyError, TypeError, ValueError) as exc:
        raise ControllerError(
            f"{where}: malformed controller ({type(exc).__name__}: {exc})"
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
    from zoetic.io import write_json

    return write_json(path, ctrl.to_dict())


def load_controller(path: str | Path, body: Body | None = None) -> Controller:
    """Return the controller in a JSON file, checked against ``body`` when one is given."""
    from zoetic.io import read_json

    try:
        d = read_json(path, what="controller file")
    except ControllerError:
        raise
    except ZoeticError as exc:
        raise ControllerError(str(exc)) from None
    if not isinstance(d, dict):
        raise ControllerError(f"{path}: a controller file holds a JSON object")
    ctrl = from_dict(d, where=str(path))
    return check_fits(ctrl, body, str(path)) if body is not None else ctrl


def controller_from_spec(spec: str, body: Body) -> Controller:
    """Return the controller named by ``wave``, ``rest`` or the path of a controller file."""
    if spec == "wave":
        return wave_controller(body)
    if spec == "rest":
        return rest_controller(body)
    path = Path(spec)
    if not path.exists():
        raise ControllerError(f"{spec}: not a controller file (and not 'wave' or 'rest')")
    return load_controller(path, body)
