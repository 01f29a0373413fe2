"""The grid that finds which targets may lie within a fish's range misses no pair."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.behavior.aquarium.neighbours import near_pairs


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


def test_a_narrow_tank_or_an_endless_range_gives_all_pairs():
    rng = np.random.default_rng(0)
    eyes, targets = rng.uniform(-5, 5, (7, 3)), rng.uniform(-5, 5, (9, 3))
    for reach in (6.0, np.inf):
        rows, cols = near_pairs(eyes, targets, reach)
        assert np.array_equal(rows, np.repeat(np.arange(7), 9))
        assert np.array_equal(cols, np.tile(np.arange(9), 7))
    rows, cols = near_pairs(eyes, np.zeros((0, 3)), 1.0)
    assert len(rows) == len(cols) == 0
