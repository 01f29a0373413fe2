"""The force law and the step, written once for NumPy and JAX (an array-module argument ``xp``).

The law works in a node-major layout with the batch innermost: positions and velocities
are (N, 3, B) (the x, y and z components of N nodes for B candidates) and activations
(A, B), so that every term is elementwise work over contiguous rows of B lanes, which NumPy
and XLA vectorise, and a node's three components are one row of 3B floats: a product of a
(K, N) matrix by the nodes, or a gather of node rows, serves all three components at once
without transposing the state. ``to_soa``/``from_soa`` convert from and to the (..., N, 3)
arrays the rest of the package holds; ``forces`` and ``step`` take those. The NumPy reference
steps a batch in float64, the JAX mirror a batch (or one candidate, B = 1) in float32. The
terms are those of the Numba kernel (``kernel_terms``), its hand-tuned twin: springs and
muscles, gravity and buoyancy, water panels whose force can at most stop a panel's normal
motion in one step, fins, a penalty floor with implicit directional Coulomb friction, implicit
nodal damping, semi-implicit Euler with the stiff springs sub-stepped after one kick of
everything else (``multirate.split``). Conformance tests hold the three equal.

Nothing is written in place. A term reads node rows (``edges``, ``_corners``) and spreads its
contributions back onto the nodes (``onto_ends``, ``onto_corners``: spring ends, panel and fin
corners) in one of two forms, chosen by ``dense`` (a spring's two ends are gathered in both
on a wide batch: ``edges``). JAX steps a small body by products with
constant incidence matrices built from the model's indices (``node_matrix``: +1/-1 per
spring, a panel's or fin's corner shares), a few dense products a step. Otherwise node rows
are gathered and contributions summed by ``gather_sum``: in JAX one scatter-add of whole node
rows, in NumPy through a padded incidence table built once from the model's constant indices
(``incidence``), summed in order (in XLA that table's gather and reduction cost twice the
scatter). Dot products
over xyz are written on the x, y and z components of vectors that a product (or a gather)
has just made (``_dot3``): XLA fuses them into the elementwise work that reads them, where a
reduction over the component axis was a kernel of its own; a term reads all it needs of the
positions in one product where it can (the panels' diagonals and centres, the fins' axes and
centres), as each product is a kernel too.
Square roots and unit vectors are guarded (the double-``where`` trick) so that JAX gradients
stay finite at rest, where velocities are exactly zero.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from zoetic.physics.model import Model

TINY = 1e-12  # the kernel's guard on lengths
TINY2 = 1e-30  # the kernel's guard on squared panel normals
DENSE_NODES = 64  # JAX steps bodies of at most this many nodes by incidence matrices
WIDE = 8  # lanes from which JAX gathers a spring's ends even in the matrix form (``edges``)


def to_soa(xp, q):
    """Return node vectors (..., N, 3) as (N, 3, B), the batch axes flattened into B (1 for
    a single candidate)."""
    n = q.shape[-2]
    return xp.transpose(xp.reshape(q, (-1, n, 3)), (1, 2, 0))


def from_soa(xp, q, batch_shape: tuple):
    """Return (N, 3, B) node vectors as (*batch_shape, N, 3)."""
    return xp.reshape(xp.transpose(q, (2, 0, 1)), (*batch_shape, q.shape[0], 3))


def col(q):
    """Return per-item values with an axis after the first: a model array (K,) as a column
    (K, 1) that broadcasts over the batch, values (K, B) or (K, 1) as (K, 1, B) or (K, 1, 1)
    that scale vectors (K, 3, B)."""
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


def dense(xp, n: int) -> bool:
    """Return whether a body of n nodes reads (but ``edges`` on a wide batch) and spreads its
    node rows by products with constant incidence matrices (``node_matrix``) rather than by
    gathers and scatter-adds: in JAX for a small body, where a product of a (K, n) matrix by n
    rows of B lanes is a dense kernel that XLA's CPU backend runs faster than the gathers at
    every batch of 32 lanes or more, the step has fewer fusions to compile, and its reverse
    pass is matrix products again. NumPy always gathers, so that the float64 reference sums in
    order."""
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
    """Return matrix (K, n) times node rows q (n, B) or (n, 3, B), at full float32 precision
    on every device."""
    from jax import lax

    return xp.tensordot(matrix, q, axes=1, precision=lax.Precision.HIGHEST)


def edges(xp, q, a: np.ndarray, b: np.ndarray):
    """Return q[b] - q[a] for node rows q (N, 3, B): each edge's vector from node a to b.

    Gathered, but for a narrow batch in the product form: on a batch of ``WIDE`` lanes or more
    XLA fuses the two row gathers into the spring's elementwise work, where an incidence
    product (S x N multiply-adds for 2S rows read) is a kernel of dense arithmetic (a tenth of
    the shark's step, a fifth of the ray's); a narrow batch (the gradient's few start states)
    keeps the product, whose reverse pass compiles to fewer fusions than the gathers'
    scatters. The two agree to float32 rounding (``test_law_dense``)."""
    if dense(xp, q.shape[0]) and q.shape[-1] < WIDE:
        ends = np.stack([b, a], axis=1)
        return _product(xp, node_matrix(ends, np.array([1.0, -1.0]), q.shape[0], q.dtype), q)
    return rows(xp, q, b) - rows(xp, q, a)


def onto_ends(xp, f, a: np.ndarray, b: np.ndarray, n: int):
    """Return (n, 3, B): each edge's force f (M, 3, B) on its node a, and -f on its node b."""
    if dense(xp, n):
        ends = np.stack([a, b], axis=1)
        return _product(xp, node_matrix(ends, np.array([1.0, -1.0]), n, f.dtype).T, f)
    return gather_sum(xp, xp.concatenate([f, -f]), np.concatenate([a, b]), n)


def onto_corners(xp, s, d, nodes: np.ndarray, w: np.ndarray, n: int):
    """Return (n, 3, B): the forces s * d (s (K, B), d (K, 3, B)) of K panels or fins shared
    by their corners ``nodes`` (K, C) in the shares ``w`` (K, C)."""
    if dense(xp, n):
        return _product(xp, node_matrix(nodes, w, n, d.dtype).T, _scaled(xp, s, d))
    shares = [col(w[:, c, None] * s) * d for c in range(nodes.shape[1])]
    return gather_sum(xp, xp.concatenate(shares), nodes.T.reshape(-1), n)


def rows(xp, q, idx):
    """Return the node rows ``idx`` (an index array of any shape) of q (N, B) or (N, 3, B)."""
    return q[idx]


def gather_sum(xp, values, targets: np.ndarray, n: int):
    """Return (n, 3, B): the rows of ``values`` (M, 3, B) summed onto the nodes ``targets`` (M,)
    they belong to: one scatter-add of whole node rows in JAX, the incidence table's sum in
    NumPy."""
    zeros = xp.zeros((n, *values.shape[1:]), dtype=values.dtype)
    if targets.size == 0:
        return zeros
    if xp is not np:
        return zeros.at[targets].add(values)
    table = incidence(targets, n)
    padded = xp.concatenate([values, xp.zeros_like(values[:1])])
    return xp.sum(rows(xp, padded, table), axis=1)


def _corners(xp, q, nodes: np.ndarray, w: np.ndarray):
    """Return the weighted sums over each row of ``nodes`` (K, C) of node rows q (N, B) or
    (N, 3, B) with weights ``w`` (K, C): a panel's or a fin's mean of its corners, (K, B) or
    (K, 3, B)."""
    if dense(xp, q.shape[0]):
        return _product(xp, node_matrix(nodes, w, q.shape[0], q.dtype), q)
    shares = np.reshape(w, w.shape + (1,) * (q.ndim - 1))
    return xp.sum(rows(xp, q, nodes) * shares, axis=1)


def _safe_sqrt(xp, s):
    """Return sqrt(s) for s >= 0 with a zero (not NaN) gradient at s = 0."""
    pos = s > 0
    return xp.where(pos, xp.sqrt(xp.where(pos, s, 1.0)), 0.0)


def _xyz(xp, q):
    """Return the x, y and z components (K, B) of vectors q (K, 3, B): one split, whose
    reverse pass is one concatenation (three slices' is three pads summed, each a kernel
    of its own with the work that makes its component copied into it)."""
    return tuple(xp.squeeze(c, axis=1) for c in xp.split(q, 3, axis=1))


def springs(xp, m: Model, x, v, a, idx, nodes=None):
    """Return the nodal forces (N, 3, B) of the springs with indices ``idx`` (NumPy, fixed
    when JAX traces) on node rows x, v of every node, or of the sorted ``nodes`` only (their
    forces (len(nodes), 3, B); the springs must join those nodes)."""
    sa, sb = m.spring_a[idx], m.spring_b[idx]
    if nodes is not None:
        sa, sb = np.searchsorted(nodes, sa), np.searchsorted(nodes, sb)
    d = edges(xp, x, sa, sb)
    d3 = _xyz(xp, d)
    length = _safe_sqrt(xp, _dot3(d3, d3)) + TINY
    relaxed = col(m.relaxed[idx])
    rest = relaxed + a[m.spring_col[idx]] * (col(m.contracted[idx]) - relaxed)
    edot = _dot3(_xyz(xp, edges(xp, v, sa, sb)), d3) / length
    tension = col(m.stiffness[idx]) * (length - rest) + col(m.spring_damping[idx]) * edot
    fs = _scaled(xp, tension / length, d)
    return onto_ends(xp, fs, sa, sb, x.shape[0])


def weight(xp, m: Model, x):
    """Return gravity and, below the water level, buoyancy (N, B) along y."""
    g, mass = m.gravity, col(m.mass)
    return xp.where(x[:, 1] < m.water_level, mass * (g * m.buoyancy - g), -mass * g)


def water(xp, m: Model, x, v):
    """Return the water's reaction on the surface panels (Tu & Terzopoulos), shared by each
    panel's nodes: it opposes a panel's outward normal velocity, c * drag * A * |v| (n.v),
    and at most stops the panel's normal motion in one step."""
    w, panels = m.panel_weights, m.panels  # (P, 4)
    p = panels.shape[0]
    pad = np.zeros((p, 2), dtype=panels.dtype)
    diff = np.broadcast_to(np.r_[1.0, -1.0, 0.0, 0.0], (2 * p, 4))
    read = _corners(
        xp,
        x,
        np.concatenate([np.c_[panels[:, [2, 0]], pad], np.c_[panels[:, [3, 1]], pad], panels]),
        np.concatenate([diff, w]),
    )  # (3P, 3, B): each panel's two diagonals and its centre
    diagonal, other, centre = xp.split(read, 3)
    n3 = _cross3(_xyz(xp, diagonal), _xyz(xp, other))  # 2 A n
    vm3 = _xyz(xp, _corners(xp, v, panels, w))
    nn = _dot3(n3, n3) + TINY2
    q = xp.maximum(_dot3(n3, vm3), 0.0)
    vv = _dot3(vm3, vm3)
    lim = 0.5 * m.water_drag * col(m.panel_drag) * _safe_sqrt(xp, nn * vv)
    lim = xp.minimum(lim, col(m.panel_mass_dt))
    wet = centre[:, 1] < m.water_level
    mag = xp.where(wet, q / nn * lim, 0.0)
    return onto_corners(xp, -mag, xp.stack(n3, axis=1), panels, w, x.shape[0])


def fins(xp, m: Model, x, v, a):
    """Return the fins' forces: flat plates at their actuator's angle to the body, pushed on
    by the water (at most stopping their normal motion in one step).

    A fin's axes and centre are read in one product and its velocity in another; the rest is
    written on x, y and z components, so that XLA fuses a fin's few floats per lane into a
    handful of kernels."""
    k = m.fin_area.shape[0]
    nodes = np.maximum(m.fin_nodes, 0)  # padding: node 0 at weight 0
    wts = m.fin_weights  # (K, 4)
    pair = np.zeros((k, nodes.shape[1] - 2), dtype=nodes.dtype)
    diff = np.broadcast_to(np.r_[1.0, -1.0, np.zeros(nodes.shape[1] - 2)], (2 * k, nodes.shape[1]))
    read = _corners(
        xp,
        x,
        np.concatenate([np.c_[m.fin_forward, pair], np.c_[m.fin_span, pair], nodes]),
        np.concatenate([diff, wts]),
    )  # (3K, 3, B): each fin's forward axis, span axis and centre
    forward, span, centre = xp.split(read, 3)
    fwd = _unit3(xp, _xyz(xp, forward))
    span = _xyz(xp, span)
    along = _dot3(span, fwd)
    span = _unit3(xp, tuple(s - along * f for s, f in zip(span, fwd, strict=True)))
    up = _cross3(fwd, span)
    lo, hi = col(m.fin_angle[:, 0]), col(m.fin_angle[:, 1])
    ang = lo + a[m.fin_actuator] * (hi - lo)
    cos, sin = xp.cos(ang), xp.sin(ang)
    nrm = tuple(cos * u + sin * f for u, f in zip(up, fwd, strict=True))
    vm = _xyz(xp, _corners(xp, v, nodes, wts))
    vn = _dot3(nrm, vm)
    cap = col(m.fin_mass) * xp.abs(vn) / m.dt
    mag = xp.clip(m.water_drag * col(m.fin_area) * _safe_sqrt(xp, _dot3(vm, vm)) * vn, -cap, cap)
    mag = xp.where(centre[:, 1] < m.water_level, -mag, 0.0)
    return onto_corners(xp, mag, xp.stack(nrm, axis=1), nodes, wts, x.shape[0])


def _scaled(xp, s, d):
    """Return the vectors s d (K, 3, B) for scales s (K, B) and vectors d (K, 3, B). On a
    narrow batch (the gradient's start states) a stack of the three components' products,
    whose reverse pass is elementwise work: a scale broadcast over the components has a sum
    over them in its reverse, a kernel of its own (docs/performance.md, "The gradient's cold
    compile, second look"). A wide batch keeps the broadcast, which runs faster there."""
    if s.shape[-1] < WIDE:
        return xp.stack([s * c for c in _xyz(xp, d)], axis=1)
    return col(s) * d


def _dot3(a, b):
    """Return the dot products of vectors given as their x, y and z components."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross3(a, b):
    """Return the cross product of vectors given as their x, y and z components."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _unit3(xp, a):
    """Return the unit vector of a vector given as its x, y and z components."""
    inverse = 1.0 / (_safe_sqrt(xp, _dot3(a, a)) + TINY)  # one division for three components
    return tuple(c * inverse for c in a)


def ground(xp, m: Model, x, v, f_other):
    """Return the floor's forces: a penalty normal force at y = 0 and directional Coulomb
    friction along the local body axis, solved against the velocity ``f_other`` would give."""
    dt, mass = m.dt, col(m.mass)
    (vx, vy, vz), (fx, _, fz) = _xyz(xp, v), _xyz(xp, f_other)
    pen = -x[:, 1]
    normal = m.floor_stiffness * pen - m.floor_damping * vy
    normal = xp.where((pen > 0) & (normal > 0), normal, 0.0)
    ax, _, az = _xyz(xp, edges(xp, x, m.axis_back, m.axis_front))
    length = _safe_sqrt(xp, ax * ax + az * az) + TINY
    tx, tz = ax / length, az / length
    px = vx + dt * fx / mass
    pz = vz + dt * fz / mass
    vf = px * tx + pz * tz
    vl = pz * tx - px * tz
    mu = xp.where(vf > 0, m.friction_forward, m.friction_backward)
    ff = xp.minimum(mu * normal, mass * xp.abs(vf) / dt)
    fl = xp.minimum(m.friction_lateral * normal, mass * xp.abs(vl) / dt)
    ff = xp.where(vf > 0, -ff, ff)
    fl = xp.where(vl > 0, -fl, fl)
    return xp.stack([ff * tx - fl * tz, normal, ff * tz + fl * tx], axis=1)


def forces_soa(xp, m: Model, x, v, a, idx):
    """Return the total nodal forces (N, 3, B) with the springs ``idx`` (the step passes the
    slow ones; every other term in full)."""
    f = springs(xp, m, x, v, a, idx)
    fx, fy, fz = _xyz(xp, f)
    f = xp.stack([fx, fy + weight(xp, m, x), fz], axis=1)
    if m.water:
        f = f + water(xp, m, x, v)
        if m.fin_area.shape[0]:
            f = f + fins(xp, m, x, v, a)
    if m.floor:
        f = f + ground(xp, m, x, v, f)
    return f


def step_soa(xp, m: Model, x, v, a):
    """Return (x, v) (N, 3, B) after one semi-implicit Euler step of dt (nodal damping
    implicit): every force but the stiff springs kicks once, then those drive ``m.substeps``
    sub-steps of the nodes they touch (impulse multirate, ``multirate.split``); the other
    nodes keep the one step, as without a split."""
    real = m.mass.dtype.type
    hm = col(col(m.dt / m.mass))
    damp = 1.0 / (1.0 + hm * col(col(m.node_damping)))
    f = forces_soa(xp, m, x, v, a, m.slow_springs)
    vs = (v + hm * f) * damp
    xs = x + m.dt * vs
    if m.fast_springs.shape[0] == 0:
        return xs, vs
    nodes = m.fast_nodes  # sorted: the nodes a stiff spring touches, sub-stepped on their own
    x, v = rows(xp, x, nodes), rows(xp, v + hm * f, nodes)  # a kick, then sub-steps
    h = real(m.dt) / real(m.substeps)
    hms = col(col(h / m.mass[nodes]))
    damps = 1.0 / (1.0 + hms * col(col(m.node_damping[nodes])))

    def substep(x, v):
        vq = (v + hms * springs(xp, m, x, v, a, m.fast_springs, nodes)) * damps
        return x + h * vq, vq

    x, v = repeat(xp, m.substeps, substep, (x, v))
    fast = np.zeros((m.mass.shape[0], 1, 1), dtype=bool)
    fast[nodes] = True
    back = np.cumsum(fast.ravel()) - 1  # a fast node's row among ``nodes`` (others: masked)
    return xp.where(fast, rows(xp, x, back), xs), xp.where(fast, rows(xp, v, back), vs)


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
