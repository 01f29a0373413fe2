"""Contacts never make energy: a ball bounces lower than it fell, a body that squeezes a ball
against its post launches it no faster than an elastic-with-restitution hit, a node driven
into a thin post is let out, not shot out."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from zoetic.physics.contacts import CORRECTION_SPEED, restitution
from zoetic.physics.media import Medium
from zoetic.physics.objects import Ball, Box, Cylinder
from zoetic.physics.world import Animal, World

AIR = Medium("air", gravity=9.81)
VACUUM = Medium("still", gravity=0.0)
R, M = 0.25, 0.3  # the stunts' beach ball


def _drop(body, support, medium, height):
    """Return the highest the ball's bottom gets after its first bounce, over its fall."""
    top = 0.0
    ball = Ball(radius=R, mass=M, position=(0.0, top + R + height, 0.0))
    far = Animal(body, offset=(50.0, 10.0, 0.0))
    world = World([far, ball, *support], medium=medium)
    y = []
    for _ in range(int(1.2 / (10 * world.dt))):
        world.step(10 * world.dt)
        y.append(world.ball_positions[0, 0, 1])
    y = np.array(y)
    first = int(np.argmax(np.diff(y) > 0))  # the first bounce
    return (y[first:].max() - R - top) / height


@pytest.mark.parametrize("support, medium", [
    ([Cylinder(center=(0.0, -0.5, 0.0), radius=0.05, length=1.0)], AIR),
    ([Box(center=(0.0, -0.5, 0.0), half_size=(0.5, 0.5, 0.5))], AIR),
    ([], Medium("floor", gravity=9.81, floor=True)),
])  # fmt: skip
def test_a_dropped_ball_never_rebounds_higher_than_it_fell(dolphin, support, medium):
    for height in (0.3, 1.0):
        rebound = _drop(dolphin, support, medium, height)
        e = restitution(0.3)
        assert 0.0 < rebound < 1.0
        assert rebound == pytest.approx(e * e, abs=0.05)  # the restitution the world sets


def _squeeze(body, lanes, seconds=0.6):
    """Bodies (rigidly moving at the start) thrown at a ball resting on its post, without
    gravity; return the ball's top speed per lane, the bodies' start speeds, the world."""
    post = Cylinder(center=(0.0, -0.5, 0.0), radius=0.05, length=1.0)
    world = World([body, Ball(radius=R, mass=M, position=(0.0, R, 0.0)), post], medium=VACUUM,
                  batch=len(lanes))  # fmt: skip
    rest = body.rest_pos - body.mass @ body.rest_pos / body.total_mass
    pos = np.stack([rest + (x, y, 0.0) for x, y, _, _ in lanes])
    vel = np.stack([np.broadcast_to((vx, vy, 0.0), rest.shape) for _, _, vx, vy in lanes])
    world.restore(replace(world.initial_state(), positions=(pos,), velocities=(vel,)))
    top = np.zeros(len(lanes))
    for _ in range(int(seconds / world.dt)):
        world.step(world.dt)
        top = np.maximum(top, np.linalg.norm(world.ball_velocities[:, 0], axis=1))
    return top, np.hypot(*np.array(lanes)[:, 2:].T), world


def test_a_ball_squeezed_on_its_post_leaves_no_faster_than_an_elastic_hit_allows(dolphin):
    # bellies falling onto the ball from above at 2 and 4 m/s (pinned against the post), and
    # noses driven into it level, and from above at a slant, at 3 and 5 m/s
    above = R + 0.196 + 0.03 + 0.1
    lanes = [(x, R + above, 0.0, -v) for x in np.linspace(-1.6, -0.1, 4) for v in (2.0, 4.0)]
    lanes += [(-1.3, y, v, 0.0) for y in np.linspace(-0.2, 0.6, 5) for v in (3.0, 5.0)]
    lanes += [(-1.45, y + 0.3, v, -0.5 * v) for y in np.linspace(-0.2, 0.6, 5) for v in (3.0, 5.0)]
    top, speed, world = _squeeze(dolphin, lanes)
    mass = dolphin.total_mass
    bound = (1.0 + restitution(0.3)) * mass / (mass + M) * speed + CORRECTION_SPEED
    assert (top > 0.3 * speed).sum() > len(lanes) // 2  # most lanes really struck the ball
    assert (top <= bound).all(), (top / speed).max()
    # and the contacts pushed the ball and the body apart: at most 1 cm of overlap is left
    gap = np.linalg.norm(world.positions(0) - world.ball_positions[:, :1], axis=2).min(axis=1)
    assert (gap > R + world.node_radius - 0.01).all()


def test_a_node_driven_into_a_thin_post_is_let_out_not_shot_out(dolphin):
    # the nose rams the post's top edge, the whole body behind it at 4.3 m/s
    post = Cylinder(center=(0.0, -0.5, 0.0), radius=0.05, length=1.0)
    world = World([dolphin, post], medium=VACUUM, batch=3)
    rest = dolphin.rest_pos - dolphin.rest_pos[dolphin.head]
    pos = np.stack([rest + (-0.05, y, 0.0) for y in (-0.02, 0.0, 0.02)])
    vel = np.broadcast_to((4.3, 0.0, 0.0), pos.shape).copy()
    world.restore(replace(world.initial_state(), positions=(pos,), velocities=(vel,)))
    touched, fastest = False, 0.0
    for _ in range(int(0.2 / world.dt)):
        touched |= bool(world.step(world.dt).touching.any())
        fastest = max(fastest, float(np.linalg.norm(world.velocities(0), axis=2).max()))
    assert touched
    # the body's own springs may fling the nose node (2x here); the penalty without its cap
    # on the separation speed shot it out at 17 m/s, 4x
    assert fastest < 3.0 * 4.3


def _near_node_by_node(pos, vel, radius, skind, scenter, ssize, horizon) -> bool:
    """``broadphase.near`` without balls, every node against every shape (the reference)."""
    from zoetic.physics.shapes import shape_sdf

    for b in range(pos.shape[2]):
        vmax = float(np.sqrt((vel[:, :, b] ** 2).sum(axis=1).max()))
        reach = 2.0 * (vmax + 0.0) * horizon + radius + 0.05
        for p in pos[:, :, b]:
            for s in range(len(skind)):
                if shape_sdf(s, skind, scenter, ssize, p[0], p[1], p[2])[0] < reach:
                    return True
    return False


def test_near_tests_the_shapes_within_reach_of_the_animal_as_every_shape():
    from zoetic.physics.broadphase import near

    rng = np.random.default_rng(6)
    skind = np.array([0, 1, 1, 1, 0], np.int64)  # boxes and cylinders along x, y and z
    scenter = rng.uniform(-1.0, 1.0, (5, 3))
    ssize = np.array([[0.3, 0.2, 0.4], [0.2, 0.5, 0], [0.1, 0.3, 1], [0.25, 0.2, 2], [1, 1, 1]])
    no_balls = (np.zeros((0, 3, 2)), np.zeros((0, 3, 2)), np.zeros((0, 2)))
    answers = []
    for _ in range(300):
        pos = rng.uniform(-2.5, 2.5, (1, 1, 3, 2)) + rng.normal(0.0, 0.2, (6, 1, 3, 2))
        pos = np.ascontiguousarray(pos.reshape(6, 3, 2))
        vel = rng.normal(0.0, 0.5, pos.shape)
        got = near(pos, vel, 0.03, *no_balls, skind, scenter, ssize, 0.1)
        assert got == _near_node_by_node(pos, vel, 0.03, skind, scenter, ssize, 0.1)
        answers.append(got)
    assert 30 < sum(answers) < 270  # near and apart both met
    # a node exactly at the reach of a box's face (along x): not near; a hair inside: near
    pos, vel = np.zeros((1, 3, 1)), np.zeros((1, 3, 1))
    box = (np.array([0], np.int64), np.zeros((1, 3)), np.array([[0.5, 0.5, 0.5]]))
    balls1 = (np.zeros((0, 3, 1)), np.zeros((0, 3, 1)), np.zeros((0, 2)))
    pos[0, 0, 0] = 0.5 + 0.08 + 1e-9
    assert not near(pos, vel, 0.03, *balls1, *box, 0.1)
    pos[0, 0, 0] = 0.5 + 0.08 - 1e-9
    assert near(pos, vel, 0.03, *balls1, *box, 0.1)
