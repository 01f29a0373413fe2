"""Animals of one model stepped as the lanes of one kernel call.

The kernel steps the lanes of an array (nodes, 3, lanes) together, SIMD across the lanes; a
World keeps each animal's nodes as its own rows. The animals of a world that share a model
(the same body in the same medium at the same step: a tank's fishes) form a ``LaneGroup``:
the animals a slice steps are gathered, lane by lane, into the group's buffers, stepped in
one kernel call and scattered back. A lane is stepped exactly as it would be alone (the
kernel's arithmetic of a lane never reads another lane), so grouping changes only the speed.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from zoetic.jitcache import fresh_numba_cache
from zoetic.physics.kernel import make_stepper
from zoetic.physics.kernel_terms import SPLIT_LANES
from zoetic.physics.model import Model
from zoetic.physics.simulate import VMAX, chunk_size

fresh_numba_cache()

F32 = np.float32
KEEP = 64  # sets of animals whose lanes a group keeps
PAD = 8  # lanes: a group's buffers come in multiples of this (the SIMD width of AVX2 float32)
# a group's buffers hold at least this many lanes (so ``chunk_size`` makes chunks of at least
# as many): a chunk of fewer takes the kernel's path for one animal, whose step costs more for
# 8 lanes than the split path's for 32 (the few fishes near one another, stepped one step at a
# time); the padding lanes repeat the first
MIN_LANES = SPLIT_LANES


@njit(cache=True)
def gather(pos, vel, fs, failed, table, t0, t1, rows, lane, animal, column, g):
    """Copy the lanes' state and activation rows t0 .. t1 into the group buffers ``g`` (pos,
    vel (N, 3, m), fs, failed (m,), table (T, A, m)): lane j is batch lane ``lane[j]`` of the
    animal ``animal[j]`` whose nodes are the world's rows from ``rows[j]`` (pos, vel (N_all,
    3, B); fs, failed (animals, B)), its activations column ``column[j]`` of ``table``. Lanes
    past the given ones (padding) repeat the first."""
    gpos, gvel, gfs, gfailed, gtable = g
    k = rows.shape[0]
    for j in range(gpos.shape[2]):
        q = j if j < k else 0
        r0, b, a, c = rows[q], lane[q], animal[q], column[q]
        for i in range(gpos.shape[0]):
            for d in range(3):
                gpos[i, d, j] = pos[r0 + i, d, b]
                gvel[i, d, j] = vel[r0 + i, d, b]
        gfs[j] = fs[a, b] if j < k else -1
        gfailed[j] = failed[a, b] if j < k else -1
        for t in range(t0, t1):
            for u in range(gtable.shape[1]):
                gtable[t, u, j] = table[t, u, c]


@njit(cache=True)
def scatter(pos, vel, fs, failed, rows, lane, animal, g):
    """Copy the given lanes' state back from the group buffers (``gather``'s inverse)."""
    gpos, gvel, gfs, gfailed, _ = g
    for j in range(rows.shape[0]):
        r0, b, a = rows[j], lane[j], animal[j]
        for i in range(gpos.shape[0]):
            for d in range(3):
                pos[r0 + i, d, b] = gpos[i, d, j]
                vel[r0 + i, d, b] = gvel[i, d, j]
        fs[a, b] = gfs[j]
        failed[a, b] = gfailed[j]


class LaneGroup:
    """The animals ``members`` (world indices) of one ``model``, each with ``batch`` lanes, as
    lanes of one kernel call: ``run`` steps any of them together.

    pos, vel: the world's (N_all, 3, B) state; fs, failed: its (animals, B) failure marks;
    first: each animal's first row; n_act: the model's actuators."""

    def __init__(self, members: list[int], model: Model, world_arrays, first, n_act: int):
        self.members = members
        self.model = model
        self.pos, self.vel, self.fs, self.failed, self.batch = world_arrays
        self.first = np.asarray(first, np.int64)
        self.n_act = max(1, n_act)
        self.n_nodes = model.mass.shape[0]
        self.column = {a: k for k, a in enumerate(members)}  # member -> its block of columns
        self._buffers: dict[int, tuple] = {}  # padded lane count -> (stepper, arrays)
        self._tables: dict[tuple[int, int], np.ndarray] = {}  # (padded lanes, steps) -> table
        self._lanes: dict[tuple[int, ...], tuple[np.ndarray, ...]] = {}  # animals -> lanes

    def _buffer(self, m: int, steps: int):
        """Return the stepper and buffers (pos, vel, fs, failed, table) for m lanes."""
        got = self._buffers.get(m)
        if got is None:
            pos = np.zeros((self.n_nodes, 3, m), F32)
            vel = np.zeros_like(pos)
            fs, failed = -np.ones(m, np.int64), -np.ones(m, np.int64)
            stepper = make_stepper(self.model, pos, vel, fs, failed, chunk_size(m), VMAX)
            got = self._buffers[m] = (stepper, (pos, vel, fs, failed))
        table = self._tables.get((m, steps))
        if table is None:
            table = self._tables[(m, steps)] = np.zeros((steps, self.n_act, m), F32)
        return got[0], (*got[1], table)

    def lanes(self, animals: list[int]) -> tuple[np.ndarray, ...]:
        """Return the rows, batch lanes, animals and table columns of the animals' lanes
        (kept for the latest sets of animals asked for: a slice asks for the same ones again)."""
        key = tuple(animals)
        got = self._lanes.get(key)
        if got is None:
            if len(self._lanes) >= KEEP:
                self._lanes.clear()
            got = self._lanes[key] = self._new_lanes(animals)
        return got

    def _new_lanes(self, animals: list[int]) -> tuple[np.ndarray, ...]:
        a = np.repeat(np.asarray(animals, np.int64), self.batch)
        lane = np.tile(np.arange(self.batch, dtype=np.int64), len(animals))
        col = np.array([self.column[x] for x in animals], np.int64)
        column = np.repeat(col * self.batch, self.batch) + lane
        return self.first[a], lane, a, column

    def run(self, kernels, animals: list[int], table, t0: int, t1: int, base: int) -> None:
        """Step the animals' lanes (members of this group) through rows t0 .. t1 of the
        group's ``table`` (T, A, members x B) in one kernel call (``kernels``: serial and
        threaded entries and the lane-steps from which the threads are worth it)."""
        rows, lane, animal, column = self.lanes(animals)
        k = len(rows)
        m = max(-(-k // PAD) * PAD, MIN_LANES)
        stepper, g = self._buffer(m, table.shape[0])
        gather(
            self.pos, self.vel, self.fs, self.failed, table, t0, t1, rows, lane, animal, column, g
        )
        serial, parallel, threads_from = kernels
        kernel = parallel if m * (t1 - t0) >= threads_from else serial
        kernel(stepper, g[4], t0, t1, base)
        scatter(self.pos, self.vel, self.fs, self.failed, rows, lane, animal, g)


def fingerprint(model: Model) -> tuple:
    """Return a key equal for models that step the same (every field's value)."""
    return tuple(
        (x.dtype.str, x.shape, x.tobytes()) if isinstance(x, np.ndarray) else x for x in model
    )
