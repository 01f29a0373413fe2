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


def test_close_pairs_finds_the_pairs_close_finds_one_by_one(pairs_one_by_one):
    from zoetic.physics.bodycontact import close_pairs

    rng = np.random.default_rng(3)
    sizes = [5, 7, 4, 6]
    off = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    centres = np.array([[0.0, 0, 0], [0.5, 0, 0], [5.0, 0, 0], [5.4, 0.2, 0]])
    pos = np.concatenate([c + 0.2 * rng.normal(size=(n, 3))
                          for c, n in zip(centres, sizes, strict=True)])  # fmt: skip
    pos = np.ascontiguousarray(pos[:, :, None])
    vel = np.ascontiguousarray(0.1 * rng.normal(size=pos.shape))
    reach = np.array([0.1, 0.2, 0.1, 0.15])
    found = [tuple(p) for p in close_pairs(pos, vel, off, reach, 0.03, 0.1).tolist()]
    one_by_one = pairs_one_by_one(pos, vel, off, reach, 0.03, 0.1)
    assert found == one_by_one
    assert (0, 1) in found and (0, 2) not in found  # near pairs only


def _overlapping_sharks(n: int, lanes: int, seed: int):
    """n sharks crowded into a 1 m square (many pairs overlap), stacked as a World stacks
    them: positions and velocities (N, 3, lanes) float32, each shark's first row, masses."""
    body = load_animal("shark")
    rng = np.random.default_rng(seed)
    shift = rng.uniform(-0.5, 0.5, (n, 1, 3, lanes)) * [[[1.0], [0.2], [1.0]]]
    pos = (body.rest_pos[None, :, :, None] + shift).reshape(-1, 3, lanes)
    vel = rng.normal(0.0, 0.5, pos.shape)
    off = np.arange(n + 1, dtype=np.int64) * body.n_nodes
    return body, pos.astype(np.float32), vel.astype(np.float32), off


def test_every_pairs_contacts_in_one_call_are_those_of_each_pair_in_turn():
    from zoetic.physics.bodycontact import pair_contacts, pairs_contacts

    n, lanes = 6, 2
    body, pos, vel, off = _overlapping_sharks(n, lanes, 3)
    pairs = np.array([(a, c) for a in range(n) for c in range(a + 1, n)], np.int64)[::-1]
    mass, faces = body.mass.astype(np.float64), np.asarray(body.faces, np.int64)
    v_one, between_one = vel.copy(), np.zeros((lanes, n, n))
    for a, c in pairs:  # each pair in turn, as the world stepped them one call a pair
        buf = np.zeros((2, lanes))
        ra, rc = slice(off[a], off[a + 1]), slice(off[c], off[c + 1])
        pair_contacts(pos[ra], v_one[ra], mass, faces, pos[rc], v_one[rc], mass, faces,
                      0.03, 0.005, 80.0, 0.3, buf)  # fmt: skip
        between_one[:, a, c] += buf[0]
        between_one[:, c, a] += buf[1]
    v_all, between_all = vel.copy(), np.zeros((lanes, n, n))
    face_off = np.arange(n + 1, dtype=np.int64) * len(faces)
    pairs_contacts(pos, v_all, off, np.tile(mass, n), np.tile(faces, (n, 1)), face_off,
                   pairs, 0.03, 0.005, 80.0, 0.3, between_all)  # fmt: skip
    assert (between_one > 0).sum() >= 4 and not np.array_equal(v_one, vel)  # they touched
    assert np.array_equal(v_all, v_one) and np.array_equal(between_all, between_one)


def test_close_among_keeps_the_pairs_close_finds_one_by_one(pairs_one_by_one):
    from zoetic.physics.bodycontact import close_among

    n, lanes = 12, 2
    body, pos, vel, off = _overlapping_sharks(n, lanes, 4)
    pos[: off[n // 2]] += np.float32(1.5)  # two crowds apart: some pairs close, some not
    reach = np.random.default_rng(1).uniform(0.1, 0.3, n)
    every = np.array([(a, c) for a in range(n) for c in range(a + 1, n)], np.int64)
    keep = close_among(pos, vel, off, every, reach, 0.03, 0.02)
    one_by_one = pairs_one_by_one(pos, vel, off, reach, 0.03, 0.02)
    assert 0 < len(one_by_one) < len(every)
    assert [tuple(p) for p in every[keep].tolist()] == one_by_one
