"""A batch's balls are resolved lane by lane as if each lane were alone: lanes whose ball is in
the same state share one solution (``lane_memo.recalled``), which must be the bits each lane
would get by itself, whether the states repeat in order or interleaved, differ only in the
sign of a zero, or a node touches the ball in one lane."""

from __future__ import annotations

import numpy as np

from zoetic.physics.balls import balls_step
from zoetic.physics.contacts import node_contacts
from zoetic.physics.media import MEDIA
from zoetic.physics.objects import Ball, Cylinder
from zoetic.physics.world import World

# lane -> which ball state it holds: repeats, interleaved, and a lane of its own
PATTERN = [0, 0, 1, 0, 2, 1, 4, 0, 3, 2, 0, 1, 4]


def _batch(body):
    """A ball resting on a post in len(PATTERN) lanes, in five states (3 differs from 0 only by
    a -0.0 velocity, 4 from 1 by its velocity), the dolphin's nodes far from it except in lane 4,
    where its snout sinks into the ball; return the arrays ``node_contacts`` reads."""
    lanes = len(PATTERN)
    post = Cylinder(center=(0.0, 1.0, 0.0), radius=0.05, length=2.0, axis="y")
    world = World(
        [body, Ball(radius=0.25, mass=0.3, position=(0.0, 2.24, 0.0)), post],
        medium=MEDIA["sea"],
        batch=lanes,
    )
    c = world._contacts
    s = c.solids
    states = [((0.0, 2.24, 0.0), (0.0, 0.0, 0.0)), ((0.01, 2.245, 0.0), (0.3, -0.2, 0.0))]
    states += [((0.0, 2.3, 0.02), (0.0, -1.0, 0.1)), ((0.0, 2.24, 0.0), (-0.0, 0.0, -0.0))]
    states += [((0.01, 2.245, 0.0), (0.3, -0.4, 0.0))]  # state 1's place, another velocity
    for b, q in enumerate(PATTERN):
        s.pos[0, :, b], s.vel[0, :, b] = states[q]
    p, v = c.views[0]
    snout = int(np.argmax(p[:, 0, 4]))
    p[:, :, 4] += (np.array(s.pos[0, :, 4]) + (0.2, 0.0, 0.0) - p[snout, :, 4]).astype(np.float32)
    v[:, 1, :] = -0.5
    return c, s, p, v


def _resolve(c, s, p, v, lanes):
    """Copies of the given lanes' arrays after one step's node contacts and ball step."""
    pos, vel = p[:, :, lanes].copy(), v[:, :, lanes].copy()
    bpos, bvel, bforce = (a[:, :, lanes].copy() for a in (s.pos, s.vel, s.force))
    impulse = np.zeros((pos.shape[0], len(s.columns), 3, len(lanes)))
    consts = (s.par, s.kind, s.center, s.size)
    node_contacts(
        pos, vel, c.mass[0], c.node_radius, bpos, bvel, *consts, s.ball_col, s.static_col,
        c.dt, c.w, c.zeta, c.mu, bforce, impulse,
    )  # fmt: skip
    contact_force = bforce.copy()
    balls_step(bpos, bvel, *consts[:1], bforce, c.med64, c.current, *consts[1:], c.dt, 3,
               c.w, c.zeta, c.mu)  # fmt: skip
    return vel, bpos, bvel, contact_force, impulse


def test_lanes_sharing_a_ball_state_get_the_bits_each_would_get_alone(dolphin):
    c, s, p, v = _batch(dolphin)
    together = _resolve(c, s, p, v, list(range(len(PATTERN))))
    assert np.abs(together[4][:, :, :, 4]).sum() > 0.0  # the snout struck the ball in lane 4
    assert np.abs(together[3][:, :, 0]).sum() > 0.0  # the post holds the resting ball up
    for b in range(len(PATTERN)):
        alone = _resolve(c, s, p, v, [b])
        for x, y in zip(together, alone, strict=True):
            np.testing.assert_array_equal(x[..., b : b + 1].view(np.uint8), y.view(np.uint8))
