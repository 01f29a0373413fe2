"""Lanes in the same state share one result, to the bit.

In a batch of lanes, a passive object often starts each step alike in many lanes (a ball
resting on its post until an animal strikes it). A compiled loop over the lanes keeps, per
object, the distinct input states it has met this step and their results (``remember``), and
a lane whose inputs match a kept row to the bit takes that row's result (``recalled``): the
same arithmetic on the same inputs, so the same bits as solving it again.
"""

from __future__ import annotations

import math

from numba import njit

from zoetic.jitcache import fresh_numba_cache

fresh_numba_cache()

MEMO_ROWS = 8  # distinct states kept for one object in one step (``remember``)


@njit(cache=True, inline="always")
def same_bits(a, b):
    """Return True if the floats a and b are the same to the bit (never for a NaN)."""
    return a == b and (a != 0.0 or math.copysign(1.0, a) == math.copysign(1.0, b))


@njit(cache=True, inline="always")
def recalled(memo, k, seen, values):
    """Return the row of ``memo[k]``'s first ``seen[k]`` rows that begins with ``values``, each
    the same to the bit, or -1: the lane that wrote that row had a ball in the same state, and
    its result (the rest of the row) holds for this lane too."""
    for q in range(seen[k]):
        hit = True
        for j in range(len(values)):
            if not same_bits(memo[k, q, j], values[j]):
                hit = False
                break
        if hit:
            return q
    return -1


@njit(cache=True, inline="always")
def remember(memo, k, seen, values):
    """Append ``values`` as a new row of ``memo[k]`` (``recalled``) and return the row, or -1
    if it holds MEMO_ROWS rows already (a batch whose balls went many ways is solved lane by
    lane, not searched through)."""
    q = seen[k]
    if q >= min(MEMO_ROWS, memo.shape[1]):
        return -1
    seen[k] += 1
    for j in range(len(values)):
        memo[k, q, j] = values[j]
    return q
