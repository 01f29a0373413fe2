"""simulate(body, activations, medium, dt, state) -> Trajectory, for one candidate or many."""

from __future__ import annotations

import os
import weakref
from dataclasses import dataclass

import numpy as np

from zoetic.bodies import Body
from zoetic.errors import SimulationError
from zoetic.physics.media import Medium, get_medium

VMAX = 200.0  # m/s: any node faster than this marks its candidate as blown up


@dataclass(frozen=True)
class State:
    """Positions and velocities of a batch of candidates: arrays (B, N, 3) in m and m/s."""

    positions: np.ndarray
    velocities: np.ndarray

    @property
    def batch(self) -> int:
        return int(self.positions.shape[0])

    def take(self, index) -> State:
        """Return the candidates at ``index`` (an int keeps a batch axis of one)."""
        idx = np.atleast_1d(np.asarray(index))
        return State(self.positions[idx], self.velocities[idx])


@dataclass(frozen=True)
class Trajectory:
    """What a simulation produced: recorded positions, the final state and who blew up."""

    times: np.ndarray  # (R,) s
    positions: np.ndarray  # (B, R, N, 3) m; NaN after a candidate failed
    final: State
    failed_step: np.ndarray  # (B,) int: step at which it blew up, -1 if it did not
    dt: float

    @property
    def failed(self) -> np.ndarray:
        """Return a (B,) bool array: True where the candidate blew up."""
        return self.failed_step >= 0

    def com(self, body: Body) -> np.ndarray:
        """Return the centre of mass over time, (B, R, 3)."""
        w = body.mass / body.total_mass
        return np.einsum("brnk,n->brk", self.positions, w)


def rest_state(
    body: Body,
    batch: int = 1,
    offset=None,
    velocity=(0.0, 0.0, 0.0),
) -> State:
    """Return ``batch`` copies of the rest pose, shifted by ``offset``, moving at ``velocity``.

    The default offset is the body's own start offset (a dolphin starts under water).
    """
    off = body.start_offset if offset is None else np.asarray(offset, float)
    pos = np.broadcast_to(body.rest_pos + off, (batch, body.n_nodes, 3))
    vel = np.broadcast_to(np.asarray(velocity, float), (batch, body.n_nodes, 3))
    return State(pos.copy(), vel.copy())


MAX_SUBSTEPS = 4  # the most sub-steps of stiff springs a body's own step may ask for
DENSE_NODES = 150  # up to this many nodes the eigenproblems are solved densely, beyond sparsely


def _lattice_matrix(body: Body, weights: np.ndarray, floor: np.ndarray):
    """Return M^-1/2 W M^-1/2 (3N, 3N, sparse) for spring weights (stiffness or damping).

    W is the lattice's stiffness (or damping) matrix linearised at the rest pose: each spring
    adds w u u^T along its axis u; ``floor`` (N,) adds a vertical penalty per node.
    """
    from scipy import sparse

    n = body.n_nodes
    a, b = np.asarray(body.spring_a), np.asarray(body.spring_b)
    u = body.rest_pos[b] - body.rest_pos[a]
    u = u / np.maximum(np.linalg.norm(u, axis=1), 1e-12)[:, None]
    blk = np.asarray(weights, np.float64)[:, None, None] * u[:, :, None] * u[:, None, :]
    ii, jj = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
    rows, cols, vals = [], [], []
    for p, q, sign in ((a, a, 1.0), (b, b, 1.0), (a, b, -1.0), (b, a, -1.0)):
        rows.append((3 * p[:, None, None] + ii).ravel())
        cols.append((3 * q[:, None, None] + jj).ravel())
        vals.append((sign * blk).ravel())
    rows.append(3 * np.arange(n) + 1)
    cols.append(3 * np.arange(n) + 1)
    vals.append(np.asarray(floor, np.float64))
    w = sparse.coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(3 * n, 3 * n)
    ).tocsr()
    inv = sparse.diags(np.repeat(1.0 / np.sqrt(np.asarray(body.mass, np.float64)), 3))
    return (inv @ w @ inv).tocsr()


def _largest(matrix) -> float:
    """Return the largest eigenvalue of a symmetric (sparse) matrix."""
    if matrix.shape[0] <= 3 * DENSE_NODES:
        return float(np.linalg.eigvalsh(matrix.toarray())[-1])
    from scipy.sparse.linalg import eigsh

    return float(eigsh(matrix, k=1, which="LA", tol=1e-8, return_eigenvectors=False)[0])


def stable_dt(body: Body, medium: Medium | str | None = None) -> float:
    """Return the largest time step (s) the kernel's integrator can take with this body.

    Semi-implicit Euler with explicit spring forces is stable for the linearised lattice
    while dt^2 M^-1 K + 2 dt M^-1 C < 4 I (K the stiffness and C the spring-damping matrix at
    the rest pose, plus the floor's penalty contact on the nodes that rest on it); nodal
    damping is implicit and water drag is capped, so neither limits the step. The springs
    that the multirate step sub-steps at the body's own dt (``multirate.split``: a stiff
    caudal fin, say) are left out of K and C, since they are stepped at a fraction of dt (at
    most ``MAX_SUBSTEPS`` of them, else no spring is exempt); the bound is conservative above
    the body's own dt, where more springs would be sub-stepped.
    The limit is found by bisection on the largest eigenvalue (dense up to ``DENSE_NODES``
    nodes, Lanczos beyond); for a body with no sub-stepped springs it predicts the step at
    which its gait blows up to within a few per cent.
    """
    from zoetic.physics.multirate import split

    med = get_medium(medium or body.medium)
    own = split(body, float(body.dt))
    slow = np.zeros(body.n_springs, dtype=bool)
    slow[own.slow_springs] = True
    if own.substeps > MAX_SUBSTEPS:  # a file whose own step is far too large: no exemption
        slow[:] = True
    n = body.n_nodes
    floor_k = np.zeros(n)
    floor_c = np.zeros(n)
    if med.floor:
        y = body.rest_pos[:, 1] + body.start_offset[1]
        contact = y <= y.min() + 1e-6
        floor_k[contact] = med.floor_stiffness
        floor_c[contact] = med.floor_damping
    ks = _lattice_matrix(body, np.where(slow, body.stiffness, 0.0), floor_k)
    cs = _lattice_matrix(body, np.where(slow, body.spring_damping, 0.0), floor_c)
    lam = _largest(ks)
    eta = max(_largest(cs), 0.0)
    if lam <= 0:
        return float("inf")
    hi = 2.0 / np.sqrt(lam)  # undamped limit: the damped one is below it
    lo = 4.0 / (eta + np.sqrt(eta * eta + 4.0 * lam))  # both worst modes in one: safe
    for _ in range(16):  # to 1e-5 of the bracket, which is at most a factor 2 wide
        mid = 0.5 * (lo + hi)
        if _largest(mid * mid * ks + 2.0 * mid * cs) < 4.0:
            lo = mid
        else:
            hi = mid
    return float(lo)


_STABLE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _stable_cached(body: Body, med: Medium) -> float:
    key = (med.floor, med.floor_stiffness, med.floor_damping)
    per_body = _STABLE.setdefault(body, {})
    if key not in per_body:
        per_body[key] = stable_dt(body, med)
    return per_body[key]


def check_dt(body: Body, dt: float, medium: Medium | str | None = None, where: str = "") -> float:
    """Return ``dt`` if it is positive and within the body's stable step; else SimulationError.

    The message names the animal (``where``: the file or option it came from) and a step
    that works (0.8 x the limit, or the animal's own when that is smaller).
    """
    at = f"{where}: " if where else ""
    if not (np.isfinite(dt) and dt > 0):
        raise SimulationError(f"{at}the time step must be a positive number, got {dt}")
    med = get_medium(medium or body.medium)
    limit = _stable_cached(body, med)
    if dt > limit:
        raise SimulationError(
            f"{at}dt = {dt:g} s is too large for the {body.name} (from {body.source}): its "
            f"stiffest springs and lightest nodes allow at most {limit:.3g} s in {med.name}; "
            f"use dt <= {good_dt(body, med):.3g} s"
        )
    return dt


def good_dt(body: Body, medium: Medium | str | None = None) -> float:
    """Return a time step that works for the body: its own, or 0.8 x the stable limit."""
    limit = _stable_cached(body, get_medium(medium or body.medium))
    return float(min(body.dt, 0.8 * limit)) if body.dt <= limit else float(0.8 * limit)


def _threads() -> int:
    from numba import get_num_threads

    return max(1, get_num_threads())


def chunk_size(batch: int, threads: int | None = None) -> int:
    """Return the lanes per thread chunk: one chunk per thread, a multiple of 8, at most 512,
    and no more chunks than whole ``SPLIT_LANES`` fit in the batch.

    Long chunks amortise each spring's and panel's loop set-up over more SIMD lanes; at 512
    lanes a chunk's state is about 0.4 MB and still sits in L2 (measured: 256 lanes per thread
    run 1.5x faster than 64). A chunk under ``SPLIT_LANES`` takes the kernel's one-animal path,
    many times slower a lane when it holds several (docs/performance.md), so a batch of 16 to
    31 lanes (a stunt search's 16 plans) is one chunk, not two of 8.
    """
    from zoetic.physics.kernel_terms import SPLIT_LANES

    threads = threads or _threads()
    chunks = max(1, min(threads, batch // SPLIT_LANES))
    per = -(-batch // chunks)
    return int(min(512, max(8, -(-per // 8) * 8)))


def _check_activations(body: Body, act: np.ndarray) -> None:
    if act.ndim != 3 or act.shape[2] != body.n_actuators:
        raise SimulationError(
            f"activations must be shaped (candidates, steps, {body.n_actuators}) for "
            f"{body.name}, got {act.shape}"
        )


def _check_state(body: Body, state: State, batch: int) -> None:
    if state.positions.shape != (batch, body.n_nodes, 3):
        raise SimulationError(
            f"start state holds {state.positions.shape} positions; expected "
            f"({batch}, {body.n_nodes}, 3)"
        )


def simulate(
    body: Body,
    activations: np.ndarray,
    medium: str | Medium | None = None,
    dt: float | None = None,
    state: State | None = None,
    record_every: int = 1,
    check_step: bool = True,
) -> Trajectory:
    """Return the Trajectory of each candidate driven by its activation table.

    Parameters
    ----------
    activations : (B, T, A) or (T, A) array in [0, 1] (values are clipped); one row a step.
    medium : a Medium or the name of a built-in one; default the body's own.
    dt : time step in s; default the body's own.
    state : start State with batch B; default the rest pose.
    record_every : record positions every this many steps (and at the last step's end).
    check_step : refuse (SimulationError) a dt beyond the body's stable step (``stable_dt``).
    """
    act = np.asarray(activations)
    if act.ndim == 2:
        act = act[None]
    _check_activations(body, act)
    act_t = kernel_layout(act.shape[1], act.shape[2], act.shape[0])
    if act.shape[2]:
        act_t[...] = act.transpose(1, 2, 0)
    return simulate_laid_out(body, act_t, medium, dt, state, record_every, check_step)


def kernel_layout(steps: int, actuators: int, batch: int) -> np.ndarray:
    """Return an activation table as the kernel reads it, (T, A, B) float32 zeros, for
    ``simulate_laid_out``: filled straight from float64 tables, with no float64 copy between
    (on a big batch the copy costs as much as the simulation). A body without actuators gets
    one zero column for its passive springs to read."""
    return np.zeros((steps, max(1, actuators), batch), dtype=np.float32)


def simulate_laid_out(
    body: Body,
    act_t: np.ndarray,
    medium: str | Medium | None = None,
    dt: float | None = None,
    state: State | None = None,
    record_every: int = 1,
    check_step: bool = True,
    threads: bool = True,
) -> Trajectory:
    """Return the Trajectory of ``simulate`` from activations already laid out as the kernel
    reads them (``kernel_layout``, step-major); ``act_t`` is checked and clipped in place.
    ``threads=False``: the chunks in turn on this thread (``kernel.simulate_chunks_serial``,
    as a World steps a small batch), without the thread pool's launch."""
    med = get_medium(medium or body.medium)
    dt = float(dt or body.dt)
    if check_step:
        check_dt(body, dt, med)
    if act_t.shape[1:2] != (max(1, body.n_actuators),) or act_t.dtype != np.float32:
        raise SimulationError(
            f"laid-out activations must be float32 (steps, {max(1, body.n_actuators)}, "
            f"candidates) for {body.name}, got {act_t.dtype} {act_t.shape}"
        )
    steps, batch = act_t.shape[0], act_t.shape[2]
    state = state or rest_state(body, batch)
    _check_state(body, state, batch)
    if record_every < 1:
        raise SimulationError("record_every must be at least 1")

    from zoetic.physics.kernel import simulate_chunks, simulate_chunks_serial
    from zoetic.physics.model import compile_model

    n = body.n_nodes
    f32 = np.float32
    if not np.isfinite(act_t).all():
        raise SimulationError("activations contain non-finite values")
    np.clip(act_t, 0.0, 1.0, out=act_t)
    pos0 = np.ascontiguousarray(state.positions.transpose(1, 2, 0), dtype=f32)
    vel0 = np.ascontiguousarray(state.velocities.transpose(1, 2, 0), dtype=f32)
    n_rec = steps // record_every + 1
    rec = np.empty((n_rec, n, 3, batch), dtype=f32)
    final_pos = np.empty((n, 3, batch), dtype=f32)
    final_vel = np.empty((n, 3, batch), dtype=f32)
    failed_step = -np.ones(batch, dtype=np.int64)
    model = compile_model(body, med, dt)
    (simulate_chunks if threads else simulate_chunks_serial)(
        pos0,
        vel0,
        act_t,
        record_every,
        chunk_size(batch),
        f32(VMAX),
        model,
        rec,
        final_pos,
        final_vel,
        failed_step,
    )
    times = np.arange(n_rec) * record_every * dt
    return Trajectory(
        times=times,
        positions=rec.transpose(3, 0, 1, 2).astype(np.float64),
        final=State(
            final_pos.transpose(2, 0, 1).astype(np.float64),
            final_vel.transpose(2, 0, 1).astype(np.float64),
        ),
        failed_step=failed_step,
        dt=dt,
    )


def set_threads(n: int | None) -> None:
    """Use ``n`` CPU threads for batched simulation (default: all cores)."""
    from numba import config, set_num_threads

    set_num_threads(n or config.NUMBA_NUM_THREADS)


def cores() -> int:
    """Return the number of CPU cores the batched kernel can use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
