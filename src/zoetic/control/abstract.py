"""Abstracted controllers (a few sinusoids per actuator) and sequences of blended controllers.

An abstracted controller is periodic, so it can be played for any duration:
    u_a(t) = offset_a + sum_k amp_ak cos(2 pi freq_ak t + phase_ak).
A sequence plays controllers one after another; each overlaps the next by a fraction of its
length (5% by default) and the two are cross-faded linearly over the overlap (section 3.1).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from zoetic.control.blend import add_item
from zoetic.control.controllers import Controller
from zoetic.errors import ControllerError

# an abstract controller's mode waves kept for a plan search: the times t (T,) s they were
# taken at, and the waves there (AbstractController.waves)
Waves = tuple[np.ndarray, np.ndarray]


@dataclass(frozen=True)
class AbstractController(Controller):
    """Per actuator: an offset and K modes (frequency Hz, amplitude, phase rad)."""

    offset: np.ndarray = None  # (A,)
    freq: np.ndarray = None  # (A, K) Hz
    amp: np.ndarray = None  # (A, K)
    phase: np.ndarray = None  # (A, K) rad
    period: float = 1.0  # s, the period all modes share (for display)
    kind = "abstract"

    def __post_init__(self):
        a = len(self.actuators)
        off = np.asarray(self.offset, float).reshape(a)
        f, am, ph = (np.asarray(v, float) for v in (self.freq, self.amp, self.phase))
        if f.ndim != 2 or f.shape[0] != a or am.shape != f.shape or ph.shape != f.shape:
            raise ControllerError(
                f"abstract controller: freq, amp, phase must be (actuators={a}, K), got "
                f"{f.shape}, {am.shape}, {ph.shape}"
            )
        for name, v in (("offset", off), ("freq", f), ("amp", am), ("phase", ph)):
            object.__setattr__(self, name, v)

    @property
    def modes(self) -> int:
        """Return the number of non-zero modes."""
        return int(np.count_nonzero(self.amp))

    def resumed(self, t0: float) -> AbstractController:
        """Return the controller as it plays from ``t0`` s on, with its own clock reset:
        ``resumed(t0).raw(t) == raw(t0 + t)`` (each mode's phase advanced by 2 pi f t0), so a
        sequence item that takes over mid-stroke carries the stroke on instead of restarting."""
        return dataclasses.replace(self, phase=self.phase + 2 * np.pi * self.freq * float(t0))

    def raw(self, t):
        """Return unclipped activations (T, A) at times t (s): offset plus the cosine modes."""
        t = np.asarray(t, float)[:, None, None]
        waves = self.amp * np.cos(2 * np.pi * self.freq * t + self.phase)  # (T, A, K)
        # the modes added in order: NumPy's reduction over a short last axis is slow
        total = np.zeros(waves.shape[:2])
        for k in range(waves.shape[2]):
            total = total + waves[:, :, k]
        return self.offset[None, :] + total

    def waves(self, t) -> np.ndarray:
        """Return each mode's unit wave at times t (s) as (2, K, T, A): cos and sin of
        2 pi freq t, from which ``blend.add_item`` plays the controller started at any time."""
        wt = 2 * np.pi * self.freq.T[:, None, :] * np.asarray(t, float)[None, :, None]
        return np.stack([np.cos(wt), np.sin(wt)])

    def ahead(self, seconds: float) -> AbstractController:
        """Return this gait ``seconds`` ahead: it plays at t what this one plays at t + seconds
        (each mode's phase advanced by 2 pi freq seconds)."""
        phase = self.phase + 2.0 * np.pi * self.freq * float(seconds)
        return AbstractController(
            self.animal, self.actuators, self.offset, self.freq, self.amp, phase, self.period
        )

    def to_dict(self):
        """Return the base description plus period (s), offset, freq (Hz), amp, phase (rad)."""
        return super().to_dict() | {
            "period": self.period,
            "offset": self.offset.round(6).tolist(),
            "freq": self.freq.round(6).tolist(),
            "amp": self.amp.round(6).tolist(),
            "phase": self.phase.round(6).tolist(),
        }


@dataclass(frozen=True)
class SequenceController(Controller):
    """Controllers played in turn, each for its duration, cross-faded over the overlaps."""

    items: tuple = ()  # ((Controller, duration s), ...)
    overlap: float = 0.05  # fraction of each controller's length shared with the next
    kind = "sequence"

    def __post_init__(self):
        if not self.items:
            raise ControllerError("a sequence needs at least one controller")
        for ctrl, duration in self.items:
            if tuple(ctrl.actuators) != tuple(self.actuators):
                raise ControllerError(
                    "every controller in a sequence must drive the same actuators"
                )
            if not duration > 0:
                raise ControllerError(f"sequence durations must be positive, got {duration}")
        if not 0.0 <= self.overlap < 0.5:
            raise ControllerError(f"overlap must be in [0, 0.5), got {self.overlap}")

    def starts(self) -> np.ndarray:
        """Return the time (s) at which each controller starts."""
        d = np.array([dur for _, dur in self.items])
        return np.concatenate([[0.0], np.cumsum(d[:-1] * (1.0 - self.overlap))])

    @property
    def duration(self) -> float:
        """The total time (s) from the first controller's start to the last one's end."""
        return float(self.starts()[-1] + self.items[-1][1])

    def weights(self, t: np.ndarray) -> np.ndarray:
        """Return each controller's blend weight (T, n) at times t; rows sum to 1.

        Controller i fades in linearly over its overlap with i-1 and out over its overlap
        with i+1; the first holds before time 0 and the last holds after its end.
        """
        t = np.asarray(t, float)[:, None]
        s = self.starts()[None, :]
        e = s + np.array([dur for _, dur in self.items])[None, :]
        n = s.shape[1]
        fade_in = np.ones((t.shape[0], n))
        fade_out = np.ones((t.shape[0], n))
        if n > 1:
            width = np.maximum(e[:, :-1] - s[:, 1:], 1e-12)  # overlap of i and i+1
            fade_in[:, 1:] = np.clip((t - s[:, 1:]) / width, 0.0, 1.0)
            fade_out[:, :-1] = np.clip((e[:, :-1] - t) / width, 0.0, 1.0)
        return fade_in * fade_out

    def waves(self, t) -> dict[int, Waves]:
        """Return each abstract item's times and ``AbstractController.waves`` at them, by the
        item controller's id: what ``raw`` computes afresh, kept to play many sequences of
        the same controllers at the same times (a plan search)."""
        t = np.asarray(t, float).reshape(-1)
        ctrls = {id(c): c for c, _ in self.items if isinstance(c, AbstractController)}
        return {key: (t, c.waves(t)) for key, c in ctrls.items()}

    def raw(self, t, waves: dict[int, Waves] | None = None):
        """Return unclipped activations (T, A) at t (s): the blend-weighted item outputs.
        Abstract items are played from their modes' waves at t (``blend.add_item``;
        ``waves``: those of this sequence's controllers at these t, as ``waves(t)`` returns
        them, filled in where missing or taken at other times)."""
        t = np.asarray(t, float).reshape(-1)
        out = np.zeros((t.size, self.n_actuators))
        starts = self.starts()
        ends = starts + np.array([dur for _, dur in self.items])
        n, w = len(self.items), None
        for i, (ctrl, _) in enumerate(self.items):
            if not isinstance(ctrl, AbstractController):
                w = self.weights(t) if w is None else w
                on = w[:, i] > 0
                if on.any():
                    out[on] += w[on, i : i + 1] * ctrl.raw(t[on] - starts[i])
                continue
            # the rows it plays (add_item leaves the others alone): after its start, but the
            # first item's, and before its end, but the last item's
            after = t > starts[i] if i > 0 else np.ones(t.size, bool)
            on = np.flatnonzero(after & (t < ends[i]) if i < n - 1 else after)
            if on.size == 0:
                continue
            rows = slice(on[0], on[-1] + 1)
            if waves is None:
                own = ctrl.waves(t[rows])
            else:
                kept = waves.get(id(ctrl))
                if kept is None or not np.array_equal(kept[0], t):  # none yet, or other times
                    kept = waves[id(ctrl)] = (t, ctrl.waves(t))
                own = kept[1][:, :, rows]
            # each fade: (where it starts, its width s); width 0: none (the first item holds
            # before its start, the last after its end)
            fade_in = (starts[i], max(ends[i - 1] - starts[i], 1e-12)) if i > 0 else (0.0, 0.0)
            fade_out = (ends[i], max(ends[i] - starts[i + 1], 1e-12)) if i < n - 1 else (0.0, 0.0)
            c = ctrl
            add_item(
                out[rows],
                t[rows],
                own,
                c.offset,
                c.freq,
                c.amp,
                c.phase,
                starts[i],
                fade_in,
                fade_out,
            )
        return out

    def table(self, steps: int, dt: float, t0: float = 0.0, waves=None) -> np.ndarray:
        """Return the activation table (steps, A) for a simulation of ``steps`` steps of dt
        (``waves``: as ``raw``'s, at these steps' times)."""
        return np.clip(self.raw(t0 + np.arange(steps) * dt, waves), 0.0, 1.0)

    def to_dict(self):
        """Return the base description plus overlap and each item's duration (s) and dict."""
        return super().to_dict() | {
            "overlap": self.overlap,
            "items": [{"duration": dur, "controller": c.to_dict()} for c, dur in self.items],
        }
