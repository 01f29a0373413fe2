"""Closed-loop rollouts: policies sense and act every control period while a World steps."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

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


def _as_rows(u, world: World, animal: int, steps: int) -> np.ndarray:
    u = np.asarray(u, dtype=float)
    na = world.bodies[animal].n_actuators
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
    dt = world.dt
    if not control_period > 0:
        raise ControllerError(f"control_period must be positive, got {control_period}")
    rec_every = int(record_every) if record_every is not None else 0  # 0: at each period end
    if record_every is not None and rec_every < 1:
        raise ControllerError("record_every must be at least 1")
    start = world.step_count
    end = start + world.steps_for(seconds)
    times = [world.time]
    pos = [[world.positions(a)] for a in range(len(world.animals))]
    balls = [world.ball_positions]
    counts = [np.zeros(world.batch, dtype=np.int64)]
    touched = np.zeros(world.batch, dtype=np.int64)
    contacts = None
    k = start
    i = 0
    while k < end:
        # periods end on the dt grid nearest to multiples of control_period (1/30 s with dt
        # 5 ms alternates 7 and 6 steps), so that policies are asked at the asked-for rate
        i += 1
        steps = min(max(1, start + int(round(i * control_period / dt)) - k), end - k)
        period = Period(k, steps, dt)
        rows = []
        for a, p in enumerate(pols):
            obs = observe(world, a, p.sensors, contacts, target)
            rows.append(_as_rows(p.act(obs, period), world, a, steps))
        j = 0
        while j < steps:
            here = k + j - start
            m = steps - j if not rec_every else min(steps - j, rec_every - here % rec_every)
            contacts = world.step(m * dt, [r[:, j : j + m] for r in rows])
            if world.objects:
                touched += contacts.count
            j += m
            if (j == steps if not rec_every else (k + j - start) % rec_every == 0):
                times.append(world.time)
                for a in range(len(world.animals)):
                    pos[a].append(world.positions(a))
                balls.append(world.ball_positions)
                counts.append(touched)
                touched = np.zeros(world.batch, dtype=np.int64)
        k += steps
    return Rollout(
        times=np.array(times) - times[0],
        positions=tuple(np.stack(p, axis=1) for p in pos),
        ball_positions=np.stack(balls, axis=1),
        contacts=np.stack(counts, axis=1),
        final=world.state,
    )
