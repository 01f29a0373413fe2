"""What the tank works out only near each fish or obstacle equals working out everything: the
grid of pairs within range misses no pair, the fish threats of the near pairs are those of
every pair, and the deepest point inside an obstacle is the deepest."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.behavior.aquarium import routines
from zoetic.behavior.aquarium.neighbours import near_pairs
from zoetic.behavior.aquarium.perception import deepest_inside, obstacle_distance
from zoetic.physics.objects import Box, Cylinder, pack_statics


def _within(eyes, targets, reach):
    d = np.linalg.norm(targets[None] - eyes[:, None], axis=-1)
    return set(zip(*np.nonzero(d <= reach), strict=True))


@pytest.mark.parametrize("seed", range(5))
def test_grid_pairs_hold_every_pair_within_range(seed):
    rng = np.random.default_rng(seed)
    reach = float(rng.choice([2.0, 3.0, 6.0, 8.0]))
    eyes = rng.uniform(-50, 50, (300, 3)) * [1.0, 0.04, 1.0]
    targets = rng.uniform(-50, 50, (400, 3)) * [1.0, 0.04, 1.0]
    # targets exactly at the range from an eye (quarter metres: exact sums), along x, z
    # and across a cell's corner (3-4-5), and one at the same point as an eye
    eyes[:40] = np.round(eyes[:40] * 4) / 4
    targets[:10] = eyes[:10] + [reach, 0.0, 0.0]
    targets[10:20] = eyes[10:20] - [0.0, 0.0, reach]
    targets[20:30] = eyes[20:30] + [0.6 * reach, 0.0, -0.8 * reach]
    targets[30] = eyes[30]
    rows, cols = near_pairs(eyes, targets, reach)
    got = set(zip(rows.tolist(), cols.tolist(), strict=True))
    want = _within(eyes, targets, reach)
    assert want <= got
    assert len(got) == len(set(got)) == len(rows)  # no pair twice
    assert len(got) < 0.2 * len(eyes) * len(targets)  # and far fewer than all the pairs
    # each eye's targets in ascending order, the eyes in order
    order = np.lexsort((cols, rows))
    assert np.array_equal(order, np.arange(len(rows)))


def test_a_point_flung_far_away_loses_no_pair():
    # the grid is at most MAX_CELLS wide: its cells grow, and every pair within range stays
    rng = np.random.default_rng(5)
    eyes, targets = rng.uniform(-40, 40, (200, 3)), rng.uniform(-40, 40, (300, 3))
    eyes[0], targets[0] = [3e7, 0.0, -2e7], [3e7 + 2.0, 0.0, -2e7]
    rows, cols = near_pairs(eyes, targets, 6.0)
    got = set(zip(rows.tolist(), cols.tolist(), strict=True))
    assert _within(eyes, targets, 6.0) <= got and (0, 0) in got


def test_a_narrow_tank_or_an_endless_range_gives_all_pairs():
    rng = np.random.default_rng(0)
    eyes, targets = rng.uniform(-5, 5, (7, 3)), rng.uniform(-5, 5, (9, 3))
    for reach in (6.0, np.inf):  # 6 m: three cells wide, all neighbours
        rows, cols = near_pairs(eyes, targets, reach)
        assert np.array_equal(rows, np.repeat(np.arange(7), 9))
        assert np.array_equal(cols, np.tile(np.arange(9), 7))
    rows, cols = near_pairs(eyes, np.zeros((0, 3)), 1.0)
    assert len(rows) == len(cols) == 0


def test_deepest_inside_equals_the_least_signed_distance_of_every_point():
    kind, center, size = pack_statics(
        [
            Box((0.0, 0.0, 0.0), (1.0, 2.0, 0.6)),
            Cylinder((3.0, 0.0, -2.0), 0.7, 4.0, "y"),
            Box((-3.0, 0.0, 2.5), (0.4, 2.0, 1.2)),
        ]
    )
    rng = np.random.default_rng(2)
    points = rng.uniform(-5, 5, (400, 3))
    want = max(0.0, float(-obstacle_distance(points, kind, center, size).min()))
    assert want > 0.1  # some points lie well inside
    assert deepest_inside(points, kind, center, size) == want
    outside = points[obstacle_distance(points, kind, center, size).min(axis=1) > 0]
    assert deepest_inside(outside, kind, center, size) == 0.0
    on_face = np.array([[1.0, 0.0, 0.0], [-0.5, 0.0, 0.6]])  # on the box's faces: 0 deep
    assert deepest_inside(on_face, kind, center, size) == 0.0


@pytest.mark.parametrize("seed", range(3))
def test_fish_threats_of_near_pairs_equal_those_of_every_pair(seed, monkeypatch):
    # a crowd swimming every way in 12 x 12 m: some fishes threaten each other, many seen
    # pairs are too far apart to; dropping those (``_within_box_reach``) changes nothing
    rng = np.random.default_rng(seed)
    n = 120
    com = np.column_stack([rng.uniform(-6, 6, n), rng.uniform(-0.3, 0.3, n), rng.uniform(-6, 6, n)])
    fwd = rng.normal(size=(n, 3)) * [1.0, 0.1, 1.0]
    fwd /= np.linalg.norm(fwd, axis=1, keepdims=True)
    nose = com + 0.35 * fwd
    vel = fwd * rng.uniform(0.0, 1.2, (n, 1)) + rng.normal(0, 0.1, (n, 3))
    seen = rng.random((n, n)) < 0.8
    np.fill_diagonal(seen, False)
    region = (np.full(n, 0.7), np.full(n, 0.45), np.full(n, 1.5))  # reach, half width, s
    prefer = rng.integers(-1, 2, n)
    got = routines.fish_threats(nose, com, fwd, vel, seen, *region, prefer)
    kept = routines._within_box_reach(*np.nonzero(seen), nose, com, vel, *region)
    monkeypatch.setattr(routines, "_within_box_reach", lambda ii, jj, *rest: (ii, jj))
    want = routines.fish_threats(nose, com, fwd, vel, seen, *region, prefer)
    for a, b in zip(got, want, strict=True):
        assert np.array_equal(a, b)
    assert (want[0] >= 0).sum() > 10  # threats found
    assert len(kept[0]) < 0.5 * seen.sum()  # and most pairs dropped
