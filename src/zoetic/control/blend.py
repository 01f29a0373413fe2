"""A sequence item's share of a blended activation table, compiled: one abstract controller
(offset plus cosine modes) started at a time s, played from its modes' waves at the table's
times (cos and sin of 2 pi f t, ``AbstractController.waves``) by the angle-sum rule
    amp cos(2 pi f (t - s) + phase) = amp cos(phase - 2 pi f s) cos(2 pi f t)
                                      - amp sin(phase - 2 pi f s) sin(2 pi f t),
and cross-faded: weighted by its linear fade in (over the overlap with the item before) and
fade out (over the overlap with the item after). A plan search plays many sequences of the
same few controllers at the same times, so the waves are computed once and only these sums
run per plan (``control.abstract.SequenceController.raw``)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from zoetic.jitcache import fresh_numba_cache

fresh_numba_cache()


@njit(cache=True)
def _fade(t, s, width):
    """Return the linear ramp from 0 at s to 1 at s + width (s), clipped to [0, 1]."""
    return min(max((t - s) / width, 0.0), 1.0)


@njit(cache=True)
def add_item(out, t, waves, offset, freq, amp, phase, start, fade_in, fade_out):
    """Add to ``out`` (T, A) an item's weighted activations at times ``t`` (T,) s: the
    controller (``offset`` (A,), ``freq`` Hz, ``amp``, ``phase`` rad (A, K)) started at
    ``start`` s, from ``waves`` (2, K, T, A) of cos and sin of 2 pi f t. ``fade_in``: (start
    of the overlap with the item before, its width s), width <= 0 for none (the first item
    holds before its start); ``fade_out``: (end of this item, the overlap's width s), width
    <= 0 for none (the last item holds after its end). Rows of weight 0 are left alone."""
    n_a, n_k = freq.shape
    cos_part = np.empty((n_a, n_k))
    sin_part = np.empty((n_a, n_k))
    for a in range(n_a):
        for k in range(n_k):
            lag = phase[a, k] - 2.0 * math.pi * freq[a, k] * start
            cos_part[a, k] = amp[a, k] * math.cos(lag)
            sin_part[a, k] = amp[a, k] * math.sin(lag)
    for r in range(t.shape[0]):
        w = 1.0
        if fade_in[1] > 0.0:
            w *= _fade(t[r], fade_in[0], fade_in[1])
        if fade_out[1] > 0.0:
            w *= _fade(-t[r], -fade_out[0], fade_out[1])
        if w > 0.0:
            for a in range(n_a):
                v = offset[a]
                for k in range(n_k):
                    v += waves[0, k, r, a] * cos_part[a, k] - waves[1, k, r, a] * sin_part[a, k]
                out[r, a] += w * v
