"""Closed-loop rollouts: policies sense and act every control period while a World steps
(through the one driver, ``control.loop``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from zoetic.control.loop import Observer, Schedule, drive
from zoetic.control.policy import Period, Policy, as_policy
from zoetic.control.sensors import observe
from zoetic.errors import ControllerError
from zoetic.physics.simulate import State, Trajectory
from zoetic.physics.world import World, WorldState


@dataclass(frozen=True)
class Rollout:
    """What a rollout recorded: times (R,), per animal positions (B, R, N, 3), balls
    (B, R, K, 3), node-object pairs in contact during the stretch ending at each record
    (B, R), and the final world state."""

    times: np.ndarray
    positions: tuple[np.ndarray, ...]
    ball_positions: np.ndarray
    contacts: np.ndarray
    final: WorldState

    def trajectory(self, animal: int = 0) -> Trajectory:
        """Return one animal's record as a physics Trajectory (as ``simulate`` returns)."""
        return Trajectory(
            times=self.times,
            positions=self.positions[animal],
            final=State(self.final.positions[animal], self.final.velocities[animal]),
            failed_step=self.final.failed_step[animal],
            dt=self.final.dt,
        )


def _policies(world: World, policies) -> list[Policy]:
    n = len(world.animals)
    if isinstance(policies, Mapping):
        names = [a.name for a in world.animals]
        missing = [nm for nm in names if nm not in policies]
        if missing:
            raise ControllerError(f"no policy for the animal(s) {missing}")
        return [as_policy(policies[nm]) for nm in names]
    if n == 1 and not (isinstance(policies, Sequence) and len(policies) == 1):
        return [as_policy(policies)]
    if not isinstance(policies, Sequence) or len(policies) != n:
        raise ControllerError(f"give one policy for each of the world's {n} animals")
    return [as_policy(p) for p in policies]


class _Recorder(Observer):
    """Times, every animal's positions, the balls and the node-object contacts at each record."""

    def __init__(self, world: World) -> None:
        self.times: list[float] = []
        self.pos: list[list[np.ndarray]] = [[] for _ in world.animals]
        self.balls: list[np.ndarray] = []
        self.counts: list[np.ndarray] = []
        self.touched = np.zeros(world.batch, dtype=np.int64)

    def slice(self, world: World, contacts) -> None:
        if world.objects:
            self.touched += contacts.count

    def record(self, world: World) -> None:
        self.times.append(world.time)
        for a, p in enumerate(self.pos):
            p.append(world.positions(a))
        self.balls.append(world.ball_positions)
        self.counts.append(self.touched)
        self.touched = np.zeros(world.batch, dtype=np.int64)


class _Sensing(Observer):
    """Every animal's policy asked with its sensors' observations (the contacts of the last
    slice feed the touch sensors)."""

    def __init__(self, world: World, policies: list[Policy], target) -> None:
        self.policies, self.target, self.contacts = policies, target, None

    def slice(self, world: World, contacts) -> None:
        self.contacts = contacts

    def __call__(self, world: World, period: Period) -> list[np.ndarray]:
        return [
            p.act(observe(world, a, p.sensors, self.contacts, self.target), period)
            for a, p in enumerate(self.policies)
        ]


def rollout(
    world: World,
    policies,
    seconds: float,
    control_period: float = 1 / 30,
    record_every: int | None = None,
    target=None,
    seed: int | None = None,
) -> Rollout:
    """Run the world for ``seconds`` from its current state under closed-loop policies.

    policies: one per animal (a list, a dict by animal name, or one for a lone animal): a
    Policy, a Controller or an activation table. Each is reset with ``seed`` and then asked
    every ``control_period`` s. record_every: steps between records (default: at the end of
    each control period); a record is taken at t = now and at each multiple of it.
    target: a point or an object of the world, for the target sensors.
    """
    pols = _policies(world, policies)
    for p in pols:
        p.reset(seed)
    schedule = Schedule(control_period, record_every=record_every, record_end=False)
    rec = _Recorder(world)
    sensing = _Sensing(world, pols, target)
    drive(world, sensing, seconds, schedule, observers=(sensing, rec))
    return Rollout(
        times=np.array(rec.times) - rec.times[0],
        positions=tuple(np.stack(p, axis=1) for p in rec.pos),
        ball_positions=np.stack(rec.balls, axis=1),
        contacts=np.stack(rec.counts, axis=1),
        final=world.state,
    )
