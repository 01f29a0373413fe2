"""A creature's own mechanical scales, from which the SAN search's defaults are derived.

Random SANs switch their actuators between targets; whether a switching pattern becomes a
gait depends on how the body answers: how fast each servo moves its limb (its natural
period) and whether it overshoots or creeps (its damping ratio). Those depend on the
creature's masses, sizes and gains, so defaults fixed in seconds (the paper's kd/ks = 0.1 s,
a 0.5 s locomotion cycle) suit creatures of the zoo's size and not a much smaller, larger
or stiffer one. Here the defaults come from the creature itself:

- ``joint_inertias``: per actuator, the body's inertia about (or, for a slide, the mass
  moved along) the actuated joint at the rest pose: MuJoCo's joint-space inertia matrix
  diagonal, the distal part of the tree the servo swings.
- ``servo_periods``: 2 pi sqrt(I / ks), each servo's undamped natural period (s).
- ``derived_kd``: the servo damping kd = 2 zeta sqrt(ks I) that gives the damping ratio
  ``DAMPING_RATIO`` (0.7, the textbook fast-without-ringing servo), whatever the size.
- ``derived_cycle``: the default expected locomotion cycle, ``CYCLE_PER_SERVO_PERIOD``
  servo periods (median over the actuators), so node delays (0.25 of it) keep pace with
  how fast the body can move.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "CYCLE_PER_SERVO_PERIOD",
    "DAMPING_RATIO",
    "derived_cycle",
    "derived_kd",
    "joint_inertias",
    "servo_periods",
]

DAMPING_RATIO = 0.7
CYCLE_PER_SERVO_PERIOD = 1.5  # the zoo's expected cycles lie at 0.8-2.4 servo periods


def joint_inertias(creature) -> np.ndarray:
    """Return (A,) the inertia (kg m^2; kg for a slide) each actuator drives, at rest."""
    import mujoco

    from zoetic.san.mjcf import build_mjcf

    model = mujoco.MjModel.from_xml_string(build_mjcf(creature))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    dofs = [int(model.jnt_dofadr[model.joint(a.joint).id]) for a in creature.actuators]
    return np.array([full[i, i] for i in dofs], dtype=float)


def servo_periods(creature, ks: np.ndarray | None = None) -> np.ndarray:
    """Return (A,) each servo's undamped natural period 2 pi sqrt(I / ks) (s)."""
    k = np.array([a.ks for a in creature.actuators], dtype=float) if ks is None else ks
    return 2.0 * math.pi * np.sqrt(joint_inertias(creature) / k)


def derived_kd(creature, zeta: float = DAMPING_RATIO) -> np.ndarray:
    """Return (A,) the servo damping kd = 2 zeta sqrt(ks I) for the damping ratio ``zeta``."""
    ks = np.array([a.ks for a in creature.actuators], dtype=float)
    return 2.0 * zeta * np.sqrt(ks * joint_inertias(creature))


def derived_cycle(creature) -> float:
    """Return the default expected locomotion cycle (s): ``CYCLE_PER_SERVO_PERIOD`` times the
    median servo period."""
    return CYCLE_PER_SERVO_PERIOD * float(np.median(servo_periods(creature)))


def own_scales(c, no_kd: set[str]):
    """Return creature ``c`` with its time scales derived from its own mechanics (this module):
    the expected cycle, and the damping of every actuator that gave no kd.

    The paper's two time constants, kd/ks = 0.1 s and node delays of 0.07-0.15 s (0.25 of
    the expected cycle), suit creatures of its size; a file that gives ``expected_cycle`` is
    taken to be calibrated in those terms (the zoo) and keeps kd/ks = 0.1 where it gives no
    kd. A file without it gets kd for a damping ratio of 0.7 about each actuated joint's own
    inertia, and a cycle of 1.5 servo periods, whatever its size and mass."""
    from dataclasses import replace

    kd = derived_kd(c)
    acts = tuple(
        replace(a, kd=float(kd[i])) if a.name in no_kd else a for i, a in enumerate(c.actuators)
    )
    c = replace(c, actuators=acts)
    return replace(c, expected_cycle=derived_cycle(c))
