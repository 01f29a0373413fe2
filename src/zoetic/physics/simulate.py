"""simulate(body, activations, medium, dt, state) -> Trajectory, for one candidate or many."""

from __future__ import annotations

import os
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


def _threads() -> int:
    from numba import get_num_threads

    return max(1, get_num_threads())


def chunk_size(batch: int, threads: int | None = None) -> int:
    """Return the lanes per thread chunk: one chunk per thread, a multiple of 8, at most 512.

    Long chunks amortise each spring's and panel's loop set-up over more SIMD lanes; at 512
    lanes a chunk's state is about 0.4 MB and still sits in L2 (measured: 256 lanes per thread
    run 1.5x faster than 64).
    """
    threads = threads or _threads()
    per = -(-batch // threads)
    return int(min(512, max(8, -(-per // 8) * 8)))


def _check(body: Body, act: np.ndarray, state: State) -> None:
    if act.ndim != 3 or act.shape[2] != body.n_actuators:
        raise SimulationError(
            f"activations must be shaped (candidates, steps, {body.n_actuators}) for "
            f"{body.name}, got {act.shape}"
        )
    if state.positions.shape != (act.shape[0], body.n_nodes, 3):
        raise SimulationError(
            f"start state holds {state.positions.shape} positions; expected "
            f"({act.shape[0]}, {body.n_nodes}, 3)"
        )


def _kernel_arrays(body: Body) -> tuple:
    """Return the body's arrays in the order and precision the kernel takes them."""
    f32 = np.float32
    muscle = body.spring_actuator >= 0
    # the kernel's rest length is l_r + a * shorten with a read from column scol: passive
    # springs shorten by nothing and read column 0, so the spring loop has no branch
    shorten = np.where(muscle, body.contracted - body.relaxed, 0.0).astype(f32)
    scol = np.where(muscle, body.spring_actuator, 0).astype(np.int64)
    return (
        body.mass.astype(f32), body.node_damping.astype(f32), body.spring_a, body.spring_b,
        body.stiffness.astype(f32), body.spring_damping.astype(f32), body.relaxed.astype(f32),
        shorten, scol, body.panels,
        body.panel_weights.astype(f32), body.fin_nodes,
        body.fin_forward, body.fin_span, body.fin_area.astype(f32),
        body.fin_angle.astype(f32), body.fin_actuator, body.axis_front, body.axis_back,
        body.rest_pos.astype(f32),
    )  # fmt: skip


def simulate(
    body: Body,
    activations: np.ndarray,
    medium: str | Medium | None = None,
    dt: float | None = None,
    state: State | None = None,
    record_every: int = 1,
) -> Trajectory:
    """Return the Trajectory of each candidate driven by its activation table.

    Parameters
    ----------
    activations : (B, T, A) or (T, A) array in [0, 1] (values are clipped); one row a step.
    medium : a Medium or the name of a built-in one; default the body's own.
    dt : time step in s; default the body's own.
    state : start State with batch B; default the rest pose.
    record_every : record positions every this many steps (and at the last step's end).
    """
    act = np.asarray(activations)
    if act.ndim == 2:
        act = act[None]
    med = get_medium(medium or body.medium)
    dt = float(dt or body.dt)
    batch, steps = act.shape[0], act.shape[1]
    state = state or rest_state(body, batch)
    _check(body, act, state)
    if record_every < 1:
        raise SimulationError("record_every must be at least 1")

    from zoetic.physics.kernel import simulate_chunks
    from zoetic.physics.multirate import split

    n = body.n_nodes
    f32 = np.float32
    # (T, A, B) float32, then checked and clipped to [0, 1] in place: on a big batch this copy
    # costs as much as the simulation, so no float64 intermediates. A body without actuators
    # gets one zero column for its passive springs to read.
    act_t = np.zeros((steps, max(1, act.shape[2]), batch), dtype=f32)
    if act.shape[2]:
        act_t[...] = act.transpose(1, 2, 0)
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
    k = _kernel_arrays(body)
    sp = split(body, dt)
    simulate_chunks(
        pos0, vel0, act_t, f32(dt), record_every, chunk_size(batch), f32(VMAX), *k,
        med.as_array().astype(f32), rec, final_pos, final_vel, failed_step,
        sp.slow_springs, sp.fast_springs, sp.substeps, sp.slow_nodes, sp.fast_nodes,
    )  # fmt: skip
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
