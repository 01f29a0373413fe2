"""A node box judged apart from a shape or a ball (``shapes.box_apart``) holds no point that
could touch it: the contacts skip such lanes and nodes on that judgement alone, so a wrong
judgement would drop real contacts."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.physics.contacts import GAP
from zoetic.physics.objects import Box, Cylinder, pack_statics
from zoetic.physics.shapes import box_apart, node_box, shape_apart, shape_sdf

RADIUS = 0.04  # m, a node's contact radius


def _points(rng, n: int) -> np.ndarray:
    """Random points around the origin, many of them near the shapes' surfaces."""
    return rng.uniform(-0.8, 0.8, (n, 3))


@pytest.mark.parametrize(
    "shape",
    [
        Cylinder(center=(0.1, 0.2, 0.0), radius=0.05, length=1.0, axis="y"),
        Cylinder(center=(0.0, 0.0, 0.1), radius=0.3, length=0.4, axis="x"),
        Box(center=(0.0, -0.1, 0.0), half_size=(0.5, 0.1, 0.3)),
    ],
)
def test_a_point_judged_apart_from_a_shape_is_beyond_a_node_radius(shape):
    kind, center, size = pack_statics([shape])
    rng = np.random.default_rng(0)
    apart = touching = 0
    for p in _points(rng, 3000):
        far = shape_apart((*p, *p), 0, kind, center, size, RADIUS + GAP)
        d = shape_sdf(0, kind, center, size, *p)[0]
        touching += d < RADIUS
        if far:
            apart += 1
            assert d > RADIUS
    assert apart > 100 and touching > 10  # both cases were tried


def test_a_lane_box_judged_apart_from_a_ball_has_no_node_within_reach():
    rng = np.random.default_rng(1)
    r = 0.25
    ball = np.array([0.2, 0.1, 0.0])
    apart = 0
    for _ in range(300):
        nodes = rng.uniform(-0.6, 0.6, (20, 3)) * rng.uniform(0.1, 1.0) + rng.uniform(-1, 1, 3)
        pos = nodes[:, :, None].astype(np.float32)  # (N, 3, one lane)
        if box_apart(node_box(pos, 0, 0.0), *ball, r, r, r, RADIUS + GAP):
            apart += 1
            assert np.linalg.norm(pos[:, :, 0] - ball, axis=1).min() > r + RADIUS
    assert 30 < apart < 270  # both cases were tried
