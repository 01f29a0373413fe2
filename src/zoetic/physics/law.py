"""The force law and the step, written once for NumPy and JAX (an array-module argument ``xp``).

The law works in a structure-of-arrays layout with the batch innermost: positions and
velocities are (3, N, B) (the x, y and z components of N nodes for B candidates) and
activations (A, B), so that every term is elementwise work over contiguous rows of B lanes,
which NumPy and XLA vectorise. ``to_soa``/``from_soa`` convert from and to the (..., N, 3)
arrays the rest of the package holds; ``forces`` and ``step`` take those. The NumPy reference
steps a batch in float64, the JAX mirror a batch (or one candidate, B = 1) in float32. The
terms are those of the Numba kernel (``kernel_terms``), its hand-tuned twin: springs and
muscles, gravity and buoyancy, water panels whose force can at most stop a panel's normal
motion in one step, fins, a penalty floor with implicit directional Coulomb friction, implicit
nodal damping, semi-implicit Euler with the stiff springs sub-stepped after one kick of
everything else (``multirate.split``). Conformance tests hold the three equal.

Nothing is written in place. A term reads node rows (``edges``, ``_corners``) and spreads its
contributions back onto the nodes (``onto_ends``, ``onto_corners``: spring ends, panel and fin
corners) in one of two forms, chosen by ``dense``. JAX steps a small body by products with
constant incidence matrices built from the model's indices (``node_matrix``: +1/-1 per
spring, a panel's or fin's corner shares), a few dense products a step. Otherwise node rows
are gathered and contributions summed by ``gather_sum``: in JAX one scatter-add of whole
B-lane rows per component (one for all three in a narrow batch, ``per_component``), in NumPy
through a padded incidence table built once from the model's constant indices
(``incidence``), summed in order (in XLA that table's gather and reduction cost twice the
scatter). Dot products
over xyz and corner means are written as reductions (``sum`` over an axis): XLA's CPU fusion
copies an elementwise producer into every fusion that reads it, so a value read through
gathers would be recomputed per element read, while a reduction is computed once into a
buffer. NumPy sums those short axes in order.
Square roots and unit vectors are guarded (the double-``where`` trick) so that JAX gradients
stay finite at rest, where velocities are exactly zero.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from zoetic.physics.model import Model

TINY = 1e-12  # the kernel's guard on lengths
TINY2 = 1e-30  # the kernel's guard on squared panel normals
NARROW = 8  # JAX batches of at most this many lanes index (3, N, B) at once (``rows``)
DENSE_NODES = 64  # JAX steps bodies of at most this many nodes by incidence matrices


def to_soa(xp, q):
    """Return node vectors (..., N, 3) as (3, N, B), the batch axes flattened into B (1 for
    a single candidate)."""
    n = q.shape[-2]
    return xp.transpose(xp.reshape(q, (-1, n, 3)), (2, 1, 0))


def from_soa(xp, q, batch_shape: tuple):
    """Return (3, N, B) node vectors as (*batch_shape, N, 3)."""
    return xp.reshape(xp.transpose(q, (2, 1, 0)), (*batch_shape, q.shape[1], 3))


def col(q):
    """Return a per-item model array (K,) as a column (K, 1) that broadcasts over the batch."""
    return q[:, None]


@lru_cache(maxsize=256)
def _incidence(targets: bytes, n: int) -> np.ndarray:
    t = np.frombuffer(targets, dtype=np.int64)
    order = np.argsort(t, kind="stable")
    counts = np.bincount(t, minlength=n)
    table = np.full((n, max(int(counts.max(initial=0)), 1)), t.size, dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    for node in range(n):
        table[node, : counts[node]] = order[starts[node] : starts[node] + counts[node]]
    table.setflags(write=False)
    return table


def incidence(targets: np.ndarray, n: int) -> np.ndarray:
    """Return the (n, D) table of which entries of ``targets`` (node indices) land on each
    node, in their order, padded with len(targets) (the zero row ``gather_sum`` appends)."""
    return _incidence(np.ascontiguousarray(targets, dtype=np.int64).tobytes(), n)


def per_component(xp, q) -> bool:
    """Return whether node rows of q (3, N, B) are gathered and summed one component at a
    time: in JAX for a wide batch, where indexing (3, N, B) at once puts the index axis first
    and costs XLA a transpose back per step; a narrow batch (the gradient's few start states)
    is indexed at once, a third as many fusions for XLA to compile (the rollout's run time
    there is per-fusion overhead, not the transpose)."""
    return xp is np or q.shape[-1] > NARROW


def dense(xp, n: int) -> bool:
    """Return whether a body of n nodes reads and spreads its node rows by products with
    constant incidence matrices (``node_matrix``) rather than by gathers and scatter-adds: in
    JAX for a small body, where a product of a (K, n) matrix by n rows of B lanes is a dense
    kernel that XLA's CPU backend runs faster than the gathers at every batch of 32 lanes or
    more, the step has fewer fusions to compile, and its reverse pass is matrix products
    again. NumPy always gathers, so that the float64 reference sums in order."""
    return xp is not np and n <= DENSE_NODES


@lru_cache(maxsize=512)
def _node_matrix(nodes: bytes, weights: bytes, shape: tuple, n: int, dtype: str) -> np.ndarray:
    idx = np.frombuffer(nodes, dtype=np.int64).reshape(shape)
    w = np.frombuffer(weights, dtype=np.float64).reshape(shape)
    out = np.zeros((shape[0], n), dtype=np.float64)
    np.add.at(out, (np.arange(shape[0])[:, None], idx), w)
    out = out.astype(dtype)
    out.setflags(write=False)
    return out


def node_matrix(nodes: np.ndarray, weights, n: int, dtype) -> np.ndarray:
    """Return the (K, n) matrix whose row k holds ``weights[k, c]`` at column ``nodes[k, c]``
    (summed where a node repeats): the weighted sums of each row of ``nodes`` (K, C) as one
    product with node rows (n, B); its transpose spreads K values back onto the nodes."""
    idx = np.ascontiguousarray(nodes, dtype=np.int64)
    w = np.ascontiguousarray(np.broadcast_to(weights, idx.shape), dtype=np.float64)
    return _node_matrix(idx.tobytes(), w.tobytes(), idx.shape, n, np.dtype(dtype).str)


def _product(xp, matrix: np.ndarray, q):
    """Return matrix (K, n) times node rows q (n, B), or each component of q (3, n, B), at
    full float32 precision on every device."""
    from jax import lax

    return xp.matmul(matrix, q, precision=lax.Precision.HIGHEST)


def edges(xp, q, a: np.ndarray, b: np.ndarray):
    """Return q[b] - q[a] for node rows q (3, N, B): each edge's vector from node a to b."""
    if dense(xp, q.shape[-2]):
        ends = np.stack([b, a], axis=1)
        return _product(xp, node_matrix(ends, np.array([1.0, -1.0]), q.shape[-2], q.dtype), q)
    return rows(xp, q, b) - rows(xp, q, a)


def onto_ends(xp, f, a: np.ndarray, b: np.ndarray, n: int):
    """Return (3, n, B): each edge's force f (3, M, B) on its node a, and -f on its node b."""
    if dense(xp, n):
        ends = np.stack([a, b], axis=1)
        return _product(xp, node_matrix(ends, np.array([1.0, -1.0]), n, f.dtype).T, f)
    return gather_sum(xp, xp.concatenate([f, -f], axis=1), np.concatenate([a, b]), n)


def onto_corners(xp, s, d, nodes: np.ndarray, w: np.ndarray, n: int):
    """Return (3, n, B): the forces s * d (s (K, B), d (3, K, B)) of K panels or fins shared
    by their corners ``nodes`` (K, C) in the shares ``w`` (K, C)."""
    if dense(xp, n):
        return _product(xp, node_matrix(nodes, w, n, d.dtype).T, s * d)
    shares = [(w[:, c, None] * s) * d for c in range(nodes.shape[1])]
    return gather_sum(xp, xp.concatenate(shares, axis=1), nodes.T.reshape(-1), n)


def rows(xp, q, idx):
    """Return the node rows ``idx`` (an index array of any shape) of q (N, B) or (3, N, B)."""
    if q.ndim == 2:
        return q[idx]
    if not per_component(xp, q):
        return q[:, idx]
    return xp.stack([q[c][idx] for c in range(q.shape[0])])


def gather_sum(xp, values, targets: np.ndarray, n: int):
    """Return (3, n, B): the rows of ``values`` (3, M, B) summed onto the nodes ``targets`` (M,)
    they belong to: a scatter-add per component in JAX, the incidence table's sum in NumPy."""
    zeros = xp.zeros((values.shape[0], n, values.shape[-1]), dtype=values.dtype)
    if targets.size == 0:
        return zeros
    if not per_component(xp, values):  # JAX, a narrow batch: one scatter-add
        return zeros.at[:, targets].add(values)
    if xp is not np:  # JAX: one scatter-add of whole B-lane rows per component, no padded table
        return xp.stack([zeros[c].at[targets].add(values[c]) for c in range(values.shape[0])])
    table = incidence(targets, n)
    padded = xp.concatenate([values, xp.zeros_like(values[:, :1])], axis=1)
    return xp.sum(rows(xp, padded, table), axis=2)


def _corners(xp, q, nodes: np.ndarray, w: np.ndarray):
    """Return the weighted sums over each row of ``nodes`` (K, C) of q (..., N, B) with
    weights ``w`` (K, C): a panel's or a fin's mean of its corners, (..., K, B)."""
    if dense(xp, q.shape[-2]):
        return _product(xp, node_matrix(nodes, w, q.shape[-2], q.dtype), q)
    return xp.sum(rows(xp, q, nodes) * w[..., None], axis=-2)


def _safe_sqrt(xp, s):
    """Return sqrt(s) for s >= 0 with a zero (not NaN) gradient at s = 0."""
    pos = s > 0
    return xp.where(pos, xp.sqrt(xp.where(pos, s, 1.0)), 0.0)


def _dot(xp, a, b):
    """Return the dot products over the component axis 0 of (3, ...) arrays."""
    return xp.sum(a * b, axis=0)


def _cross(xp, a, b):
    return xp.stack(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def _norm(xp, a):
    return _safe_sqrt(xp, _dot(xp, a, a))


def _unit(xp, a):
    return a / (_norm(xp, a) + TINY)


def springs(xp, m: Model, x, v, a, idx):
    """Return the nodal forces (3, N, B) of the springs with indices ``idx`` (NumPy, fixed
    when JAX traces)."""
    sa, sb = m.spring_a[idx], m.spring_b[idx]
    d = edges(xp, x, sa, sb)
    length = _norm(xp, d) + TINY
    u = d / length
    relaxed = col(m.relaxed[idx])
    rest = relaxed + a[m.spring_col[idx]] * (col(m.contracted[idx]) - relaxed)
    edot = _dot(xp, edges(xp, v, sa, sb), u)
    fs = (col(m.stiffness[idx]) * (length - rest) + col(m.spring_damping[idx]) * edot) * u
    return onto_ends(xp, fs, sa, sb, x.shape[1])


def weight(xp, m: Model, x):
    """Return gravity and, below the water level, buoyancy (N, B) along y."""
    g, mass = m.gravity, col(m.mass)
    return xp.where(x[1] < m.water_level, mass * (g * m.buoyancy - g), -mass * g)


def water(xp, m: Model, x, v):
    """Return the water's reaction on the surface panels (Tu & Terzopoulos), shared by each
    panel's nodes: it opposes a panel's outward normal velocity, c * drag * A * |v| (n.v),
    and at most stops the panel's normal motion in one step."""
    w, panels = m.panel_weights, m.panels  # (P, 4)
    nrm = _cross(
        xp, edges(xp, x, panels[:, 0], panels[:, 2]), edges(xp, x, panels[:, 1], panels[:, 3])
    )  # 2 A n
    nn = _dot(xp, nrm, nrm) + TINY2
    vm = _corners(xp, v, panels, w)
    q = xp.maximum(_dot(xp, nrm, vm), 0.0)
    vv = _dot(xp, vm, vm)
    lim = 0.5 * m.water_drag * col(m.panel_drag) * _safe_sqrt(xp, nn * vv)
    lim = xp.minimum(lim, col(m.panel_mass_dt))
    wet = _corners(xp, x[1], panels, w) < m.water_level
    mag = xp.where(wet, q / nn * lim, 0.0)
    return onto_corners(xp, -mag, nrm, panels, w, x.shape[1])


def fins(xp, m: Model, x, v, a):
    """Return the fins' forces: flat plates at their actuator's angle to the body, pushed on
    by the water (at most stopping their normal motion in one step)."""
    fwd = _unit(xp, edges(xp, x, m.fin_forward[:, 1], m.fin_forward[:, 0]))
    span = edges(xp, x, m.fin_span[:, 1], m.fin_span[:, 0])
    span = _unit(xp, span - _dot(xp, span, fwd) * fwd)
    up = _cross(xp, fwd, span)
    lo, hi = col(m.fin_angle[:, 0]), col(m.fin_angle[:, 1])
    ang = lo + a[m.fin_actuator] * (hi - lo)
    nrm = xp.cos(ang) * up + xp.sin(ang) * fwd
    nodes = np.maximum(m.fin_nodes, 0)  # padding: node 0 at weight 0
    wts = m.fin_weights  # (K, 4)
    vm = _corners(xp, v, nodes, wts)
    cy = _corners(xp, x[1], nodes, wts)
    vn = _dot(xp, nrm, vm)
    cap = col(m.fin_mass) * xp.abs(vn) / m.dt
    mag = xp.clip(m.water_drag * col(m.fin_area) * _norm(xp, vm) * vn, -cap, cap)
    mag = xp.where(cy < m.water_level, mag, 0.0)
    return onto_corners(xp, -mag, nrm, nodes, wts, x.shape[1])


def ground(xp, m: Model, x, v, f_other):
    """Return the floor's forces: a penalty normal force at y = 0 and directional Coulomb
    friction along the local body axis, solved against the velocity ``f_other`` would give."""
    dt, mass = m.dt, col(m.mass)
    pen = -x[1]
    normal = m.floor_stiffness * pen - m.floor_damping * v[1]
    normal = xp.where((pen > 0) & (normal > 0), normal, 0.0)
    axis = edges(xp, x, m.axis_back, m.axis_front)
    length = _safe_sqrt(xp, axis[0] * axis[0] + axis[2] * axis[2]) + TINY
    tx, tz = axis[0] / length, axis[2] / length
    px = v[0] + dt * f_other[0] / mass
    pz = v[2] + dt * f_other[2] / mass
    vf = px * tx + pz * tz
    vl = pz * tx - px * tz
    mu = xp.where(vf > 0, m.friction_forward, m.friction_backward)
    ff = xp.minimum(mu * normal, mass * xp.abs(vf) / dt)
    fl = xp.minimum(m.friction_lateral * normal, mass * xp.abs(vl) / dt)
    ff = xp.where(vf > 0, -ff, ff)
    fl = xp.where(vl > 0, -fl, fl)
    return xp.stack([ff * tx - fl * tz, normal, ff * tz + fl * tx])


def forces_soa(xp, m: Model, x, v, a, idx):
    """Return the total nodal forces (3, N, B) with the springs ``idx`` (the step passes the
    slow ones; every other term in full)."""
    f = springs(xp, m, x, v, a, idx)
    f = xp.stack([f[0], f[1] + weight(xp, m, x), f[2]])
    if m.water:
        f = f + water(xp, m, x, v)
        if m.fin_area.shape[0]:
            f = f + fins(xp, m, x, v, a)
    if m.floor:
        f = f + ground(xp, m, x, v, f)
    return f


def step_soa(xp, m: Model, x, v, a):
    """Return (x, v) (3, N, B) after one semi-implicit Euler step of dt (nodal damping
    implicit): every force but the stiff springs kicks once, then those drive ``m.substeps``
    sub-steps of the nodes they touch (impulse multirate, ``multirate.split``); the other
    nodes keep the one step, as without a split."""
    real = m.mass.dtype.type
    hm = col(m.dt / m.mass)
    damp = 1.0 / (1.0 + hm * col(m.node_damping))
    f = forces_soa(xp, m, x, v, a, m.slow_springs)
    vs = (v + hm * f) * damp
    xs = x + m.dt * vs
    if m.fast_springs.shape[0] == 0:
        return xs, vs
    fast = np.zeros((m.mass.shape[0], 1), dtype=bool)  # nodes a stiff spring touches
    fast[m.fast_nodes] = True
    x, v = xp.where(fast, x, xs), xp.where(fast, v + hm * f, vs)  # a kick, then sub-steps
    h = real(m.dt) / real(m.substeps)
    hms = col(h / m.mass)
    damps = 1.0 / (1.0 + hms * col(m.node_damping))

    def substep(x, v):
        vq = (v + hms * springs(xp, m, x, v, a, m.fast_springs)) * damps
        return xp.where(fast, x + h * vq, x), xp.where(fast, vq, v)

    return repeat(xp, m.substeps, substep, (x, v))


def repeat(xp, n: int, body, carry: tuple):
    """Return ``body(*carry)`` applied ``n`` times: a Python loop in NumPy, one ``fori_loop``
    in JAX, so that the traced step holds the sub-step once: fewer fusions to compile, at no
    cost in run time (the shark: about 3.2 us of CPU a lane-step, 3.4 with the n sub-steps
    traced one after another)."""
    if xp is np:
        for _ in range(n):
            carry = body(*carry)
        return carry
    from jax import lax

    return lax.fori_loop(0, n, lambda _, c: body(*c), carry)


def forces(xp, m: Model, x, v, a, idx):
    """Return ``forces_soa`` for node vectors (..., N, 3) and activations (..., A), as
    (..., N, 3)."""
    f = forces_soa(xp, m, to_soa(xp, x), to_soa(xp, v), _acts(xp, a), idx)
    return from_soa(xp, f, x.shape[:-2])


def step(xp, m: Model, x, v, a):
    """Return ``step_soa`` for node vectors (..., N, 3) and activations (..., A), as
    (x, v) (..., N, 3)."""
    xs, vs = step_soa(xp, m, to_soa(xp, x), to_soa(xp, v), _acts(xp, a))
    return from_soa(xp, xs, x.shape[:-2]), from_soa(xp, vs, x.shape[:-2])


def _acts(xp, a):
    """Return activations (..., A) as (A, B)."""
    return xp.transpose(xp.reshape(a, (-1, a.shape[-1])))
