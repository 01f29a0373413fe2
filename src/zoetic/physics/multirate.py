"""Which springs are too stiff for the step, and how many substeps they need (multirate Euler).

A spring-mass lattice stepped by explicit (symplectic) Euler is stable while its highest
natural frequency times the step stays below 2. Strong muscles and a stiff caudal fin raise
that frequency, but only locally: the light nodes of a fin with stiff springs ring fast while
the heavy trunk does not. Shrinking the step for everything would slow the whole simulator;
instead every other force (the slow springs, gravity, water, fins, the floor) is computed
once per step and kicks the velocities, and then the springs that touch those fast nodes
drive ``substeps`` smaller steps of the nodes they touch (the impulse multirate method,
r-RESPA: Tuckerman, Berne and Martyna 1992). The order matters: holding the slow forces over
the sub-steps instead puts 3/4 h^2 rather than h^2 of their acceleration into the positions
(two sub-steps), which makes the step map's determinant 1 + omega^2 h^2 / 4 > 1: it blew up
the shark at rest. The fast set is small (9 of 91 springs, 6 of 23 nodes for the shark), so
a step costs little more than before. Bodies whose whole lattice is stable at the step get
no split at all and are stepped exactly as before.

The split depends only on the body and the step, and every backend (Numba kernel, NumPy
reference, JAX mirror) uses this function, so they step the same scheme.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import NamedTuple

import numpy as np

from zoetic.bodies import Body

# the largest omega * dt an explicit step is given (2 is the limit of stability; the margin
# covers the geometric stiffness of stretched springs and the damping)
STABLE_OMEGA_DT = 1.7


def omega_max(body: Body, springs: np.ndarray | None = None) -> float:
    """Return the highest natural frequency (rad/s) of ``springs`` (default all) at rest."""
    idx = np.arange(body.n_springs) if springs is None else np.asarray(springs)
    if idx.size == 0:
        return 0.0
    x = body.rest_pos
    n = body.n_nodes
    a, b = body.spring_a[idx], body.spring_b[idx]
    d = x[b] - x[a]
    u = d / np.linalg.norm(d, axis=1, keepdims=True)
    blocks = body.stiffness[idx, None, None] * u[:, :, None] * u[:, None, :]
    K = np.zeros((n, 3, n, 3))
    np.add.at(K, (a, slice(None), a, slice(None)), blocks)
    np.add.at(K, (b, slice(None), b, slice(None)), blocks)
    np.add.at(K, (a, slice(None), b, slice(None)), -blocks)
    np.add.at(K, (b, slice(None), a, slice(None)), -blocks)
    s = 1.0 / np.sqrt(np.repeat(body.mass, 3))
    w2 = np.linalg.eigvalsh(K.reshape(3 * n, 3 * n) * s[:, None] * s[None, :])
    return float(math.sqrt(max(float(w2.max()), 0.0)))


class Split(NamedTuple):
    """How a body is stepped at one dt: index arrays and the fast springs' sub-step count."""

    slow_springs: np.ndarray
    fast_springs: np.ndarray
    substeps: int
    slow_nodes: np.ndarray  # touched by no fast spring: stepped once per step, as before
    fast_nodes: np.ndarray  # touched by a fast spring: one kick, then the sub-steps


@lru_cache(maxsize=64)
def split(body: Body, dt: float) -> Split:
    """Return the Split of ``body``'s springs and nodes at step ``dt``.

    No split (all slow, 1 substep) when the whole lattice is stable at ``dt``. Otherwise the
    fast nodes are those with the highest sqrt(sum of their springs' stiffness / mass), taken
    from the top until the springs touching none of them are stable at ``dt``; the fast
    springs are the rest, substepped so that the whole lattice is stable at ``dt / substeps``.
    """
    every = np.arange(body.n_springs)
    nodes = np.arange(body.n_nodes)
    w_all = omega_max(body)
    if w_all * dt <= STABLE_OMEGA_DT:
        return _frozen(Split(every, every[:0], 1, nodes, nodes[:0]))
    k_node = np.zeros(body.n_nodes)
    np.add.at(k_node, body.spring_a, body.stiffness)
    np.add.at(k_node, body.spring_b, body.stiffness)
    w_node = np.sqrt(k_node / body.mass)
    # thresholds from the top, nodes of (nearly) equal frequency together so that a mirror-
    # symmetric body gets a mirror-symmetric split
    levels = np.unique(np.round(w_node, 3))[::-1]
    slow = every
    for level in levels:
        fast_node = np.round(w_node, 3) >= level
        slow = every[~(fast_node[body.spring_a] | fast_node[body.spring_b])]
        if omega_max(body, slow) * dt <= STABLE_OMEGA_DT:
            break
    fast = np.setdiff1d(every, slow)
    substeps = max(1, math.ceil(w_all * dt / STABLE_OMEGA_DT))
    touched = np.zeros(body.n_nodes, dtype=bool)
    touched[body.spring_a[fast]] = True
    touched[body.spring_b[fast]] = True
    return _frozen(Split(slow, fast, substeps, nodes[~touched], nodes[touched]))


def _frozen(s: Split) -> Split:
    arrays = [np.ascontiguousarray(a, dtype=np.int64) for a in (s[0], s[1], s[3], s[4])]
    for a in arrays:
        a.setflags(write=False)
    return Split(arrays[0], arrays[1], s.substeps, arrays[2], arrays[3])
