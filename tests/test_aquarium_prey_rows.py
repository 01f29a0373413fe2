"""The seeing fishes' sighting reads every prey fish's nodes at once (``vision.prey_rows``):
each fish's rows of ``World.node_positions`` in the order given, none leaked from a
neighbour, and where each fish's block starts."""

from __future__ import annotations

import numpy as np

from zoetic.behavior.aquarium.vision import prey_rows


def test_prey_rows_are_each_fishs_own_block_in_order() -> None:
    sizes = np.array([3, 5, 2, 4, 1])
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    prey = np.array([3, 0, 4, 1])  # not sorted: the caller's order is kept
    rows, starts = prey_rows(offsets, prey)
    owner = np.repeat(np.arange(len(sizes)), sizes)  # which fish each node row belongs to
    assert len(rows) == sizes[prey].sum()
    for k, fish in enumerate(prey):
        block = rows[starts[k] : starts[k] + sizes[fish]]
        assert np.array_equal(block, np.arange(offsets[fish], offsets[fish + 1]))
        assert np.all(owner[block] == fish)
    # a reduceat over the starts groups exactly one fish's nodes
    assert np.array_equal(np.add.reduceat(owner[rows], starts), sizes[prey] * prey)


def test_one_prey_fish_gives_its_rows_from_zero() -> None:
    offsets = np.array([0, 4, 9])
    rows, starts = prey_rows(offsets, np.array([1]))
    assert rows.tolist() == [4, 5, 6, 7, 8]
    assert starts.tolist() == [0]
