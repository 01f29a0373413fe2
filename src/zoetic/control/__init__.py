"""What drives the muscles: controllers, their files, and the built-in ones of each animal."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from zoetic import io as rd
from zoetic.bodies import Body
from zoetic.control.controllers import (
    ConstantController,
    Controller,
    FrequencyDomainController,
    MirroredController,
    TimeDomainController,
    WaveController,
    fourier_basis,
)
from zoetic.control.files import check_fits, from_dict, load_controller, save_controller
from zoetic.errors import ControllerError

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
    "steered_wave",
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


def steered_wave(
    body: Body,
    times: np.ndarray,
    amplitude: float = 1.0,
    bias: float = 0.0,
    fins: float = 0.0,
    frequency: float | None = None,
) -> np.ndarray:
    """Return activations (T, A): the body's own wave (at ``frequency``, default its own) with
    the muscles' swing scaled by ``amplitude`` about the wave's offset, ``bias`` added to the
    left muscles and taken from the right ones (bias > 0 turns left), and ``fins`` added to
    the fins' held level (> 0 tilts them nose up: the animal rises); clipped to [0, 1]."""
    wave = wave_controller(body)
    if frequency is not None:
        wave = replace(wave, frequency=float(frequency))
    u = wave.sample(np.asarray(times, float))
    muscle = np.array([k == "muscle" for k in body.actuator_kind])
    side = np.array([{"left": 1.0, "right": -1.0}.get(s, 0.0) for s in body.actuator_side])
    swing = np.where(muscle, body.wave_offset + amplitude * (u - body.wave_offset), u)
    return np.clip(swing + np.where(muscle, bias * side, fins), 0.0, 1.0)


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


def controller_from_spec(spec: str, body: Body) -> Controller:
    """Return the controller named by ``wave``, ``rest`` or the path of a controller file."""
    if spec == "wave":
        return wave_controller(body)
    if spec == "rest":
        return rest_controller(body)
    path = Path(spec)
    if not path.exists():
        hint = rd.suggest(spec, ("wave", "rest"))
        raise ControllerError(f"{spec}: not a controller file (and not 'wave' or 'rest'){hint}")
    if path.is_dir():
        raise ControllerError(f"{spec}: is a directory; give a controller .json file")
    return load_controller(path, body)
