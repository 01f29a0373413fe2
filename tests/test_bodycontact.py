"""Animal-animal contact (physics.bodycontact): two sharks driven into each other."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.bodies import load_animal
from zoetic.physics.bodycontact import deepest
from zoetic.physics.world import Animal, World


def _kinetic(world: World, body) -> float:
    return sum(0.5 * float((body.mass[:, None] * world.velocities(a)[0] ** 2).sum())
               for a in range(2))  # fmt: skip


def _collide(contact: bool, side: float, speed: float = 1.0):
    """Two passive sharks nose to nose in a vacuum, closing at 2 x ``speed`` m/s, offset
    ``side`` m sideways; return (deepest node inside the other m, kinetic energies J (0 first),
    impulse recorded between them, the first shark's final x velocity)."""
    body = load_animal("shark")
    a = Animal(body, (0.0, 0.0, 0.0), 0.0, (speed, 0.0, 0.0))
    b = Animal(body, (1.3, 0.0, side), np.pi, (-speed, 0.0, 0.0))
    world = World([a, b], medium="vacuum", animal_contact=contact)
    energy, deep, between = [_kinetic(world, body)], 0.0, 0.0
    for _ in range(80):
        c = world.step(0.01, None)
        if c.between is not None:
            between += float(c.between.sum())
        pa, pb = world.positions(0)[0], world.positions(1)[0]
        deep = max(deep, deepest(pa, pb, body.faces), deepest(pb, pa, body.faces))
        energy.append(_kinetic(world, body))
    vx = float(body.mass @ world.velocities(0)[0][:, 0] / body.total_mass)
    return deep, np.array(energy), between, vx


def test_without_contact_the_bodies_pass_through_each_other():
    deep, _, between, vx = _collide(False, 0.1)
    assert deep > 0.04  # the measure sees a node well inside the other body
    assert between == 0.0
    assert vx > 0.7  # and the shark swims on


@pytest.mark.parametrize("side", [0.0, 0.1, 0.2])
def test_contact_keeps_bodies_apart_without_adding_energy(side):
    deep, energy, between, vx = _collide(True, side)
    assert deep < 0.015  # at most 1.5 cm past the other's skin, closing at 2 m/s
    assert between > 0.0  # the world recorded the contact
    # the contact never raised the kinetic energy (the pair starts at rest shape, so there is
    # no stored elastic energy to release) and, dissipative, took some away
    assert energy.max() <= energy[0] * (1 + 1e-4)
    assert energy[-1] < 0.9 * energy[0]
    assert vx < 0.9  # the first shark was slowed or turned back


def test_deepest_measures_a_node_inside_the_surface():
    body = load_animal("shark")
    inside = body.rest_pos[5:9].mean(axis=0)  # the middle of the thickest cross-section
    probe = np.vstack([inside, inside + [0.0, 1.0, 0.0]])
    assert deepest(probe, body.rest_pos, body.faces) == pytest.approx(0.12, abs=0.01)
    assert deepest(probe[1:], body.rest_pos, body.faces) == 0.0
