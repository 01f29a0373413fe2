"""The fast CPU path: a Numba kernel that steps a batch of candidates, SIMD across the batch.

Layout: every per-node quantity is an array (nodes, lanes) so that the innermost loop runs
over candidates ("lanes") with unit stride and LLVM vectorises it; each thread owns a chunk
of lanes and runs all its steps with that chunk in cache. Activations arrive as a table
(steps, actuators, candidates); the kernel never knows which controller made it. The body,
its spring split and the medium arrive as one ``model.Model``, read by field name.

One step is semi-implicit (symplectic) Euler: forces from the current state, velocity
updated with nodal damping implicit, then positions from the new velocity. Ground friction is
solved last, against the velocity the other forces would produce (implicit Coulomb), and
water forces can at most stop a face's normal motion in one step, so stiff drag on light
nodes cannot blow up. A candidate whose state is non-finite or faster than ``vmax`` is marked
failed, reset to rest (so it cannot slow or poison the others) and reported. Springs too
stiff for the step (``multirate.split``) are integrated in sub-steps inside each step, after
one kick of every other force (impulse multirate), so a stiff caudal fin does not shrink the
whole body's step. The force terms are in ``kernel_terms``.

error_model="numpy" on the entry points (every helper is inlined into them): with Python's
error model each float division checks for zero and may raise, an early exit that keeps LLVM
from vectorising a loop with two or more divisions (the fins ran scalar: 46 against 5 ns a
lane-step). Every divisor here is a mass, the step, or a length plus TINY, never zero.
"""

from __future__ import annotations

import types as pytypes

import numpy as np
from numba import njit, prange, types
from numba.experimental import structref
from numba.extending import typeof_impl

from zoetic.physics.kernel_terms import (
    FM,
    FX,
    GX,
    GY,
    GZ,
    NF,
    VX,
    VY,
    VZ,
    ZERO,
    F,
    X,
    Y,
    Z,
    FY,
    FZ,
    advance_nodes,
    fins,
    floor_constants,
    ground,
    springs,
    water,
    weight,
)
from zoetic.physics.model import INDEX, NO_WATER, Model, field_kinds


# Lanes a block steps together: a compile-time constant, so that every lane loop has a known
# length (no remainder loop) and a block's state (nodes, NF, LANES) stays in L1. 16 is two
# AVX2 vectors or one AVX-512 vector.
LANES = 16
WIDE = 4  # from this many lanes the wide blocks step them (fewer: one lane a block)


@njit(cache=True, fastmath=FM, inline="always")
def _block_steps(
    s, arow, tmp, pos0, vel0, act, record_every, vmax, b0, nb, m, rec, final_pos, final_vel,
    failed_step,
):
    """Step lanes b0 .. b0 + nb of model ``m`` through all rows of ``act`` in the block state
    s (nodes, NF, lanes >= nb; lanes past nb repeat lane b0): load them from pos0/vel0,
    record every ``record_every`` steps (never if 0), store the final state (NaN for failed
    lanes) in final_pos/final_vel. ``arow`` (A, lanes) and ``tmp`` (3, lanes) are scratch.

    A step: every force but the stiff springs, the floor last, then the nodes no fast spring
    touches advance once, exactly as without a split, and the others take their sub-steps."""
    _put(s, X, pos0, b0, nb)
    _put(s, VX, vel0, b0, nb)
    # what the steps share, decided once
    dt = F(m.dt)
    water_on = F(m.water_drag) > 0.0 and F(m.water_level) > NO_WATER
    fins_on = water_on and m.fin_nodes.shape[0] > 0
    split = m.fast_springs.shape[0] > 0
    floor = floor_constants(m)
    n_steps = act.shape[0]
    r = 0
    for t in range(n_steps + 1):
        if record_every > 0 and t % record_every == 0:
            _take(rec[r], s, X, failed_step, b0, nb)
            r += 1
        if t == n_steps:
            break
        _act_row(arow, act, t, b0, nb)
        weight(s, m)
        springs(s, FX, arow, m, m.slow_springs)
        if water_on:
            water(s, m)
        if fins_on:
            fins(s, tmp, arow, m)
        if m.floor:
            ground(s, m, floor)
        advance_nodes(s, FX, m, dt, m.slow_nodes)
        if split:
            _substeps(s, arow, m)
        if t % 8 == 7 or t == n_steps - 1:
            _check_lanes(s, tmp, m, vmax, t, b0, nb, failed_step)
    _take(final_pos, s, X, failed_step, b0, nb)
    _take(final_vel, s, VX, failed_step, b0, nb)


@njit(cache=True, fastmath=FM, inline="always")
def _act_row(arow, act, t, b0, nb):
    """Copy step t's activations of lanes b0 .. b0 + nb into arow (A, lanes), the lanes past
    nb repeating lane b0, so that the force terms read them with unit stride from lane 0.
    The index is unsigned: a signed b0 + b is checked for wrap-around lane by lane, which
    turned the load of each spring's activation into eight scalar loads."""
    for c in range(act.shape[1]):
        for b in range(nb):
            arow[c, b] = act[t, c, np.uint64(b0 + b)]
        for b in range(nb, arow.shape[1]):
            arow[c, b] = arow[c, 0]


@njit(cache=True, fastmath=FM, inline="always")
def _put(s, f, src, b0, nb):
    """Load lanes b0 .. b0 + nb of src (nodes, 3, lanes) into fields f .. f + 2 of the block
    s, the block's lanes past nb repeating lane b0."""
    for i in range(s.shape[0]):
        for b in range(s.shape[2]):
            lane = np.uint64(b0 + (b if b < nb else 0))
            s[i, f, b] = src[i, 0, lane]
            s[i, f + 1, b] = src[i, 1, lane]
            s[i, f + 2, b] = src[i, 2, lane]


@njit(cache=True, fastmath=FM, inline="always")
def _take(dst, s, f, failed_step, b0, nb):
    """Write fields f .. f + 2 of the block's first nb lanes into lanes b0 .. b0 + nb of dst
    (nodes, 3, lanes), NaN in the lanes that failed."""
    for i in range(s.shape[0]):
        for b in range(nb):
            lane = np.uint64(b0 + b)
            dead = failed_step[lane] >= 0
            dst[i, 0, lane] = np.nan if dead else s[i, f, b]
            dst[i, 1, lane] = np.nan if dead else s[i, f + 1, b]
            dst[i, 2, lane] = np.nan if dead else s[i, f + 2, b]


@njit(cache=True, fastmath=FM, inline="always")
def _substeps(s, arow, m):
    """The fast nodes of a split (``multirate.split``): the step's other forces (fields FX ..
    FZ) kick their velocities once, then the stiff springs (into GX .. GZ) drive
    ``m.substeps`` sub-steps.

    Impulse (RESPA) order: holding the slow forces over the sub-steps instead is not
    symplectic and grows energy (det of the step map > 1)."""
    dt = F(m.dt)
    hsub = dt / F(max(m.substeps, 1))
    fast_nodes, mass = m.fast_nodes, m.mass
    for q in range(fast_nodes.shape[0]):
        i = fast_nodes[q]
        hm = dt / mass[i]
        for b in range(s.shape[2]):
            s[i, VX, b] += hm * s[i, FX, b]
            s[i, VY, b] += hm * s[i, FY, b]
            s[i, VZ, b] += hm * s[i, FZ, b]
    for _sub in range(m.substeps):
        for q in range(fast_nodes.shape[0]):
            i = fast_nodes[q]
            for b in range(s.shape[2]):
                s[i, GX, b] = ZERO
                s[i, GY, b] = ZERO
                s[i, GZ, b] = ZERO
        springs(s, GX, arow, m, m.fast_springs)
        advance_nodes(s, GX, m, hsub, fast_nodes)


@njit(cache=True, fastmath=FM, inline="always")
def _check_lanes(s, tmp, m, vmax, t, b0, nb, failed_step):
    """Mark the lanes faster than vmax (or not finite) as failed at step t + 1, and put every
    failed lane back to rest so that it cannot slow or poison the others (``tmp`` (1, lanes)
    scratch)."""
    rest_pos = m.rest_pos
    n_nodes = rest_pos.shape[0]
    lanes = s.shape[2]
    worst = tmp[0]
    for b in range(lanes):
        worst[b] = ZERO
    for i in range(n_nodes):
        for b in range(lanes):
            s2 = s[i, VX, b] * s[i, VX, b] + s[i, VY, b] * s[i, VY, b] + s[i, VZ, b] * s[i, VZ, b]
            worst[b] = s2 if s2 > worst[b] else worst[b]
    for b in range(lanes):
        bad = not (worst[b] < vmax * vmax)
        if b < nb:
            lane = np.uint64(b0 + b)
            if bad and failed_step[lane] < 0:
                failed_step[lane] = t + 1
            bad = failed_step[lane] >= 0
        if bad:
            for i in range(n_nodes):
                s[i, X, b] = rest_pos[i, 0]
                s[i, Y, b] = rest_pos[i, 1]
                s[i, Z, b] = rest_pos[i, 2]
                s[i, VX, b] = ZERO
                s[i, VY, b] = ZERO
                s[i, VZ, b] = ZERO


@njit(cache=True, fastmath=FM, parallel=True, error_model="numpy")
def simulate_chunks(pos0, vel0, act, record_every, chunk, vmax, m, rec, final_pos, final_vel,
                    failed_step):
    """Step every candidate of model ``m`` through all activation rows; fills rec (R, N, 3, B),
    final_pos and final_vel (N, 3, B) and failed_step (B,). Each thread takes chunks of
    ``chunk`` lanes and steps them in blocks of LANES lanes (``_block_steps``), one block
    through all its steps at a time, its state in L1."""
    n_lanes = pos0.shape[2]
    f32 = np.float32
    for c in prange((n_lanes + chunk - 1) // chunk):
        c0 = c * chunk
        c1 = min(c0 + chunk, n_lanes)
        # fresh per chunk: the lane count is a constant that LLVM sees in every loop
        s = np.empty((m.mass.shape[0], NF, LANES), dtype=f32)
        arow = np.empty((act.shape[1], LANES), dtype=f32)
        tmp = np.empty((3, LANES), dtype=f32)
        for b0 in range(c0, c1, LANES):
            _block_steps(s, arow, tmp, pos0, vel0, act, record_every, vmax, b0,
                         min(LANES, c1 - b0), m, rec, final_pos, final_vel, failed_step)


# ---- a stateful entry point: one animal's lanes stepped in place, slice after slice ----------
# A call through the dispatcher pays for typing and unboxing each argument (about 60 ns an
# array); a model holds about 30: about 2 us a call, against about 15 us of work in a 1/30 s
# slice of one shark. A Stepper holds the model and the state (stepped in place) in one struct
# that crosses into compiled code as one pointer, and ``advance_entry`` skips the dispatcher's
# typing: a slice costs its steps and about 1.5 us.


def _numba_type(kind):
    """The Numba type of a Model field of kind ``kind`` (``model.field_kinds``), float32."""
    if isinstance(kind, tuple):
        dtype = types.int64 if kind[0] == INDEX else types.float32
        return types.Array(dtype, kind[1], "C", readonly=True)
    return {float: types.float64, int: types.int64, bool: types.boolean}[kind]


# the Numba type of every float32 Model (``compile_model`` enforces each field's kind)
MODEL = types.NamedTuple([_numba_type(k) for k in field_kinds().values()], Model)
_F3 = types.Array(types.float32, 3, "C")
_I1 = types.Array(types.int64, 1, "C")


@structref.register
class StepperType(types.StructRef):
    """Numba type of a Stepper."""


class Stepper(structref.StructRefProxy):
    """One animal's lanes and everything the kernel needs to step them in place.

    model: the animal's float32 Model; pos, vel: (N, 3, B) float32 state, stepped in place
    (the World's own arrays); fs: (B,) the kernel's failure marks (>= 0 a dead lane); failed:
    (B,) the step each lane blew up at (-1 if not), kept by ``advance``.
    """


structref.define_boxing(StepperType, Stepper)


@typeof_impl.register(Stepper)
def _typeof_stepper(val, c):
    # the generic typeof tries the buffer protocol first, and its exception costs more than
    # the rest of a call
    return val._type


_STEPPER = StepperType(
    [("model", MODEL), ("pos", _F3), ("vel", _F3), ("fs", _I1), ("failed", _I1),
     ("chunk", types.int64), ("vmax", types.float32)]
)


@njit(cache=True)
def _new_stepper(model, pos, vel, fs, failed, chunk, vmax):
    st = structref.new(_STEPPER)
    st.model = model
    st.pos = pos
    st.vel = vel
    st.fs = fs
    st.failed = failed
    st.chunk = chunk
    st.vmax = vmax
    return st


def make_stepper(model: Model, pos, vel, fs, failed, chunk: int, vmax: float) -> Stepper:
    """Return a Stepper of a float32 ``model`` over the state arrays pos/vel (N, 3, B), fs and
    failed (B,) (all stepped in place, so they must be C-contiguous float32 / int64), stepped
    in chunks of ``chunk`` lanes; a lane faster than ``vmax`` m/s has blown up."""
    from numba import typeof

    if typeof(model) != MODEL:
        raise TypeError("a Stepper steps a float32 Model from compile_model")
    return _new_stepper(model, pos, vel, fs, failed, int(chunk), F(vmax))


def variant(fn, name: str, parallel: bool, lanes: int):
    """Return a copy of ``fn`` (an njit(parallel=True) function of this module) under its own
    name (numba keys its on-disk cache by the qualified name) with blocks of ``lanes`` lanes,
    compiled for the thread pool or for this thread alone (its ``prange`` runs as ``range``:
    no thread-pool launch, which costs more than a short slice of one animal)."""
    py = fn.py_func
    copy = pytypes.FunctionType(
        py.__code__, {**py.__globals__, "LANES": lanes}, name, py.__defaults__, py.__closure__
    )
    copy.__qualname__ = name
    return njit(cache=True, fastmath=FM, parallel=parallel, error_model="numpy")(copy)


# one lane a block, for fewer lanes than WIDE: a wide block would step mostly copies
simulate_chunks_serial = variant(simulate_chunks, "simulate_chunks_serial", False, LANES)
simulate_narrow = variant(simulate_chunks, "simulate_narrow", True, 1)
simulate_narrow_serial = variant(simulate_chunks, "simulate_narrow_serial", False, 1)


def simulate_entry(lanes: int):
    """Return the threaded kernel entry for ``lanes`` candidates (wide or narrow blocks)."""
    return simulate_chunks if lanes >= WIDE else simulate_narrow


@njit(cache=True, error_model="numpy")
def advance(st, table, t0, t1, base):
    """Step the Stepper's lanes in place through rows t0 .. t1 of ``table`` (T, A, B), on the
    threads; a lane that blows up is marked in ``st.failed`` at step ``base`` plus its step
    in the call."""
    pos, vel = st.pos, st.vel
    no_rec = np.empty((0, pos.shape[0], 3, pos.shape[2]), dtype=np.float32)  # no records
    if pos.shape[2] >= WIDE:
        simulate_chunks(pos, vel, table[t0:t1], 0, st.chunk, st.vmax, st.model, no_rec, pos,
                        vel, st.fs)
    else:
        simulate_narrow(pos, vel, table[t0:t1], 0, st.chunk, st.vmax, st.model, no_rec, pos,
                        vel, st.fs)
    _mark_failed(st.fs, st.failed, base)


@njit(cache=True, error_model="numpy")
def advance_serial(st, table, t0, t1, base):
    """``advance`` on this thread alone (``serial``)."""
    pos, vel = st.pos, st.vel
    no_rec = np.empty((0, pos.shape[0], 3, pos.shape[2]), dtype=np.float32)  # no records
    if pos.shape[2] >= WIDE:
        simulate_chunks_serial(pos, vel, table[t0:t1], 0, st.chunk, st.vmax, st.model, no_rec,
                               pos, vel, st.fs)
    else:
        simulate_narrow_serial(pos, vel, table[t0:t1], 0, st.chunk, st.vmax, st.model, no_rec,
                               pos, vel, st.fs)
    _mark_failed(st.fs, st.failed, base)


@njit(cache=True, inline="always")
def _mark_failed(fs, failed, base):
    """Keep in ``failed`` the step (``base`` plus the kernel's mark ``fs``) each lane first
    blew up at."""
    for b in range(fs.shape[0]):
        if failed[b] < 0 and fs[b] >= 0:
            failed[b] = base + fs[b]


def advance_entry(parallel: bool):
    """Return ``advance`` (threaded) or ``advance_serial`` compiled for a Stepper and a float32
    table, as its compiled entry point: calling that skips the dispatcher's typing of each
    argument (about 0.6 us of a 2 us call, which matters in 1/30 s slices of one animal). The
    arguments must then have exactly those types: (Stepper, float32 (T, A, B) C array, int,
    int, int)."""
    fn = advance if parallel else advance_serial
    return fn.compile((_STEPPER, _F3, types.int64, types.int64, types.int64))
