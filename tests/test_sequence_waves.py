"""A sequence of abstract controllers played from its items' mode waves (``blend.add_item``):
the blend the weights define, whichever waves a caller keeps."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.control import ConstantController
from zoetic.control.abstract import AbstractController, SequenceController

ACTUATORS = ("a", "b", "c")


def _controller(rng: np.random.Generator, modes: int) -> AbstractController:
    a = len(ACTUATORS)
    return AbstractController(
        "fish",
        ACTUATORS,
        rng.uniform(0.2, 0.8, a),
        rng.choice([1.5, 3.0, 4.0], (a, modes)),
        rng.uniform(0.0, 0.4, (a, modes)),
        rng.uniform(-np.pi, np.pi, (a, modes)),
    )


def _blend(seq: SequenceController, t: np.ndarray) -> np.ndarray:
    """Each item's cosines at its own clock, weighted by the sequence's weights."""
    w = seq.weights(t)
    out = np.zeros((t.size, len(ACTUATORS)))
    for i, ((c, _), s) in enumerate(zip(seq.items, seq.starts(), strict=True)):
        out += w[:, i : i + 1] * c.raw(t - s)
    return out


@pytest.fixture
def plans():
    rng = np.random.default_rng(7)
    ctrls = [_controller(rng, k) for k in (2, 2, 1, 0)]
    return [
        SequenceController(
            "fish",
            ACTUATORS,
            tuple(
                (ctrls[i], float(d))
                for i, d in zip(rng.integers(0, 4, 4), rng.uniform(0.3, 2, 4), strict=True)
            ),
        )
        for _ in range(6)
    ]


def test_a_sequence_plays_the_weighted_blend_of_its_items(plans):
    t = np.arange(0.0, 6.0, 0.0025)
    for seq in plans:
        np.testing.assert_allclose(seq.raw(t), _blend(seq, t), rtol=0, atol=1e-12)


def test_kept_waves_give_the_same_tables_to_the_bit(plans):
    kept: dict = {}
    for seq in plans:
        alone = seq.table(2400, 0.0025)
        assert np.array_equal(seq.table(2400, 0.0025, waves=kept), alone)
        # waves kept at other times are not used for these
        assert np.array_equal(seq.table(1000, 0.0025, waves=kept), seq.table(1000, 0.0025))
        # nor at as many times starting later, or a step apart
        assert np.array_equal(seq.table(2400, 0.0025, 0.3, kept), seq.table(2400, 0.0025, 0.3))
        assert np.array_equal(seq.table(2400, 0.003, waves=kept), seq.table(2400, 0.003))
    assert np.array_equal(
        plans[0].table(2400, 0.0025, waves=kept), plans[0].sample(np.arange(2400) * 0.0025)
    )


def test_other_controllers_blend_with_abstract_ones():
    rng = np.random.default_rng(3)
    rest = ConstantController("fish", ACTUATORS, (0.1, 0.9, 0.5))
    seq = SequenceController("fish", ACTUATORS, ((_controller(rng, 2), 1.0), (rest, 1.0)))
    t = np.linspace(-0.5, 3.0, 701)
    np.testing.assert_allclose(seq.raw(t), _blend(seq, t), rtol=0, atol=1e-12)
    assert np.allclose(seq.raw(t[t > 2.0]), (0.1, 0.9, 0.5))
