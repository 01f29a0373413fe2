"""Open-loop controllers u(t): parameters plus a pure function of time, sampled to a table.

Every controller knows the animal and the actuator names it was made for, samples to an
activation table (T, A) clipped to [0, 1], and converts to and from a JSON-able dict.
Learnable ones expose a flat parameter vector with bounds so optimizers never see the shape.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from zoetic.errors import ControllerError


@dataclass(frozen=True)
class Controller:
    """Base class: ``animal`` and ``actuators`` name what it drives."""

    animal: str
    actuators: tuple[str, ...]

    kind = "base"

    @property
    def n_actuators(self) -> int:
        """The number A of actuators it drives (columns of its activation table)."""
        return len(self.actuators)

    def raw(self, t: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        """Return unclipped activations (T, A) at times t (s); subclasses define it."""
        raise NotImplementedError

    def sample(self, t: np.ndarray) -> np.ndarray:
        """Return activations (T, A) in [0, 1] at times t (s)."""
        return np.clip(self.raw(np.asarray(t, dtype=np.float64)), 0.0, 1.0)

    def table(self, steps: int, dt: float, t0: float = 0.0) -> np.ndarray:
        """Return the activation table (steps, A) for a simulation of ``steps`` steps of dt."""
        return self.sample(t0 + np.arange(steps) * dt)

    def to_dict(self) -> dict:
        """Return a JSON-able description (loadable with control.from_dict)."""
        return {"type": self.kind, "animal": self.animal, "actuators": list(self.actuators)}

    # learnable controllers override these three
    def params(self) -> np.ndarray:
        """Return the flat vector of learnable parameters."""
        return np.zeros(0)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Return (lower, upper) bounds of the learnable parameters."""
        return np.zeros(0), np.zeros(0)

    def with_params(self, p: np.ndarray) -> Controller:
        """Return a copy with the learnable parameters replaced."""
        return self

    def mirrored(self, mirror: np.ndarray) -> Controller:
        """Return the controller with left and right actuator signals swapped."""
        return MirroredController(self.animal, self.actuators, self, tuple(int(m) for m in mirror))


@dataclass(frozen=True)
class ConstantController(Controller):
    """Each actuator held at a constant activation (``rest`` is all zeros)."""

    values: tuple[float, ...] = ()
    kind = "constant"

    def raw(self, t):
        """Return (T, A) copies of ``values``, one row per time in t (s)."""
        return np.broadcast_to(np.asarray(self.values, float), (len(t), self.n_actuators)).copy()

    def to_dict(self):
        """Return the base description plus ``values``, JSON-able."""
        return super().to_dict() | {"values": list(self.values)}


@dataclass(frozen=True)
class WaveController(Controller):
    """A travelling wave: u_a(t) = offset + amplitude * (1 + sin(2 pi (f t - phase_a))) / 2;
    actuators in ``hold`` (name, value) are held at that value instead."""

    frequency: float = 1.0
    amplitude: float = 1.0
    offset: float = 0.0
    phases: tuple[float, ...] = ()
    hold: tuple[tuple[str, float], ...] = ()
    kind = "wave"

    def raw(self, t):
        """Return the unclipped wave (T, A) at times t (s), held actuators at their value."""
        ph = np.asarray(self.phases, float)
        s = np.sin(2 * np.pi * (self.frequency * t[:, None] - ph[None, :]))
        u = self.offset + self.amplitude * 0.5 * (1.0 + s)
        for name, value in self.hold:
            u[:, self.actuators.index(name)] = value
        return u

    def to_dict(self):
        """Return the base description plus frequency, amplitude, offset, phases, hold."""
        out = super().to_dict() | {
            "frequency": self.frequency,
            "amplitude": self.amplitude,
            "offset": self.offset,
            "phases": list(self.phases),
        }
        if self.hold:
            out["hold"] = dict(self.hold)
        return out


@dataclass(frozen=True)
class TimeDomainController(Controller):
    """M nodal values per actuator, evenly spaced over [0, duration], linear or B-spline."""

    duration: float = 1.0
    values: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))  # (A, M)
    interp: str = "linear"
    kind = "time"

    def __post_init__(self):
        vals = np.asarray(self.values, dtype=np.float64)
        if vals.ndim != 2 or vals.shape[0] != len(self.actuators) or vals.shape[1] < 2:
            raise ControllerError(
                f"time-domain values must be (actuators={len(self.actuators)}, M>=2), "
                f"got {vals.shape}"
            )
        if self.interp not in ("linear", "bspline"):
            raise ControllerError(f"unknown interpolation {self.interp!r} (linear or bspline)")
        if not self.duration > 0:
            raise ControllerError(f"duration must be positive, got {self.duration}")
        object.__setattr__(self, "values", vals)

    @property
    def nodes(self) -> int:
        """The number M of nodal values per actuator."""
        return int(self.values.shape[1])

    def node_times(self) -> np.ndarray:
        """Return the M node times (s)."""
        return np.linspace(0.0, self.duration, self.nodes)

    def design_matrix(self, t: np.ndarray) -> np.ndarray:
        """Return B (T, M) with u(t) = B @ values.T: tent functions or cubic B-splines."""
        tc = np.clip(np.asarray(t, dtype=np.float64), 0.0, self.duration)
        m = self.nodes
        if self.interp == "linear":
            return np.stack([np.interp(tc, self.node_times(), e) for e in np.eye(m)], axis=1)
        from scipy.interpolate import BSpline

        k = min(3, m - 1)
        inner = np.linspace(0.0, self.duration, m - k + 1)
        knots = np.concatenate([np.zeros(k), inner, np.full(k, self.duration)])
        return BSpline.design_matrix(tc, knots, k).toarray()

    def raw(self, t):
        """Return unclipped activations (T, A) interpolated from the nodes at t (s)."""
        return self.design_matrix(t) @ self.values.T

    def params(self):
        """Return a copy of the nodal values (A, M), flattened to (A*M,)."""
        return self.values.ravel().copy()

    def bounds(self):
        """Return (lower, upper) of shape (A*M,): every nodal value in [0, 1]."""
        n = self.values.size
        return np.zeros(n), np.ones(n)

    def with_params(self, p):
        """Return a copy with nodal values from flat p (A*M,) reshaped to (A, M)."""
        return replace(self, values=np.asarray(p, float).reshape(self.values.shape))

    def to_dict(self):
        """Return the base description plus duration, interp and values (A, M)."""
        return super().to_dict() | {
            "duration": self.duration,
            "interp": self.interp,
            "values": self.values.round(6).tolist(),
        }


def fourier_basis(
    m: int, duration: float, base: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Return (omega, phase) of M cosine bases: a constant, then cos/sin pairs of harmonics.

    The harmonics are of 1/duration (the horizon, the paper's basis) or of ``base`` Hz when it
    is given: then the signal repeats every 1/base seconds, so a gait learned on a horizon
    keeps going when it is played longer than that.
    """
    omega, phase = [0.0], [0.0]
    fundamental = (1.0 / duration) if base is None else float(base)
    k = 1
    while len(omega) < m:
        w = 2 * np.pi * k * fundamental
        omega.append(w)
        phase.append(0.0)
        if len(omega) < m:
            omega.append(w)
            phase.append(-np.pi / 2)
        k += 1
    return np.array(omega), np.array(phase)


@dataclass(frozen=True)
class FrequencyDomainController(Controller):
    """u_i(t) = sum_j A_ij cos(w_j t + phi_j); the amplitudes A (A, M) are the parameters."""

    omega: np.ndarray = field(default_factory=lambda: np.zeros(1))  # (M,) rad/s
    phase: np.ndarray = field(default_factory=lambda: np.zeros(1))  # (M,) rad
    amplitudes: np.ndarray = field(default_factory=lambda: np.zeros((0, 1)))  # (A, M)
    kind = "frequency"

    def __post_init__(self):
        amp = np.asarray(self.amplitudes, dtype=np.float64)
        om = np.asarray(self.omega, dtype=np.float64).ravel()
        ph = np.asarray(self.phase, dtype=np.float64).ravel()
        if amp.ndim != 2 or amp.shape != (len(self.actuators), om.size) or ph.size != om.size:
            raise ControllerError(
                f"frequency-domain amplitudes must be (actuators={len(self.actuators)}, "
                f"M={om.size}) with M phases, got {amp.shape} and {ph.size}"
            )
        object.__setattr__(self, "amplitudes", amp)
        object.__setattr__(self, "omega", om)
        object.__setattr__(self, "phase", ph)

    @property
    def nodes(self) -> int:
        """The number M of cosine bases (harmonic terms) per actuator."""
        return int(self.omega.size)

    def design_matrix(self, t: np.ndarray) -> np.ndarray:
        """Return B (T, M) with u(t) = B @ amplitudes.T: the cosine bases at times t."""
        t = np.asarray(t, dtype=np.float64)
        return np.cos(t[:, None] * self.omega[None, :] + self.phase[None, :])

    def raw(self, t):
        """Return unclipped activations (T, A): the cosine sums at times t (s)."""
        return self.design_matrix(t) @ self.amplitudes.T

    def params(self):
        """Return a copy of the amplitudes (A, M), flattened to (A*M,)."""
        return self.amplitudes.ravel().copy()

    def bounds(self):
        """Return (lower, upper) (A*M,): [0, 1] for the constant, else [-0.5, 0.5]."""
        lo = np.where(self.omega == 0, 0.0, -0.5)
        hi = np.where(self.omega == 0, 1.0, 0.5)
        a = len(self.actuators)
        return np.tile(lo, a), np.tile(hi, a)

    def with_params(self, p):
        """Return a copy with amplitudes from flat p (A*M,) reshaped to (A, M)."""
        return replace(self, amplitudes=np.asarray(p, float).reshape(self.amplitudes.shape))

    def to_dict(self):
        """Return the base description plus omega (rad/s), phase (rad), amplitudes."""
        return super().to_dict() | {
            "omega": self.omega.round(9).tolist(),
            "phase": self.phase.round(9).tolist(),
            "amplitudes": self.amplitudes.round(6).tolist(),
        }


@dataclass(frozen=True)
class MirroredController(Controller):
    """Another controller with its actuator signals permuted (left and right swapped)."""

    inner: Controller | None = None
    mirror: tuple[int, ...] = ()
    kind = "mirrored"

    def raw(self, t):
        """Return the inner controller's unclipped (T, A) with columns permuted by mirror."""
        return self.inner.raw(t)[:, list(self.mirror)]

    def to_dict(self):
        """Return the base description plus the inner controller's dict and mirror."""
        return super().to_dict() | {"inner": self.inner.to_dict(), "mirror": list(self.mirror)}
