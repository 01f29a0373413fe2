"""The lateral line: a fish senses another whose head is about to strike its flank.

Tu's collision sensitivity region (``routines.fish_threats``) lies ahead of the nose, so a
fish that is slow, courting or turning on the spot never senses a neighbour swimming into its
side or tail, and stays in that one's way. Real fishes feel the water pushed by a fish
closing on them along the body (the lateral line). A fish with no threat ahead that another
live fish (not a predator of it: those it flees) will strike, the other's head coming within
``CONTACT`` m of its centre line within ``FLANK_HORIZON`` s, both swimming on as they swim
now, avoids that fish: it turns away from where the other will be nearest and swims on at
speed, out of its way (no brake: braking leaves it in the striker's path).
"""

from __future__ import annotations

import numpy as np

from zoetic.behavior.aquarium.routines import (
    CENTRE_LINE,
    CONTACT,
    HEAD,
    closest_lateral,
    time_to_contact,
)

FLANK_HORIZON = 1.0  # s: how soon a strike into the flank is felt


def flank_threats(
    nose: np.ndarray,
    com: np.ndarray,
    forward: np.ndarray,
    velocity: np.ndarray,
    sensed: np.ndarray,
    threat: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Return for each of n fishes without a threat ahead (``threat`` (n,) -1) the fish whose
    head will strike it soonest (index, -1: none) and the side to turn to (+1 left, -1 right;
    0: none), away from where the striker's centre will be nearest (``closest_lateral``).

    sensed (n, n): the fishes each one can feel (live, not its hunters); nose, com, forward,
    velocity: (n, 3), forward unit headings."""
    n = len(nose)
    strike, side = np.full(n, -1), np.zeros(n, int)
    sensed = sensed & (threat < 0)[:, None]
    np.fill_diagonal(sensed, False)
    ii, jj = np.nonzero(sensed)
    if not len(ii):
        return strike, side
    # a cheap bound first: the two bodies' centres farther apart than both half lengths, the
    # contact distance and the way they close in the horizon cannot touch in it
    half = np.sqrt(((nose - com)[:, [0, 2]] ** 2).sum(axis=1))
    gap = (com[jj] - com[ii])[:, [0, 2]]
    rel_v = velocity[ii] - velocity[jj]  # i's velocity seen by the striker j
    far = np.sqrt((gap**2).sum(axis=1)) - half[ii] - half[jj] - CONTACT
    far -= FLANK_HORIZON * np.sqrt((rel_v[:, [0, 2]] ** 2).sum(axis=1))
    keep = far <= 0.0
    ii, jj, rel_v = ii[keep], jj[keep], rel_v[keep]
    if not len(ii):
        return strike, side
    u = np.linspace(0.0, 1.0, CENTRE_LINE)[:, None, None]  # nose (0) to tail (1)
    line = nose[ii][None] + u * 2.0 * (com[ii] - nose[ii])[None]  # (P, m, 3): the struck
    horizon = np.full(len(ii), FLANK_HORIZON)
    # when the striker's head (its front HEAD) comes within CONTACT of the fish's centre line
    when = time_to_contact(nose[jj], forward[jj], com[jj], line, rel_v, horizon, HEAD)
    hit = np.flatnonzero(np.isfinite(when))
    if not len(hit):
        return strike, side
    order = hit[np.lexsort((when[hit], ii[hit]))]  # each fish's soonest strike first
    first = order[np.r_[True, ii[order][1:] != ii[order][:-1]]]
    me, other = ii[first], jj[first]
    f = forward[me]
    left = np.stack([-f[:, 2], np.zeros(len(me)), f[:, 0]], axis=1)
    lateral = closest_lateral(com[other] - com[me], -rel_v[first], left, horizon[first])
    strike[me] = other
    side[me] = np.where(lateral > 0.0, -1, 1)  # away from the striker's nearest approach
    return strike, side
