"""A lone animal's contact steps looped in one compiled call step the same bits as the general
loop, one contact test, one kernel step and one ball step at a time from Python."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from zoetic.physics.media import MEDIA
from zoetic.physics.objects import Ball, Cylinder
from zoetic.physics.stepping import ContactSlices
from zoetic.physics.world import World


def _thrown(body, objects, lanes: int, compiled: bool, monkeypatch):
    """Lanes of the dolphin thrown up at ``objects`` near the sea's surface with random
    activations; return its positions, velocities, the balls' state and the contacts."""
    monkeypatch.setattr(ContactSlices, "compiled_lone", compiled)
    world = World([body, *objects], medium=MEDIA["sea"], batch=lanes)
    rng = np.random.default_rng(3)
    rest = body.rest_pos - body.mass @ body.rest_pos / body.total_mass
    pos = np.stack([rest + (x, -0.6, 0.0) for x in rng.uniform(-0.4, 0.4, lanes)])
    vel = np.stack([np.broadcast_to((0.0, vy, 0.0), rest.shape) for vy in rng.uniform(5, 7, lanes)])
    world.restore(replace(world.initial_state(), positions=(pos,), velocities=(vel,)))
    steps = world.steps_for(10 * world.dt)
    touched = []
    for _ in range(40):
        acts = rng.uniform(0.0, 1.0, (lanes, steps, body.n_actuators))
        touched.append(world.step(10 * world.dt, acts).impulse[0].copy())
    return world.positions(0), world.velocities(0), world.ball_velocities, np.array(touched)


@pytest.mark.parametrize(
    "objects",
    [
        [Ball(radius=0.25, mass=0.3, position=(0.0, 0.8, 0.0))],
        [Cylinder(center=(0.0, 0.0, 0.0), radius=0.05, length=2.0, axis="z")],
    ],
    ids=["ball", "bar"],
)
@pytest.mark.parametrize("lanes", [1, 16])  # the kernel's one-animal path and its lane path
def test_compiled_lone_contact_steps_equal_the_general_loop_to_the_bit(
    dolphin, objects, lanes, monkeypatch
):
    fast = _thrown(dolphin, objects, lanes, True, monkeypatch)
    slow = _thrown(dolphin, objects, lanes, False, monkeypatch)
    assert np.abs(slow[3]).sum() > 0.0  # the lanes did touch the object
    for a, b in zip(fast, slow, strict=True):
        np.testing.assert_array_equal(a, b)
