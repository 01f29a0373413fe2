"""One protocol for everything that drives muscles: observations in, activations out.

A ``Policy`` is asked once per control period. It gets the observation dict of the sensors it
declares (``sensors``; batch axis first, see ``control.sensors``) and the ``Period`` to fill,
and returns activations for that period: (B, A) held over it, or (B, T, A) one row a step.
``reset(seed)`` starts an episode. Open-loop controllers are policies that ignore what they
see (``OpenLoopPolicy``); so is a precomputed table (``TablePolicy``); ``as_policy`` makes a
policy of either.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from zoetic.control.controllers import Controller
from zoetic.errors import ControllerError


@dataclass(frozen=True)
class Period:
    """A control period: ``steps`` time steps of ``dt`` starting at step ``start``."""

    start: int
    steps: int
    dt: float

    @property
    def t0(self) -> float:
        """Return the time (s) at which the period starts."""
        return self.start * self.dt

    @property
    def times(self) -> np.ndarray:
        """Return the (T,) times (s) of the period's steps."""
        return (self.start + np.arange(self.steps)) * self.dt


@runtime_checkable
class Policy(Protocol):
    """Observations in every control period, activations for the next one out."""

    sensors: tuple[str, ...]

    def reset(self, seed: int | None = None) -> None:
        """Start a new episode (a stochastic policy reseeds its generator)."""
        ...

    def act(self, observation: Mapping[str, np.ndarray], period: Period) -> np.ndarray:
        """Return activations (B, A) held over ``period`` or (B, T, A) one row a step."""
        ...


class OpenLoopPolicy:
    """An open-loop controller u(t) (or one per lane) as a policy that ignores observations."""

    sensors: tuple[str, ...] = ()

    def __init__(self, controllers: Controller | Sequence[Controller]) -> None:
        self.controllers = (
            [controllers] if isinstance(controllers, Controller) else list(controllers)
        )
        if not self.controllers:
            raise ControllerError("an open-loop policy needs at least one controller")

    def reset(self, seed: int | None = None) -> None:
        """Nothing to reset: u(t) depends on time only."""

    def act(self, observation: Mapping[str, np.ndarray], period: Period) -> np.ndarray:
        """Return the controllers sampled at the period's steps, (B, T, A)."""
        t = period.times
        rows = np.stack([c.sample(t) for c in self.controllers])
        batch = len(observation["time"]) if "time" in observation else len(rows)
        if len(rows) == batch:
            return rows
        if len(rows) == 1:
            return np.broadcast_to(rows, (batch, *rows.shape[1:]))
        raise ControllerError(f"{len(rows)} controllers for {batch} lanes")


class TablePolicy:
    """A precomputed activation table (B, T, A) played row by row (zeros past its end)."""

    sensors: tuple[str, ...] = ()

    def __init__(self, table: np.ndarray) -> None:
        t = np.asarray(table, dtype=float)
        self.table = t[None] if t.ndim == 2 else t
        if self.table.ndim != 3:
            raise ControllerError(f"an activation table is (B, T, A), got {t.shape}")

    def reset(self, seed: int | None = None) -> None:
        """Nothing to reset: the table is fixed."""

    def act(self, observation: Mapping[str, np.ndarray], period: Period) -> np.ndarray:
        """Return the table's rows for the period's steps, (B, T, A)."""
        b, n, a = self.table.shape
        rows = np.zeros((b, period.steps, a))
        end = min(n, period.start + period.steps)
        if end > period.start:
            rows[:, : end - period.start] = self.table[:, period.start : end]
        return rows


def as_policy(x) -> Policy:
    """Return ``x`` as a Policy: a policy itself, a Controller (or a list of them, one per
    lane) or an activation table (B, T, A)."""
    if isinstance(x, Controller) or (
        isinstance(x, list | tuple) and x and all(isinstance(c, Controller) for c in x)
    ):
        return OpenLoopPolicy(x)
    if isinstance(x, np.ndarray):
        return TablePolicy(x)
    if isinstance(x, Policy):
        return x
    raise ControllerError(f"not a policy, controller or activation table: {type(x).__name__}")
