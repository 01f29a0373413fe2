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

from zoetic.jitcache import fresh_numba_cache
from zoetic.physics.kernel_terms import (
    FM,
    SPLIT_LANES,
    ZERO,
    F,
    advance_nodes,
    fins,
    floor_constants,
    ground,
    springs,
    water,
    weight,
)
from zoetic.physics.model import INDEX, NO_WATER, Model, field_kinds
from zoetic.physics.noalias import njit_noalias

fresh_numba_cache()


@njit(cache=True, fastmath=FM, inline="always")
def _chunk_steps(
    s, pos0, vel0, act, record_every, vmax, b0, nb, m, rec, final_pos, final_vel, failed_step
):
    """Step lanes b0 .. b0 + nb of model ``m`` through all rows of ``act`` in s (twelve (nodes,
    >= nb) arrays): load them from pos0/vel0, record every ``record_every`` steps (never if 0),
    store the final state (NaN for failed lanes) in final_pos/final_vel."""
    _put(s[0], s[1], s[2], pos0, b0, nb)
    _put(s[3], s[4], s[5], vel0, b0, nb)
    if nb < SPLIT_LANES:
        x, y, z, vx, vy, vz, fx, fy, fz, gx, gy, gz = s
        _steps_inline(
            x,
            y,
            z,
            vx,
            vy,
            vz,
            fx,
            fy,
            fz,
            gx,
            gy,
            gz,
            act,
            record_every,
            vmax,
            b0,
            nb,
            m,
            rec,
            failed_step,
        )
    else:
        _steps(*s, act, record_every, vmax, b0, nb, m, rec, failed_step)
    _take(final_pos, s[0], s[1], s[2], failed_step, b0, nb)
    _take(final_vel, s[3], s[4], s[5], failed_step, b0, nb)


@njit_noalias(cache=True, fastmath=FM, error_model="numpy")
def _steps(
    x,
    y,
    z,
    vx,
    vy,
    vz,
    fx,
    fy,
    fz,
    gx,
    gy,
    gz,
    act,
    record_every,
    vmax,
    b0,
    nb,
    m,
    rec,
    failed_step,
):
    """Step the chunk's state (x .. vz; fx .. gz scratch, all (nodes, >= nb) and distinct, the
    promise of ``njit_noalias``) through all rows of ``act``, recording every ``record_every``
    steps (never if 0).

    A step: every force but the stiff springs, the floor last, then the nodes no fast spring
    touches advance once, exactly as without a split, and the others take their sub-steps."""
    s = (x, y, z, vx, vy, vz, fx, fy, fz, gx, gy, gz)
    arow = np.empty((act.shape[1], nb), dtype=np.float32)  # this step's activations
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
            _take(rec[r], x, y, z, failed_step, b0, nb)
            r += 1
        if t == n_steps:
            break
        _act_row(arow, act, t, b0, nb)
        weight(y, fx, fy, fz, nb, m)
        springs(x, y, z, vx, vy, vz, fx, fy, fz, arow, nb, m, m.slow_springs)
        if water_on:
            water(x, y, z, vx, vy, vz, fx, fy, fz, gx, nb, m)
        if fins_on:
            fins(x, y, z, vx, vy, vz, fx, fy, fz, gx, arow, nb, m)
        if m.floor:
            ground(x, y, z, vx, vy, vz, fx, fy, fz, nb, m, floor)
        advance_nodes(x, y, z, vx, vy, vz, fx, fy, fz, nb, m, dt, m.slow_nodes)
        if split:
            _substeps(s, arow, nb, m)
        if t % 8 == 7 or t == n_steps - 1:
            _check_lanes(s, m, vmax, t, b0, nb, failed_step)


# a few lanes (one animal in a World) run faster inlined into the caller, as plain njit code
_steps_inline = njit(cache=True, fastmath=FM, inline="always")(_steps.py_func)


@njit(cache=True, fastmath=FM, inline="always")
def _act_row(arow, act, t, b0, nb):
    """Copy step t's activations of lanes b0 .. b0 + nb into arow (A, >= nb), so that the
    force terms read them with unit stride from lane 0. The index is unsigned: a signed
    b0 + b is checked for wrap-around lane by lane, which made the load of each spring's
    activation in the lane loop eight scalar loads and inserts (about 40 instructions of a
    spring's 100 per 8 lanes on AVX2)."""
    for c in range(act.shape[1]):
        for b in range(nb):
            arow[c, b] = act[t, c, np.uint64(b0 + b)]


@njit(cache=True, fastmath=FM, inline="always")
def _put(x, y, z, src, b0, nb):
    """Load lanes b0 .. b0 + nb of src (nodes, 3, lanes) into (x, y, z) (nodes, >= nb)."""
    for i in range(x.shape[0]):
        for b in range(nb):
            x[i, b] = src[i, 0, b0 + b]
            y[i, b] = src[i, 1, b0 + b]
            z[i, b] = src[i, 2, b0 + b]


@njit(cache=True, fastmath=FM, inline="always")
def _take(dst, x, y, z, failed_step, b0, nb):
    """Write lanes b0 .. b0 + nb of (x, y, z) (nodes, >= nb) into dst (nodes, 3, lanes), NaN
    in the lanes that failed."""
    for i in range(x.shape[0]):
        for b in range(nb):
            dead = failed_step[b0 + b] >= 0
            dst[i, 0, b0 + b] = np.nan if dead else x[i, b]
            dst[i, 1, b0 + b] = np.nan if dead else y[i, b]
            dst[i, 2, b0 + b] = np.nan if dead else z[i, b]


@njit(cache=True, fastmath=FM, inline="always")
def _substeps(s, arow, nb, m):
    """The fast nodes of a split (``multirate.split``): the step's other forces (in fx, fy,
    fz) kick their velocities once, then the stiff springs drive ``m.substeps`` sub-steps.

    Impulse (RESPA) order: holding the slow forces over the sub-steps instead is not
    symplectic and grows energy (det of the step map > 1)."""
    x, y, z, vx, vy, vz, fx, fy, fz, gx, gy, gz = (
        s[0],
        s[1],
        s[2],
        s[3],
        s[4],
        s[5],
        s[6],
        s[7],
        s[8],
        s[9],
        s[10],
        s[11],
    )
    dt = F(m.dt)
    hsub = dt / F(max(m.substeps, 1))
    fast_nodes, mass = m.fast_nodes, m.mass
    for q in range(fast_nodes.shape[0]):
        i = fast_nodes[q]
        hm = dt / mass[i]
        for b in range(nb):
            vx[i, b] += hm * fx[i, b]
            vy[i, b] += hm * fy[i, b]
            vz[i, b] += hm * fz[i, b]
    for _sub in range(m.substeps):
        for q in range(fast_nodes.shape[0]):
            i = fast_nodes[q]
            for b in range(nb):
                gx[i, b] = ZERO
                gy[i, b] = ZERO
                gz[i, b] = ZERO
        springs(x, y, z, vx, vy, vz, gx, gy, gz, arow, nb, m, m.fast_springs)
        advance_nodes(x, y, z, vx, vy, vz, gx, gy, gz, nb, m, hsub, fast_nodes)


@njit(cache=True, fastmath=FM, inline="always")
def _check_lanes(s, m, vmax, t, b0, nb, failed_step):
    """Mark the lanes faster than vmax (or not finite) as failed at step t + 1, and put every
    failed lane back to rest so that it cannot slow or poison the others.

    Each lane's largest squared node speed (NaN if any is NaN) is folded node by node into a
    scratch row (gy's first, free between steps), so that the lane loops run with unit stride
    and vectorise."""
    x, y, z, vx, vy, vz, worst = s[0], s[1], s[2], s[3], s[4], s[5], s[10][0]
    rest_pos = m.rest_pos
    n_nodes = rest_pos.shape[0]
    for b in range(nb):
        worst[b] = ZERO
    for i in range(n_nodes):
        for b in range(nb):
            s2 = vx[i, b] * vx[i, b] + vy[i, b] * vy[i, b] + vz[i, b] * vz[i, b]
            # s2 * 0 is 0, or NaN for a NaN or infinite speed: the maximum then stays NaN
            # (every later comparison with it is false), and NaN fails the check below
            worst[b] = (s2 if s2 > worst[b] else worst[b]) + s2 * ZERO
    dead = 0
    for b in range(nb):
        if not (worst[b] < vmax * vmax) and failed_step[b0 + b] < 0:
            failed_step[b0 + b] = t + 1
        if failed_step[b0 + b] >= 0:
            dead += 1
    if dead == 0:
        return
    for b in range(nb):
        if failed_step[b0 + b] >= 0:
            for i in range(n_nodes):
                x[i, b] = rest_pos[i, 0]
                y[i, b] = rest_pos[i, 1]
                z[i, b] = rest_pos[i, 2]
                vx[i, b] = ZERO
                vy[i, b] = ZERO
                vz[i, b] = ZERO


@njit(cache=True, inline="always")
def _scratch(n_nodes, nb):
    """Twelve fresh (nodes, nb) float32 arrays for one chunk's state and forces: separate
    allocations, not views of one block, so that LLVM knows they do not alias (one block
    measured 1.3x slower a step, one lane)."""
    f32 = np.float32
    return (
        np.empty((n_nodes, nb), dtype=f32),
        np.empty((n_nodes, nb), dtype=f32),
        np.empty((n_nodes, nb), dtype=f32),
        np.empty((n_nodes, nb), dtype=f32),
        np.empty((n_nodes, nb), dtype=f32),
        np.empty((n_nodes, nb), dtype=f32),
        np.empty((n_nodes, nb), dtype=f32),
        np.empty((n_nodes, nb), dtype=f32),
        np.empty((n_nodes, nb), dtype=f32),
        np.empty((max(n_nodes, 4), nb), dtype=f32),  # also the water's and fins' scratch rows
        np.empty((n_nodes, nb), dtype=f32),
        np.empty((n_nodes, nb), dtype=f32),
    )


@njit(cache=True, fastmath=FM, parallel=True, error_model="numpy")
def simulate_chunks(
    pos0, vel0, act, record_every, chunk, vmax, m, rec, final_pos, final_vel, failed_step
):
    """Step every candidate of model ``m`` through all activation rows; fills rec (R, N, 3, B),
    final_pos and final_vel (N, 3, B) and failed_step (B,) (``_chunk_steps``)."""
    n_lanes = pos0.shape[2]
    for c in prange((n_lanes + chunk - 1) // chunk):
        b0 = c * chunk
        nb = min(chunk, n_lanes - b0)
        s = _scratch(m.mass.shape[0], nb)
        _chunk_steps(
            s,
            pos0,
            vel0,
            act,
            record_every,
            vmax,
            b0,
            nb,
            m,
            rec,
            final_pos,
            final_vel,
            failed_step,
        )


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
    [
        ("model", MODEL),
        ("pos", _F3),
        ("vel", _F3),
        ("fs", _I1),
        ("failed", _I1),
        ("chunk", types.int64),
        ("vmax", types.float32),
    ]
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


def serial(fn):
    """Return ``fn`` (an njit(parallel=True) function of this module) compiled for one thread
    (its ``prange`` runs as ``range``): no thread-pool launch, which costs more than a short
    slice of one animal. A copy under its own name, so that its on-disk cache entry is apart
    from the parallel one's (numba keys the cache by the function's qualified name)."""
    py = fn.py_func
    name = f"{py.__name__}_serial"
    copy = pytypes.FunctionType(py.__code__, py.__globals__, name, py.__defaults__, py.__closure__)
    copy.__qualname__ = name
    return njit(cache=True, fastmath=FM, error_model="numpy")(copy)


simulate_chunks_serial = serial(simulate_chunks)


@njit(cache=True, error_model="numpy")
def advance(st, table, t0, t1, base):
    """Step the Stepper's lanes in place through rows t0 .. t1 of ``table`` (T, A, B), on the
    threads; a lane that blows up is marked in ``st.failed`` at step ``base`` plus its step
    in the call."""
    pos, vel = st.pos, st.vel
    no_rec = np.empty((0, pos.shape[0], 3, pos.shape[2]), dtype=np.float32)  # no records
    simulate_chunks(pos, vel, table[t0:t1], 0, st.chunk, st.vmax, st.model, no_rec, pos, vel, st.fs)
    _mark_failed(st.fs, st.failed, base)


@njit(cache=True, error_model="numpy")
def advance_serial(st, table, t0, t1, base):
    """``advance`` on this thread alone (``serial``)."""
    pos, vel = st.pos, st.vel
    no_rec = np.empty((0, pos.shape[0], 3, pos.shape[2]), dtype=np.float32)  # no records
    simulate_chunks_serial(
        pos, vel, table[t0:t1], 0, st.chunk, st.vmax, st.model, no_rec, pos, vel, st.fs
    )
    _mark_failed(st.fs, st.failed, base)


@njit(cache=True, fastmath=FM, error_model="numpy")
def advance_one(st, table, t, base, scratch):
    """``advance_serial`` for row t of ``table`` alone (one step), in the caller's
    ``scratch`` (``chunk_scratch``), so that steps taken one at a time between contacts
    allocate nothing; each chunk steps as in ``simulate_chunks``, so the bits are the same
    (the same fast-math flags: the one-animal path is inlined into this function)."""
    pos, vel = st.pos, st.vel
    s, no_rec = scratch
    row = table[t : t + 1]
    n_lanes, chunk = pos.shape[2], st.chunk
    for c in range((n_lanes + chunk - 1) // chunk):
        b0 = c * chunk
        nb = min(chunk, n_lanes - b0)
        _chunk_steps(s, pos, vel, row, 0, st.vmax, b0, nb, st.model, no_rec, pos, vel, st.fs)
    _mark_failed(st.fs, st.failed, base)


@njit(cache=True)
def chunk_scratch(st):
    """Return scratch for ``advance_one``: one chunk's twelve (nodes, chunk) arrays, and an
    empty record (a step taken alone records nothing)."""
    no_rec = np.empty((0, st.pos.shape[0], 3, st.pos.shape[2]), dtype=np.float32)
    return _scratch(st.model.mass.shape[0], min(st.chunk, st.pos.shape[2])), no_rec


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
