"""The tank's fishes as bodies: where they are and how they lie, measured from the world.

``FishBodies`` reads the world's node positions (once a step) and keeps every fish's centre,
heading, velocity and nose current at each control period's end; it measures each fish's roll
and bend for the motor layer's righting reflex and fold guard, and, as an observer of the
closed loop (``control.loop``), how deep any fish has gone into a rock or another fish.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import numpy as np

from zoetic.behavior.aquarium.locomotion import bend_nodes
from zoetic.behavior.aquarium.perception import deepest_inside
from zoetic.bodies import Body
from zoetic.control.loop import Observer
from zoetic.control.policy import Period
from zoetic.physics.bodycontact import deepest as deepest_into
from zoetic.physics.world import World
from zoetic.tasks.terms import BodyFrame, roll_angle

T = TypeVar("T")


def heading_weights(body: Body) -> np.ndarray:
    """Return c (N,) with sum_n c_n x_n = the best linear fit's image of the rest heading
    (``control.sensors.linear_fit`` applied to ``body.forward``, in one dot product)."""
    w = body.mass / body.total_mass
    r0 = body.rest_pos - w @ body.rest_pos
    m_inv = np.linalg.pinv(np.einsum("n,ni,nj->ij", w, r0, r0))
    return w * (r0 @ (m_inv @ body.forward))


def kinematics(
    world: World,
    weights: list[np.ndarray],
    cw: list[np.ndarray],
    heads: list[int],
    allpos: np.ndarray | None = None,
):
    """Return each fish's node positions, and (n, 3) centres, unit headings, centre velocities
    and noses; weights: each fish's node masses over its total; ``allpos``:
    ``world.node_positions()`` when already taken this step. The fishes of one node count
    are measured together (stacked matrix products: the same numbers as one fish at a
    time)."""
    allpos = world.node_positions(0) if allpos is None else allpos
    allvel = world.node_velocities(0)
    off = world.offsets
    n = len(weights)
    com, fwd, cv = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    sizes = off[1:] - off[:-1]
    for size in np.unique(sizes).tolist():
        idx = np.flatnonzero(sizes == size)
        rows = off[idx][:, None] + np.arange(size)  # (k, N) the group's rows
        p, v = allpos[rows], allvel[rows]  # (k, N, 3)
        w = np.stack([weights[a] for a in idx.tolist()])[:, None, :]  # (k, 1, N)
        c = np.stack([cw[a] for a in idx.tolist()])[:, None, :]
        com[idx], cv[idx] = np.matmul(w, p)[:, 0], np.matmul(w, v)[:, 0]
        fr = np.matmul(c, p)[:, 0]
        # np.linalg.norm's formula, fish by fish: sqrt(x x + y y + z z)
        fwd[idx] = fr / (np.sqrt((fr * fr).sum(axis=1)) + 1e-12)[:, None]
    pos = [allpos[o0:o1] for o0, o1 in zip(off[:-1].tolist(), off[1:].tolist(), strict=True)]
    nose = allpos[off[:-1] + np.asarray(heads, int)]
    return pos, com, fwd, cv, nose


def per_body(of: Callable[[Body], T], bodies: list[Body]) -> list[T]:
    """Return ``of(body)`` for each body, worked out once for each body object (a tank's
    fishes of one species share one compiled body: a crowd's thousand fishes ask twice)."""
    done: dict[int, T] = {}
    for body in bodies:
        if id(body) not in done:
            done[id(body)] = of(body)
    return [done[id(body)] for body in bodies]


def roll_pairs(bodies: list[Body], offsets: np.ndarray) -> list[tuple[np.ndarray, ...]]:
    """Return the fishes' mirror node pairs (``BodyFrame.left``, ``.right``) as indices into
    the world's node array (``offsets``: each fish's first node), grouped by pair count: a
    list of (fishes (k,), left (k, P), right (k, P)); fishes without pairs are left out."""
    groups: dict[int, list[tuple[int, np.ndarray, np.ndarray]]] = {}
    for a, frame in enumerate(per_body(BodyFrame.of, bodies)):
        if len(frame.left):
            o = int(offsets[a])
            groups.setdefault(len(frame.left), []).append((a, o + frame.left, o + frame.right))
    return [
        (
            np.array([g[0] for g in grp]),
            np.stack([g[1] for g in grp]),
            np.stack([g[2] for g in grp]),
        )
        for grp in groups.values()
    ]


def fish_rolls(
    allpos: np.ndarray, fwd: np.ndarray, pairs: list[tuple[np.ndarray, ...]]
) -> np.ndarray:
    """Return each fish's roll (n,), rad over +-pi (``tasks.terms.roll_angle`` against its
    heading ``fwd`` (n, 3)), from the world's node positions ``allpos``; pairs: ``roll_pairs``
    (one array expression a group of fishes with as many pairs; 0 for a fish without)."""
    out = np.zeros(len(fwd))
    for idx, left, right in pairs:
        out[idx] = roll_angle(np, allpos, left, right, fwd[idx])
    return out


def bend_indices(
    bodies: list[Body], offsets: np.ndarray
) -> tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Return what ``fish_bends`` needs: each fish's nose and tail node as indices into the
    world's node array (``offsets``: each fish's first node) and rest distance, for the fishes
    that ``locomotion.bend_nodes`` measures (after how many fishes)."""
    rows = [
        (a, int(offsets[a]) + nodes[0], int(offsets[a]) + nodes[1], nodes[2])
        for a, b in enumerate(bodies)
        if (nodes := bend_nodes(b)) is not None
    ]
    idx, nose, tail, rest = (
        np.array([r[k] for r in rows], dtype=float if k == 3 else int) for k in range(4)
    )
    return len(bodies), idx, nose, tail, rest


def fish_bends(
    allpos: np.ndarray, bends: tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]
) -> np.ndarray:
    """Return each fish's bend (n,) (``locomotion.bend``: nose to tail over rest, 1 for a fish
    without a tail node) from the world's node positions ``allpos``; bends: ``bend_indices``."""
    n, idx, nose, tail, rest = bends
    out = np.ones(n)
    if len(idx):
        out[idx] = np.linalg.norm(allpos[nose] - allpos[tail], axis=1) / rest
    return out


def near_pairs(com: np.ndarray, extent: np.ndarray) -> np.ndarray:
    """Return the pairs (P, 2) i < j, in order, of the points ``com`` (n, 3) nearer than
    ``extent[i] + extent[j]`` (n,) m (a k-d tree's neighbours, not every pair of a crowd)."""
    from scipy.spatial import cKDTree

    if len(com) < 2:
        return np.zeros((0, 2), int)
    pairs = cKDTree(com).query_pairs(2.0 * float(np.max(extent)), output_type="ndarray")
    i, j = pairs[:, 0], pairs[:, 1]
    pairs = pairs[np.linalg.norm(com[i] - com[j], axis=1) < extent[i] + extent[j]]
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


def fish_depth(
    bodies: list[Body],
    pos: list[np.ndarray],
    extent: np.ndarray,
    masses: list[tuple[np.ndarray, float]] | None = None,
) -> float:
    """Return how deep (m) the deepest node of any fish lies inside another fish's closed
    surface (``physics.bodycontact.deepest``), over the pairs whose bounding spheres meet;
    masses: each fish's node masses and total (default from the bodies)."""
    if masses is None:
        masses = [(b.mass, b.total_mass) for b in bodies]
    com = np.array([m @ p / total for (m, total), p in zip(masses, pos, strict=True)])
    out = 0.0
    for i, j in near_pairs(com, extent).tolist():
        out = max(
            out,
            deepest_into(pos[i], pos[j], bodies[j].faces),
            deepest_into(pos[j], pos[i], bodies[i].faces),
        )
    return out


def rest_reach(body: Body) -> float:
    """Return how far (m) the body's nodes reach from its centre of mass at rest."""
    r0 = body.rest_pos - body.mass @ body.rest_pos / body.total_mass
    return float(np.linalg.norm(r0, axis=1).max())


class FishBodies(Observer):
    """Every fish's body state: node positions (``nodes``, read once a step), per fish node
    positions ``pos``, and (n, 3) centres ``com``, unit headings ``fwd``, centre velocities
    ``vel`` and noses ``nose``, current at the last control period's end; and the deepest
    (m) any node went into an obstacle (``deepest``) or inside another fish
    (``deepest_fish``), measured at each period's end.

    statics: the tank's obstacles as ``pack_statics`` returns them (kind, center, size).
    """

    def __init__(self, world: World, bodies: list[Body], statics: tuple[np.ndarray, ...]) -> None:
        self.bodies, self.statics = bodies, statics
        off = world.offsets
        self.offsets = off.tolist()
        self.masses = [(b.mass, b.total_mass) for b in bodies]
        self.weights = [m / total for m, total in self.masses]
        self.headings = per_body(heading_weights, bodies)
        self.heads = [b.head for b in bodies]
        self.pairs = roll_pairs(bodies, off)
        self.bends = bend_indices(bodies, off)
        # the bounding spheres of fish_depth
        self.extent = 1.25 * np.array(per_body(rest_reach, bodies))
        self.deepest = 0.0
        self.deepest_fish = 0.0
        self.last_roll: tuple[np.ndarray, float] | None = None  # rolls at the last reading
        self._read: tuple[int, np.ndarray] = (-1, np.empty((0, 3)))
        self._update(world)

    def nodes(self, world: World) -> np.ndarray:
        """Return the world's node positions (all fishes, (N, 3)), read once a step."""
        if self._read[0] != world.step_count:
            self._read = (world.step_count, world.node_positions(0))
        return self._read[1]

    def split(self, allpos: np.ndarray) -> list[np.ndarray]:
        """Return each fish's node positions from the world's node array."""
        off = self.offsets
        return [allpos[o0:o1] for o0, o1 in zip(off[:-1], off[1:], strict=True)]

    def _update(self, world: World) -> None:
        self.pos, self.com, self.fwd, self.vel, self.nose = kinematics(
            world, self.weights, self.headings, self.heads, self.nodes(world)
        )

    def posture(self, world: World, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return each fish's roll (n,) rad, roll rate (n,) rad/s since the last reading (0 at
        the first) and bend (n,) at time ``t`` s (now), for the motor layer."""
        allpos = self.nodes(world)
        roll = fish_rolls(allpos, self.fwd, self.pairs)
        if self.last_roll is None:
            rate = np.zeros(len(roll))
        else:
            rate = np.angle(np.exp(1j * (roll - self.last_roll[0]))) / (t - self.last_roll[1])
        self.last_roll = (roll, t)
        return roll, rate, fish_bends(allpos, self.bends)

    def period(self, world: World, period: Period) -> None:
        """Measure how deep the fishes lie in the rocks and in each other, then read their
        centres, headings, velocities and noses for the next period."""
        allpos = self.nodes(world)
        kind, center, size = self.statics
        self.deepest = max(self.deepest, deepest_inside(allpos, kind, center, size))
        into_fish = fish_depth(self.bodies, self.split(allpos), self.extent, self.masses)
        self.deepest_fish = max(self.deepest_fish, into_fish)
        self._update(world)
