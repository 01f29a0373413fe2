"""The differentiable path: a JAX mirror of the physics step, float32, on any device JAX sees.

The model is the one in ``reference.py`` and ``kernel.py``, term for term: springs and
muscles, gravity and buoyancy, water panels whose force can at most stop a panel's normal
motion in one step, fins, a penalty floor with implicit directional Coulomb friction, implicit
nodal damping and semi-implicit Euler. Everything here is a pure function of arrays; ``jit``
and ``vmap`` are applied only at the edge (``make_rollout``; losses in ``learning.gradient``),
brax-style.

Unlike the Numba kernel, a candidate that blows up is not reset to rest: its state simply
becomes large or non-finite, and ``blown_up`` tells which ones did. Square roots and unit
vectors are guarded (the double-``where`` trick) so that gradients stay finite at rest, where
velocities are exactly zero.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from zoetic.bodies import Body
from zoetic.errors import SimulationError
from zoetic.physics.media import Medium, get_medium
from zoetic.physics.multirate import split
from zoetic.physics.simulate import VMAX

F32 = jnp.float32
TINY = 1e-12  # the kernel's guard on lengths
TINY2 = 1e-30  # the kernel's guard on squared panel normals

class JaxBody(NamedTuple):
    """A Body's arrays as float32 / int32 JAX constants (fins vectorised with a node mask)."""

    mass: jax.Array
    node_damping: jax.Array
    spring_a: jax.Array
    spring_b: jax.Array
    stiffness: jax.Array
    spring_damping: jax.Array
    relaxed: jax.Array
    delta: jax.Array  # contracted - relaxed
    spring_actuator: jax.Array  # -1 mapped to 0, see muscle
    muscle: jax.Array  # 1 where the spring is a muscle, else 0
    panels: jax.Array
    panel_weights: jax.Array
    panel_drag: jax.Array  # each panel's coefficient, a factor on the medium's
    panel_mass_dt: jax.Array  # the panel's own mass divided by dt
    fin_nodes: jax.Array  # -1 mapped to 0, see fin_mask
    fin_mask: jax.Array
    fin_forward: jax.Array
    fin_span: jax.Array
    fin_area: jax.Array
    fin_angle: jax.Array
    fin_actuator: jax.Array
    fin_mass: jax.Array
    axis_front: jax.Array
    axis_back: jax.Array


def jax_body(body: Body, dt: float) -> JaxBody:
    """Return the body's arrays as JAX constants, in the precision the kernel uses."""
    f, i = np.float32, np.int32
    w = body.panel_weights
    mf_dt = np.einsum("pk,pk->p", body.mass[body.panels], w) / (w[:, 0] * dt)
    mask = body.fin_nodes >= 0
    fin_nodes = np.where(mask, body.fin_nodes, 0)
    arrays = dict(
        mass=body.mass.astype(f),
        node_damping=body.node_damping.astype(f),
        spring_a=body.spring_a.astype(i),
        spring_b=body.spring_b.astype(i),
        stiffness=body.stiffness.astype(f),
        spring_damping=body.spring_damping.astype(f),
        relaxed=body.relaxed.astype(f),
        delta=(body.contracted.astype(f) - body.relaxed.astype(f)),
        spring_actuator=np.maximum(body.spring_actuator, 0).astype(i),
        muscle=(body.spring_actuator >= 0).astype(f),
        panels=body.panels.astype(i),
        panel_weights=w.astype(f),
        panel_drag=body.panel_drag.astype(f),
        panel_mass_dt=mf_dt.astype(f),
        fin_nodes=fin_nodes.astype(i),
        fin_mask=mask.astype(f),
        fin_forward=body.fin_forward.astype(i),
        fin_span=body.fin_span.astype(i),
        fin_area=body.fin_area.astype(f),
        fin_angle=body.fin_angle.astype(f),
        fin_actuator=body.fin_actuator.astype(i),
        fin_mass=(body.mass[fin_nodes] * mask).sum(axis=1).astype(f),
        axis_front=body.axis_front.astype(i),
        axis_back=body.axis_back.astype(i),
    )
    return JaxBody(**{k: jnp.asarray(v) for k, v in arrays.items()})


def _safe_sqrt(s: jax.Array) -> jax.Array:
    """Return sqrt(s) for s >= 0 with a zero (not NaN) gradient at s = 0."""
    pos = s > 0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, s, 1.0)), 0.0)


def _norm(a: jax.Array) -> jax.Array:
    return _safe_sqrt(jnp.sum(a * a, axis=-1))


def _unit(a: jax.Array) -> jax.Array:
    return a / (_norm(a) + TINY)[..., None]


def _springs(m: JaxBody, x: jax.Array, v: jax.Array, a: jax.Array, idx) -> jax.Array:
    """Forces of the springs with indices ``idx`` (a NumPy array, fixed at trace time)."""
    sa, sb = m.spring_a[idx], m.spring_b[idx]
    d = x[sb] - x[sa]
    length = _norm(d) + TINY
    u = d / length[:, None]
    rest = m.relaxed[idx] + m.muscle[idx] * a[m.spring_actuator[idx]] * m.delta[idx]
    edot = jnp.sum((v[sb] - v[sa]) * u, axis=-1)
    fs = (m.stiffness[idx] * (length - rest) + m.spring_damping[idx] * edot)[:, None] * u
    return jnp.zeros_like(x).at[sa].add(fs).at[sb].add(-fs)


def _water(m: JaxBody, x: jax.Array, v: jax.Array, level: float, drag: float) -> jax.Array:
    w = m.panel_weights  # (P, 4)
    p = x[m.panels]  # (P, 4, 3)
    nrm = jnp.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])  # twice the area times the normal
    nn = jnp.sum(nrm * nrm, axis=-1) + TINY2
    vm = jnp.einsum("pkd,pk->pd", v[m.panels], w)
    q = jnp.maximum(jnp.sum(nrm * vm, axis=-1), 0.0)
    vv = jnp.sum(vm * vm, axis=-1)
    lim = jnp.minimum(0.5 * drag * m.panel_drag * _safe_sqrt(nn * vv), m.panel_mass_dt)
    wet = jnp.einsum("pk,pk->p", p[..., 1], w) < level
    mag = jnp.where(wet, q / nn * lim, 0.0)
    fp = -(w * mag[:, None])[..., None] * nrm[:, None, :]  # (P, 4, 3)
    return jnp.zeros_like(x).at[m.panels.reshape(-1)].add(fp.reshape(-1, 3))


def _fins(m: JaxBody, x, v, a, level: float, drag: float, dt: float) -> jax.Array:
    fwd = _unit(x[m.fin_forward[:, 0]] - x[m.fin_forward[:, 1]])
    span = x[m.fin_span[:, 0]] - x[m.fin_span[:, 1]]
    span = _unit(span - jnp.sum(span * fwd, -1, keepdims=True) * fwd)
    up = jnp.cross(fwd, span)
    lo, hi = m.fin_angle[:, 0], m.fin_angle[:, 1]
    ang = lo + a[m.fin_actuator] * (hi - lo)
    nrm = jnp.cos(ang)[:, None] * up + jnp.sin(ang)[:, None] * fwd
    share = 1.0 / jnp.sum(m.fin_mask, axis=1)  # (K,)
    wts = m.fin_mask * share[:, None]  # (K, 4)
    vm = jnp.einsum("kqd,kq->kd", v[m.fin_nodes], wts)
    cy = jnp.einsum("kq,kq->k", x[m.fin_nodes][..., 1], wts)
    vn = jnp.sum(nrm * vm, axis=-1)
    cap = m.fin_mass * jnp.abs(vn) / dt
    mag = jnp.clip(drag * m.fin_area * _norm(vm) * vn, -cap, cap)
    mag = jnp.where(cy < level, mag, 0.0)
    fq = -(wts * mag[:, None])[..., None] * nrm[:, None, :]  # (K, 4, 3); padding has 0 weight
    return jnp.zeros_like(x).at[m.fin_nodes.reshape(-1)].add(fq.reshape(-1, 3))


def _ground(m: JaxBody, x, v, f_other, med: Medium, dt: float) -> jax.Array:
    pen = -x[:, 1]
    normal = med.floor_stiffness * pen - med.floor_damping * v[:, 1]
    normal = jnp.where((pen > 0) & (normal > 0), normal, 0.0)
    t = _unit((x[m.axis_front] - x[m.axis_back])[:, jnp.array([0, 2])])
    tx, tz = t[:, 0], t[:, 1]
    px = v[:, 0] + dt * f_other[:, 0] / m.mass
    pz = v[:, 2] + dt * f_other[:, 2] / m.mass
    vf = px * tx + pz * tz
    vl = pz * tx - px * tz
    mu = jnp.where(vf > 0, med.friction_forward, med.friction_backward)
    ff = jnp.minimum(mu * normal, m.mass * jnp.abs(vf) / dt)
    fl = jnp.minimum(med.friction_lateral * normal, m.mass * jnp.abs(vl) / dt)
    ff = jnp.where(vf > 0, -ff, ff)
    fl = jnp.where(vl > 0, -fl, fl)
    return jnp.stack([ff * tx - fl * tz, normal, ff * tz + fl * tx], axis=-1)


def make_step(body: Body, medium: str | Medium | None = None, dt: float | None = None):
    """Return the pure step ``(x (N,3), v (N,3), a (A,)) -> (x, v)`` of one candidate."""
    med = get_medium(medium or body.medium)
    dt = float(dt or body.dt)
    m = jax_body(body, dt)
    water = med.water_drag > 0 and med.water_level > -1e8
    fins = water and len(body.fin_area) > 0
    g, level = med.gravity, med.water_level
    sp = split(body, dt)
    slow, fast, substeps = sp.slow_springs, sp.fast_springs, sp.substeps
    sn, fn = sp.slow_nodes, sp.fast_nodes
    hm = jnp.asarray(np.float32(dt) / body.mass.astype(np.float32), F32)[:, None]
    damp = 1.0 / (1.0 + hm * m.node_damping[:, None])
    h = np.float32(dt) / np.float32(substeps)
    hms = jnp.asarray(h / body.mass[fn].astype(np.float32), F32)[:, None]
    damps = 1.0 / (1.0 + hms * m.node_damping[fn][:, None])

    def advance(x, v, f):
        v = (v + hm * f) * damp
        return x + dt * v, v

    def step(x: jax.Array, v: jax.Array, a: jax.Array) -> tuple[jax.Array, jax.Array]:
        f = _springs(m, x, v, a, slow)
        wet = x[:, 1] < level
        fy = jnp.where(wet, m.mass * (g * med.buoyancy - g), -m.mass * g)
        f = f.at[:, 1].add(fy)
        if water:
            f = f + _water(m, x, v, level, med.water_drag)
        if fins:
            f = f + _fins(m, x, v, a, level, med.water_drag, dt)
        if med.floor:
            f = f + _ground(m, x, v, f, med, dt)
        if len(fast) == 0:
            return advance(x, v, f)
        xs, vs = advance(x, v, f)  # nodes no stiff spring touches: as without a split
        x, v = x.at[sn].set(xs[sn]), v.at[sn].set(vs[sn])
        v = v.at[fn].add(hm[fn] * f[fn])  # one kick, then the stiff springs' sub-steps
        for _ in range(substeps):  # (multirate.split)
            fq = _springs(m, x, v, a, fast)[fn]
            vq = (v[fn] + hms * fq) * damps
            x, v = x.at[fn].add(h * vq), v.at[fn].set(vq)
        return x, v

    return step


def rollout_fn(body: Body, medium=None, dt: float | None = None, record_every: int = 1):
    """Return the un-jitted single-candidate rollout ``(x0, v0, act (T,A)) -> (rec, x, v)``.

    ``rec`` holds the positions (R, N, 3) at steps 0, k, 2k, ... (R = T // k + 1) exactly as
    ``simulate`` records them; activations are clipped to [0, 1] as ``simulate`` does.
    """
    if record_every < 1:
        raise SimulationError("record_every must be at least 1")
    step = make_step(body, medium, dt)

    def inner(carry, a):
        return step(*carry, a), None

    def outer(carry, chunk):
        carry, _ = jax.lax.scan(inner, carry, chunk)
        return carry, carry[0]

    def rollout(x0: jax.Array, v0: jax.Array, act: jax.Array):
        act = jnp.clip(jnp.asarray(act, F32), 0.0, 1.0)
        x0, v0 = jnp.asarray(x0, F32), jnp.asarray(v0, F32)
        n_rec = act.shape[0] // record_every
        main = act[: n_rec * record_every].reshape(n_rec, record_every, act.shape[1])
        carry, recs = jax.lax.scan(outer, (x0, v0), main)
        carry, _ = jax.lax.scan(inner, carry, act[n_rec * record_every :])
        return jnp.concatenate([x0[None], recs]), carry[0], carry[1]

    return rollout


def make_rollout(body: Body, medium=None, dt: float | None = None, record_every: int = 1):
    """Return the jitted batch rollout ``(pos0 (B,N,3), vel0, act (B,T,A)) -> (rec, x, v)``.

    ``rec`` is (B, R, N, 3); the final positions and velocities are (B, N, 3). It compiles
    once per shape; a second call with the same shapes reuses the compiled code.
    """
    return jax.jit(jax.vmap(rollout_fn(body, medium, dt, record_every)))


def blown_up(positions: jax.Array, velocities: jax.Array) -> jax.Array:
    """Return a (B,) bool array: True where a candidate's state is non-finite or too fast."""
    speed2 = jnp.sum(velocities * velocities, axis=-1).max(axis=-1)
    finite = jnp.isfinite(positions).all(axis=(-1, -2)) & jnp.isfinite(speed2)
    return ~finite | (speed2 >= VMAX * VMAX)
