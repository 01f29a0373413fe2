"""The one closed-loop driver: every control period it asks for activations, steps the world in
slices that end at the record times, and tells its observers what happened.

Every closed loop of zoetic (``rollout``, the aquarium, pursuit, stunts, tracking replay, the Gym
environments) runs through ``drive`` (a whole run) or ``step_period`` (one period, for callers
such as Gym that are handed one action at a time). A feature supplies:

- ``decide(world, period)``: the activations of every animal for the period (observe, decide,
  act), one array per animal, (B, A) held over the period or (B, T, A) one row a step;
- observers (``Observer``): called when a record is due, after each stepped slice with its
  contacts, and at each period's end (events, scalars, recordings);
- ``stop(world)``: checked after each period; True ends the run early.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from zoetic.control.policy import Period
from zoetic.errors import ControllerError
from zoetic.physics.world import World


class Observer:
    """Hooks of the driver; each does nothing unless a subclass overrides it."""

    def record(self, world: World) -> None:
        """A record is due: at the start, at each record time and at the run's end."""

    def slice(self, world: World, contacts) -> None:
        """A slice of a period was stepped; ``contacts`` is what ``World.step`` returned."""

    def period(self, world: World, period: Period) -> None:
        """The control period ``period`` has been stepped to its end."""


@dataclass(frozen=True)
class Schedule:
    """When the driver asks for activations and records.

    control_period: seconds between decisions. fixed: every period has round(control_period /
    dt) steps (the last one cut at the end); otherwise periods end on the dt grid nearest to
    multiples of control_period, so that decisions come at the asked-for rate on average.
    record_every: steps between records, counted from the run's start (None: at each period's
    end). record_end: also record at the run's end when it falls between record times.
    plan: asked with the world at each period's start for that period's steps (a planner
    that commits to windows of varying length); None: the periods come from control_period.
    """

    control_period: float = 1 / 30
    fixed: bool = False
    record_every: int | None = None
    record_end: bool = True
    plan: Callable[[World], int] | None = None

    def __post_init__(self) -> None:
        if not self.control_period > 0:
            raise ControllerError(f"control_period must be positive, got {self.control_period}")
        if self.record_every is not None and int(self.record_every) < 1:
            raise ControllerError("record_every must be at least 1")


def periods(world: World, seconds: float, schedule: Schedule) -> Iterator[Period]:
    """Yield the control periods of a run of ``seconds`` from the world's current step."""
    dt = world.dt
    start = world.step_count
    end = start + world.steps_for(seconds)
    fixed = max(1, int(round(schedule.control_period / dt)))
    k, i = start, 0
    while k < end:
        i += 1
        if schedule.plan is not None:
            steps = min(max(1, int(schedule.plan(world))), end - k)
        elif schedule.fixed:
            steps = min(fixed, end - k)
        else:
            steps = min(max(1, start + int(round(i * schedule.control_period / dt)) - k), end - k)
        yield Period(k, steps, dt)
        k += steps


def as_rows(u, world: World, animal: int, steps: int) -> np.ndarray:
    """Return one animal's activations for a period as a (B, steps, A) array, checked."""
    u = np.asarray(u, dtype=float)
    na = world.bodies[animal].n_actuators
    if u.shape == (world.batch, steps, na):  # already one row a step for every lane
        return u
    if u.ndim == 1:
        u = u[None]
    if u.ndim == 2:  # held over the period
        u = np.broadcast_to(u[:, None, :], (u.shape[0], steps, u.shape[1]))
    if u.shape[1:] != (steps, na) or u.shape[0] not in (1, world.batch):
        raise ControllerError(
            f"the {world.bodies[animal].name}'s policy returned activations {u.shape}; "
            f"expected ({world.batch}, {steps}, {na}) or ({world.batch}, {na})"
        )
    return np.broadcast_to(u, (world.batch, steps, na))


def step_period(
    world: World,
    rows: Sequence[np.ndarray],
    period: Period,
    observers: Sequence[Observer] = (),
    record_every: int | None = None,
    origin: int = 0,
    end: int | None = None,
) -> None:
    """Step one control period under ``rows`` (one (B, steps, A) array per animal), in slices
    that end at the record times (every ``record_every`` steps from step ``origin``; None: only
    at the period's end), calling each observer's ``slice``, ``record`` and ``period``."""
    dt, steps = world.dt, period.steps
    j = 0
    while j < steps:
        here = world.step_count - origin
        m = steps - j if not record_every else min(steps - j, record_every - here % record_every)
        contacts = world.step(m * dt, [r[:, j : j + m] for r in rows])
        j += m
        for o in observers:
            o.slice(world, contacts)
        on_grid = (world.step_count - origin) % record_every == 0 if record_every else j == steps
        if on_grid or world.step_count == end:
            for o in observers:
                o.record(world)
    for o in observers:
        o.period(world, period)


def drive(
    world: World,
    decide: Callable[[World, Period], Sequence[np.ndarray]],
    seconds: float,
    schedule: Schedule = Schedule(),
    observers: Sequence[Observer] = (),
    stop: Callable[[World], bool] | None = None,
) -> int:
    """Run the world for ``seconds`` from its current state in closed loop and return the
    number of control periods run. Observers get a record at the start, at each record time
    (and at the end where ``schedule.record_end``), each slice's contacts and each period's end;
    ``stop`` ends the run early after a period."""
    origin = world.step_count
    end = origin + world.steps_for(seconds) if schedule.record_end else None
    every = None if schedule.record_every is None else int(schedule.record_every)
    for o in observers:
        o.record(world)
    n = 0
    for period in periods(world, seconds, schedule):
        raw = decide(world, period)
        rows = [as_rows(u, world, a, period.steps) for a, u in enumerate(raw)]
        step_period(world, rows, period, observers, every, origin, end)
        n += 1
        if stop is not None and stop(world):
            break
    return n
