"""The food test of a crowd (``physics.food.eaten_on_path``) tests only the heads that could
reach a particle, and marks what testing every head would."""

from __future__ import annotations

import math

import numpy as np

from zoetic.physics.food import eaten_on_path


def _every_head(h0, h1, f0, f1, radius) -> np.ndarray:
    """Every head against every particle: the closest point of its relative path."""
    eaten = np.zeros(f0.shape[:2], bool)
    for b in range(f0.shape[0]):
        for q in range(f0.shape[1]):
            for a in range(h0.shape[0]):
                p0, p1 = h0[a, b] - f0[b, q], h1[a, b] - f1[b, q]
                d = p1 - p0
                s = min(max(-(p0 @ d) / (d @ d + 1e-12), 0.0), 1.0)
                closest = float(np.linalg.norm(p0 + s * d))
                eaten[b, q] |= math.isfinite(closest) and closest < radius[q]
    return eaten


def test_the_heads_tested_mark_what_every_head_would():
    rng = np.random.default_rng(7)
    heads, food, lanes = 300, 200, 2
    h0 = rng.uniform(-6, 6, (heads, lanes, 3)) * np.array([1.0, 0.05, 1.0])  # a layer
    h1 = h0 + rng.normal(0, 0.4, h0.shape)  # a slice's swim
    h1[5, 0] = np.nan  # a blown-up animal eats nothing
    f0 = rng.uniform(-6, 6, (lanes, food, 3)) * np.array([1.0, 0.05, 1.0])
    f1 = f0 + np.array([0.002, 0.0, 0.0])
    # particles right on some paths, just within and just beyond the radius (these heads
    # held still, the second twenty above the others' layer)
    h0[20:40, 0, 1] += np.arange(20) + 10.0
    f0[0, :20] = h0[:20, 0] + np.array([0.0, 0.0, 0.249])
    f0[0, 20:40] = h0[20:40, 0] + np.array([0.0, 0.0, 0.251])
    f1[0, :40] = f0[0, :40]
    h1[:40, 0] = h0[:40, 0]
    radius = np.full(food, 0.25)
    expected = _every_head(h0, h1, f0, f1, radius)
    eaten = np.zeros((lanes, food), bool)
    eaten_on_path(h0, h1, f0, f1, radius, eaten)
    assert expected[0, :20].all() and not expected[0, 20:40].any()
    assert 40 < expected.sum() < food * lanes  # some eaten by the random paths, not all
    assert np.array_equal(eaten, expected)
