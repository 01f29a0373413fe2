"""Abstraction of learned controllers into a few sinusoids per actuator (section 3, Fig. 9).

A time-domain controller's M nodal values span [0, duration] with both ends included. We read
them as one period of a periodic signal sampled N = M - 1 times, h = duration / N apart: the
first and last node sample the same phase, so the first sample is their mean (the trapezoidal
rule; exact when the controller is already periodic, half the jump otherwise) and the last is
dropped. ``numpy.fft.rfft`` of each actuator's N samples gives the DC term (kept as the
offset) and modes k / duration Hz for k = 1 .. N // 2, each with an amplitude and a phase:
    u_a(t) = offset_a + sum_k amp_ak cos(2 pi freq_ak t + phase_ak).
A frequency-domain controller needs no change of basis: the amplitudes of its bases at equal
frequencies are added as phasors and thresholded directly. "auto" keeps, per actuator, the
modes at least ``threshold`` times as strong as its strongest; an integer K keeps the K
strongest. The result is an ``AbstractController``, periodic, playable for any duration.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from zoetic.bodies import Body
from zoetic.control import (
    ConstantController,
    Controller,
    FrequencyDomainController,
    MirroredController,
    TimeDomainController,
    WaveController,
)
from zoetic.control.abstract import AbstractController
from zoetic.errors import ControllerError, ZoeticError
from zoetic.learning.objective import control_energy, signals
from zoetic.physics import Medium, get_medium, rest_state, simulate
from zoetic.tasks import Task, parse_task, start_state
from zoetic.tasks.terms import evaluate_terms

FORWARD = parse_task(
    {"name": "forward", "horizon": 1.0, "terms": [{"kind": "distance_along_heading"}]}
)

FLOOR = 1e-3  # modes weaker than this (activation units) are numerical noise, never kept


@dataclass(frozen=True)
class Spectrum:
    """All modes of a controller: offset (A,), and freq Hz, amp, phase rad, each (A, K)."""

    offset: np.ndarray
    freq: np.ndarray
    amp: np.ndarray
    phase: np.ndarray
    period: float  # s, the fundamental period (1 / lowest non-zero frequency)


@dataclass(frozen=True)
class Abstraction:
    """An abstracted controller with the spectrum it came from and which modes it kept."""

    controller: AbstractController
    spectrum: Spectrum
    kept: np.ndarray  # (A, K) bool over the spectrum's modes
    rule: str  # "auto (threshold 0.3)" or "3 strongest"

    def modes_per_actuator(self) -> np.ndarray:
        """Return the number of modes kept for each actuator, (A,)."""
        return self.kept.sum(axis=1)


def parse_modes(text: str | int) -> str | int:
    """Return "auto" or a positive int K from a --modes argument; ZoeticError otherwise."""
    if isinstance(text, int) or str(text).strip().isdigit():
        k = int(text)
        if k >= 1:
            return k
    elif str(text).strip().lower() == "auto":
        return "auto"
    raise ZoeticError(f"--modes must be 'auto' or a positive number of modes, got {text!r}")


def periodic_samples(ctrl: TimeDomainController) -> tuple[np.ndarray, float]:
    """Return (samples (A, M-1), period s): one period of the nodal signal, ends averaged."""
    u = ctrl.raw(ctrl.node_times()).T  # (A, M): the nodal values (curve values for B-splines)
    samples = u[:, :-1].copy()
    samples[:, 0] = 0.5 * (u[:, 0] + u[:, -1])
    return samples, float(ctrl.duration)


def fft_spectrum(samples: np.ndarray, period: float) -> Spectrum:
    """Return the Spectrum of signals sampled N times evenly over one period, (A, N)."""
    samples = np.atleast_2d(np.asarray(samples, float))
    a, n = samples.shape
    if n < 2:
        raise ControllerError(f"an FFT needs at least 2 samples per period, got {n}")
    x = np.fft.rfft(samples, axis=1) / n  # (A, n // 2 + 1)
    k = np.arange(1, x.shape[1])
    scale = np.where(2 * k == n, 1.0, 2.0)  # the Nyquist bin of an even N is not doubled
    amp = scale * np.abs(x[:, 1:])
    phase = np.angle(x[:, 1:])
    freq = np.broadcast_to(k / period, amp.shape).copy()
    return Spectrum(x[:, 0].real.copy(), freq, amp, phase, period)


def _phasor_spectrum(ctrl: FrequencyDomainController) -> Spectrum:
    """Spectrum of a sum of cosines: equal frequencies add as phasors A e^(i phi)."""
    hz = np.round(ctrl.omega / (2 * np.pi), 9)
    phasors = ctrl.amplitudes * np.exp(1j * ctrl.phase)[None, :]  # (A, M)
    offset = phasors[:, hz == 0].real.sum(axis=1)
    freqs = np.unique(hz[hz > 0])
    z = (
        np.stack([phasors[:, hz == f].sum(axis=1) for f in freqs], axis=1)
        if freqs.size
        else (np.zeros((ctrl.n_actuators, 0), complex))
    )
    period = float(1.0 / freqs.min()) if freqs.size else 1.0
    freq = np.broadcast_to(freqs, z.shape).copy()
    return Spectrum(offset, freq, np.abs(z), np.angle(z), period)


def spectrum(ctrl: Controller) -> Spectrum:
    """Return the modes of a time-domain, frequency-domain, wave, constant or abstract one."""
    if isinstance(ctrl, TimeDomainController):
        return fft_spectrum(*periodic_samples(ctrl))
    if isinstance(ctrl, FrequencyDomainController):
        return _phasor_spectrum(ctrl)
    if isinstance(ctrl, AbstractController):
        return Spectrum(
            ctrl.offset,
            ctrl.freq,
            np.abs(ctrl.amp),
            ctrl.phase + np.pi * (ctrl.amp < 0),
            ctrl.period,
        )
    a = ctrl.n_actuators
    if isinstance(ctrl, ConstantController):
        empty = np.zeros((a, 0))
        return Spectrum(np.asarray(ctrl.values, float), empty, empty, empty, 1.0)
    if isinstance(ctrl, WaveController):  # offset + amp/2 (1 + sin(2 pi (f t - p)))
        half = np.full((a, 1), 0.5 * ctrl.amplitude)
        phase = -2 * np.pi * np.asarray(ctrl.phases, float)[:, None] - np.pi / 2
        f = np.full((a, 1), float(ctrl.frequency))
        return Spectrum(
            np.full(a, ctrl.offset + 0.5 * ctrl.amplitude), f, half, phase, 1.0 / ctrl.frequency
        )
    raise ControllerError(
        f"cannot abstract a {ctrl.kind!r} controller (time, frequency, wave, constant, abstract "
        "or mirrored ones can be)"
    )


def select_modes(spec: Spectrum, modes: str | int = "auto", threshold: float = 0.3) -> np.ndarray:
    """Return the (A, K) mask of modes to keep: "auto" by relative threshold, or K strongest."""
    modes = parse_modes(modes)
    amp = spec.amp
    alive = amp >= FLOOR
    if amp.shape[1] == 0:
        return np.zeros(amp.shape, bool)
    if modes == "auto":
        if not 0.0 < threshold <= 1.0:
            raise ZoeticError(f"--threshold must be in (0, 1], got {threshold}")
        strongest = amp.max(axis=1, keepdims=True)
        return alive & (amp >= threshold * strongest - 1e-12)
    order = np.argsort(-amp, axis=1, kind="stable")
    rank = np.empty_like(order)
    np.put_along_axis(rank, order, np.arange(amp.shape[1])[None, :].repeat(len(amp), 0), axis=1)
    return alive & (rank < modes)


def from_spectrum(ctrl: Controller, spec: Spectrum, kept: np.ndarray) -> AbstractController:
    """Return the AbstractController of the kept modes, strongest first, padded with zeros."""
    a = spec.amp.shape[0]
    k = int(kept.sum(axis=1).max()) if kept.size else 0
    freq, amp, phase = np.zeros((a, k)), np.zeros((a, k)), np.zeros((a, k))
    for i in range(a):
        idx = np.flatnonzero(kept[i])
        idx = idx[np.argsort(-spec.amp[i, idx], kind="stable")]
        n = idx.size
        freq[i, :n], amp[i, :n] = spec.freq[i, idx], spec.amp[i, idx]
        phase[i, :n] = spec.phase[i, idx]
    phase = (phase + np.pi) % (2 * np.pi) - np.pi
    return AbstractController(
        ctrl.animal, tuple(ctrl.actuators), spec.offset.copy(), freq, amp, phase, float(spec.period)
    )


def abstract(ctrl: Controller, modes: str | int = "auto", threshold: float = 0.3) -> Abstraction:
    """Return the abstraction of a controller keeping its primary modes (see module doc)."""
    if isinstance(ctrl, MirroredController):
        inner = abstract(ctrl.inner, modes, threshold)
        perm = list(ctrl.mirror)
        s = inner.spectrum
        spec = Spectrum(s.offset[perm], s.freq[perm], s.amp[perm], s.phase[perm], s.period)
        return Abstraction(
            mirror_abstract(inner.controller, perm), spec, inner.kept[perm], inner.rule
        )
    spec = spectrum(ctrl)
    kept = select_modes(spec, modes, threshold)
    rule = (
        f"auto (threshold {threshold:g})"
        if parse_modes(modes) == "auto"
        else (f"{modes} strongest")
    )
    return Abstraction(from_spectrum(ctrl, spec, kept), spec, kept, rule)


def mirror_abstract(ctrl: AbstractController, mirror) -> AbstractController:
    """Return the abstracted controller with left and right actuator signals swapped."""
    p = [int(m) for m in mirror]
    if sorted(p) != list(range(ctrl.n_actuators)):
        raise ControllerError(f"mirror {p} is not a permutation of {ctrl.n_actuators} actuators")
    return AbstractController(
        ctrl.animal,
        tuple(ctrl.actuators),
        ctrl.offset[p],
        ctrl.freq[p],
        ctrl.amp[p],
        ctrl.phase[p],
        ctrl.period,
    )


def measure(
    body: Body,
    ctrl: Controller,
    seconds: float,
    medium: Medium | str | None = None,
    dt: float | None = None,
    task: Task | None = None,
) -> dict:
    """Return how a controller moves the body: distance, forward, heading, E, path.

    It starts from rest, or from the task's start state when a task is given. distance:
    metres the centre of mass moved (top view); forward: metres along the start heading;
    heading_change: rad, left positive; E, E_u, E_v: the task's objective (as ``Objective``
    scores it, with the same terms) when a task is given; com (R, 3), heading (R,), times (R,).
    """
    med = get_medium(medium or body.medium)
    dt = float(dt or body.dt)
    steps = int(round(seconds / dt))
    rate = task.record_hz if task is not None else 20.0
    every = max(1, int(round(1.0 / (rate * dt))))
    start = start_state(task, body, med) if task is not None else rest_state(body, 1)
    table = ctrl.table(steps, dt)
    traj = simulate(body, table[None], med, dt, start, every)
    pos = traj.positions
    rows = np.minimum(np.arange(pos.shape[1]) * every, steps - 1)
    s = signals(task or FORWARD, body, pos, table[rows][None], every * dt, med)
    com = s.com[0]
    heading = s.heading[0]
    out = {
        "seconds": float(seconds),
        "failed": bool(traj.failed[0]),
        "distance": float(np.linalg.norm(com[-1, [0, 2]] - com[0, [0, 2]])),
        "forward": float(s.along[0]),
        "heading_change": float(heading[-1] - heading[0]),
        "com": com,
        "heading": heading,
        "times": traj.times,
    }
    if task is not None:
        values = evaluate_terms(np, s, task.terms)
        e_v = float(sum(t.weight * v[0] for t, v in zip(task.terms, values, strict=True)))
        u = ctrl.raw(np.linspace(0.0, task.horizon, task.nodes)).T[None]
        e_u = float(control_energy(u, task.horizon / (task.nodes - 1), task.nu1, task.nu2)[0])
        out |= {"E": task.mu1 * e_u + task.mu2 * e_v, "E_u": e_u, "E_v": e_v}
        if out["failed"]:
            out |= {"E": float("inf"), "E_v": float("inf")}
    return out


def summary(m: dict) -> dict:
    """Return the JSON-able numbers of a ``measure`` result (rounded, no arrays)."""
    keys = ("distance", "forward", "heading_change", "E", "E_u", "E_v")
    return {k: round(float(m[k]), 4) for k in keys if k in m} | {"failed": m["failed"]}


def primary_measure(task: Task | None) -> str:
    """Return the measure a task is about: heading_change for turns (a heading or body-axis
    heading term with a target other than 0), else forward (a straight gait that keeps its
    heading is still about distance)."""
    turns = ("heading_change", "body_heading_change")
    if task is not None and any(t.kind in turns and t.target != 0.0 for t in task.terms):
        return "heading_change"
    return "forward"


@dataclass(frozen=True)
class Comparison:
    """The original and the abstracted controller on one task, from the same start."""

    measure: str  # the quantity ``kept`` compares: forward or heading_change
    original: dict  # ``measure`` results (with arrays)
    abstract: dict

    @property
    def kept(self) -> float:
        """Return abstracted / original of the primary measure (1.0 = nothing lost)."""
        a, b = self.original[self.measure], self.abstract[self.measure]
        return float(b / a) if abs(a) > 1e-9 else float("nan")

    def to_dict(self) -> dict:
        """Return the JSON-able numbers."""
        return {
            "measure": self.measure,
            "kept": round(self.kept, 4),
            "original": summary(self.original),
            "abstract": summary(self.abstract),
        }


def compare(
    body: Body,
    original: Controller,
    abstracted: Controller,
    task: Task,
    medium: Medium | str | None = None,
) -> Comparison:
    """Return both controllers' behaviour over the task's horizon and what the abstraction keeps."""
    a = measure(body, original, task.horizon, medium, task=task)
    b = measure(body, abstracted, task.horizon, medium, task=task)
    return Comparison(primary_measure(task), a, b)
