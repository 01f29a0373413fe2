"""A lone animal's contact steps looped in one compiled call step the same bits as the general
loop, one contact test, one kernel step and one ball step at a time from Python, also where
it takes the sub-slices in which nothing can touch as free slices (``lone_every``)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from zoetic.physics.media import MEDIA
from zoetic.physics.objects import Ball, Cylinder
from zoetic.physics.stepping import ContactSlices
from zoetic.physics.world import World


def _thrown(body, objects, lanes: int, compiled: bool, monkeypatch, every: int = 0):
    """Lanes of the dolphin thrown up at ``objects`` near the sea's surface with random
    activations, a lone lockstep slice's reach checked every ``every`` steps; return its
    positions, velocities, the balls' state, the contacts and the steps taken untested."""
    monkeypatch.setattr(ContactSlices, "compiled_lone", compiled)
    monkeypatch.setattr(ContactSlices, "lone_every", every)
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
    state = world.positions(0), world.velocities(0), world.ball_velocities, np.array(touched)
    return state, world._contacts.untested_steps


@pytest.mark.parametrize(
    "objects",
    [
        [Ball(radius=0.25, mass=0.3, position=(0.0, 0.8, 0.0))],
        [Cylinder(center=(0.0, 0.0, 0.0), radius=0.05, length=2.0, axis="z")],
    ],
    ids=["ball", "bar"],
)
@pytest.mark.parametrize("lanes", [1, 16])  # the kernel's one-animal path and its lane path
@pytest.mark.parametrize("every", [0, 5])  # every step tested; untested sub-slices of 5 steps
def test_compiled_lone_contact_steps_equal_the_general_loop_to_the_bit(
    dolphin, objects, lanes, every, monkeypatch
):
    fast, untested = _thrown(dolphin, objects, lanes, True, monkeypatch, every)
    slow, none = _thrown(dolphin, objects, lanes, False, monkeypatch)
    assert np.abs(slow[3]).sum() > 0.0  # the lanes did touch the object
    assert none == 0 and (untested > 0) == (every > 0)  # some lockstep steps went untested
    for a, b in zip(fast, slow, strict=True):
        np.testing.assert_array_equal(a, b)
