"""Gradient descent on a differentiable loss: Adam (optax) inside box bounds.

``learning.optimizers.gradient.Gradient`` is that method as an ordinary ask/tell optimizer: it
asks for one point at a time and needs the gradient there, which the evaluator supplies through
``value_and_grad`` (the task's objective rebuilt in JAX from the same term registry and
differentiated through the JAX simulator). ``make_loss`` builds a loss for custom objectives.

The parameters are optimised in bounds-normalised coordinates z = (x - lower) / (upper -
lower), so a learning rate of 0.02 moves each parameter by about 2% of its range per step
whatever its units. Each step clips the gradient's global norm (contact makes rare huge
gradients), takes an Adam step and projects z back onto [0, 1]. A step whose loss or gradient
is not finite changes nothing but z, which falls back halfway to the best point so far; a
failed evaluation never becomes the best. The whole optimizer state is a pytree of arrays,
so it saves to ``.npz`` and resumes exactly (``state_to_numpy`` / ``state_from_numpy``).
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from typing import TYPE_CHECKING, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optax

from zoetic.bodies import Body
from zoetic.control import Controller
from zoetic.control.jax_sampling import jax_table
from zoetic.physics.jax_backend import F32, rollout_fn
from zoetic.physics.jax_programs import StoredProgram, fingerprint
from zoetic.physics.simulate import rest_state
from zoetic.tasks.terms import BodyFrame, Signals, evaluate_terms

if TYPE_CHECKING:
    from zoetic.learning.objective import Evaluation, Objective

Loss = Callable[[jax.Array, jax.Array, jax.Array], jax.Array]

ValueAndGrad = Callable[[jax.Array], tuple[jax.Array, jax.Array]]


def compiler_options() -> dict | None:
    """Return the XLA options a gradient program compiles under; on a CPU XLA's elemental
    emitters instead of its MLIR fusion emitters (an MLIR context and pass pipeline for each
    of a gradient's some 260 small fusions: about twice the compile) and LLVM's level 1
    optimisations instead of 2 (less compile again). Either way the gradient runs as fast
    and agrees to float32 rounding (docs/performance.md, "The gradient's cold compile").
    Elsewhere none."""
    if jax.default_backend() != "cpu":
        return None
    return {"xla_cpu_use_fusion_emitters": False, "xla_backend_optimization_level": 1}


class GradientState(NamedTuple):
    """Everything a gradient run needs to resume: arrays only."""

    z: jax.Array  # (n,) current point in [0, 1]^n
    opt_state: optax.OptState  # Adam moments and the clip state
    lower: jax.Array  # (n,)
    scale: jax.Array  # (n,) upper - lower (1 where a bound is infinite)
    best_z: jax.Array  # (n,)
    best_f: jax.Array  # () inf until a finite loss is seen
    value: jax.Array  # () the loss at the last evaluated point
    grad_norm: jax.Array  # () its gradient's norm in z, before clipping
    step: jax.Array  # () int32: evaluations so far
    failures: jax.Array  # () int32: consecutive non-finite evaluations
    seed: jax.Array  # () int32: kept for the shared interface (Adam itself is deterministic)


class GradientDescent:
    """Adam with gradient-norm clipping and projection onto box bounds (minimisation)."""

    name = "gradient"

    def __init__(self, learning_rate: float = 0.02, max_grad_norm: float = 1.0) -> None:
        self.learning_rate = float(learning_rate)
        self.max_grad_norm = float(max_grad_norm)
        self.tx = optax.chain(
            optax.clip_by_global_norm(self.max_grad_norm), optax.adam(self.learning_rate)
        )
        self._update = jax.jit(self._update_impl)

    def init(self, x0, lower, upper, seed: int = 0) -> GradientState:
        """Return the starting state at x0 (clipped into the bounds)."""
        lo = np.asarray(lower, dtype=np.float64)
        hi = np.asarray(upper, dtype=np.float64)
        scale = np.where(np.isfinite(hi - lo) & (hi > lo), hi - lo, 1.0)
        lo = np.where(np.isfinite(lo), lo, 0.0)
        z0 = np.clip((np.asarray(x0, dtype=np.float64) - lo) / scale, 0.0, 1.0)
        z = jnp.asarray(z0, jnp.float32)
        return GradientState(
            z=z,
            opt_state=self.tx.init(z),
            lower=jnp.asarray(lo, jnp.float32),
            scale=jnp.asarray(scale, jnp.float32),
            best_z=z,
            best_f=jnp.asarray(jnp.inf, jnp.float32),
            value=jnp.asarray(jnp.nan, jnp.float32),
            grad_norm=jnp.asarray(jnp.nan, jnp.float32),
            step=jnp.asarray(0, jnp.int32),
            failures=jnp.asarray(0, jnp.int32),
            seed=jnp.asarray(seed, jnp.int32),
        )

    @staticmethod
    def x(state: GradientState) -> np.ndarray:
        """Return the current parameters in their own units."""
        return np.asarray(state.lower + state.scale * state.z, dtype=np.float64)

    @staticmethod
    def best_x(state: GradientState) -> np.ndarray:
        """Return the best parameters seen so far in their own units."""
        return np.asarray(state.lower + state.scale * state.best_z, dtype=np.float64)

    def step(self, state: GradientState, value_and_grad_fn: ValueAndGrad) -> GradientState:
        """Return the state after evaluating the loss and its gradient at x and one Adam step."""
        x = state.lower + state.scale * state.z
        f, g = value_and_grad_fn(x)
        return self._update(state, jnp.asarray(f, jnp.float32), jnp.asarray(g, jnp.float32))

    def _update_impl(self, state: GradientState, f: jax.Array, g: jax.Array) -> GradientState:
        gz = g * state.scale
        ok = jnp.isfinite(f) & jnp.all(jnp.isfinite(gz))
        gz_safe = jnp.where(ok, gz, 0.0)
        updates, opt_new = self.tx.update(gz_safe, state.opt_state, state.z)
        z_new = jnp.clip(optax.apply_updates(state.z, updates), 0.0, 1.0)
        z_back = 0.5 * (state.z + state.best_z)
        better = ok & (f < state.best_f)

        def keep(new: jax.Array, old: jax.Array) -> jax.Array:
            return jnp.where(ok, new, old)

        return state._replace(
            z=jnp.where(ok, z_new, z_back),
            opt_state=jax.tree_util.tree_map(keep, opt_new, state.opt_state),
            best_z=jnp.where(better, state.z, state.best_z),
            best_f=jnp.where(better, f, state.best_f),
            value=f,
            grad_norm=jnp.sqrt(jnp.sum(gz_safe * gz_safe)),
            step=state.step + 1,
            failures=jnp.where(ok, 0, state.failures + 1),
        )

    def state_to_numpy(self, state: GradientState) -> dict[str, np.ndarray]:
        """Return the state as named NumPy arrays (for ``np.savez`` or pickle)."""
        leaves = jax.tree_util.tree_leaves(state)
        return {f"leaf_{k:03d}": np.asarray(leaf) for k, leaf in enumerate(leaves)}

    def state_from_numpy(self, arrays: dict[str, np.ndarray]) -> GradientState:
        """Return the state saved by ``state_to_numpy`` (same optimizer settings)."""
        n = int(np.asarray(arrays["leaf_000"]).size)
        template = self.init(np.zeros(n), np.zeros(n), np.ones(n))
        treedef = jax.tree_util.tree_structure(template)
        keys = sorted(k for k in arrays if k.startswith("leaf_"))
        if len(keys) != treedef.num_leaves:
            raise ValueError(
                f"saved gradient state has {len(keys)} arrays, expected {treedef.num_leaves}"
            )
        return jax.tree_util.tree_unflatten(treedef, [jnp.asarray(arrays[k]) for k in keys])


def optimize_gradient(
    loss_fn: Callable[[jax.Array], jax.Array],
    x0,
    lower,
    upper,
    steps: int,
    seed: int = 0,
    callback: Callable[[int, GradientState], bool | None] | None = None,
    learning_rate: float = 0.02,
    max_grad_norm: float = 1.0,
    max_failures: int = 3,
) -> tuple[np.ndarray, float, list[dict]]:
    """Return (best x, best loss, history) after ``steps`` Adam steps on a JAX loss of x.

    ``loss_fn`` maps parameters (n,) to a scalar and must be differentiable by JAX; it is
    jitted here once. ``callback(step, state)`` runs after each step; returning True stops.
    The run also stops after ``max_failures`` consecutive non-finite evaluations.
    """
    opt = GradientDescent(learning_rate, max_grad_norm)
    vg = jax.jit(jax.value_and_grad(loss_fn), compiler_options=compiler_options())
    state = opt.init(x0, lower, upper, seed)
    history: list[dict] = []
    for k in range(int(steps)):
        state = opt.step(state, vg)
        history.append(
            {
                "step": k,
                "value": float(state.value),
                "best": float(state.best_f),
                "grad_norm": float(state.grad_norm),
            }
        )
        if callback is not None and callback(k, state):
            break
        if int(state.failures) >= max_failures:
            break
    # the last step's point has not been evaluated yet: score it too
    f_last = float(vg(state.lower + state.scale * state.z)[0])
    if np.isfinite(f_last) and f_last < float(state.best_f):
        return opt.x(state), f_last, history
    return opt.best_x(state), float(state.best_f), history


def make_loss(
    body: Body,
    ctrl: Controller,
    steps: int,
    objective: Loss,
    medium=None,
    dt: float | None = None,
    state=None,
    record_every: int | None = None,
):
    """Return the pure scalar loss ``p -> objective(rec (R,N,3), final x, final v)``.

    It samples the controller (``jax_table``), rolls one candidate out from ``state`` (a
    ``State`` with batch 1; default the rest pose) and applies the JAX objective. Wrap it in
    ``jax.jit(jax.value_and_grad(...))`` (or pass it to ``learning.gradient.optimize_gradient``).
    """
    dt = float(dt or body.dt)
    state = state or rest_state(body, 1)
    x0 = jnp.asarray(state.positions[0], F32)
    v0 = jnp.asarray(state.velocities[0], F32)
    table = jax_table(ctrl, steps, dt)
    roll = rollout_fn(body, medium, dt, record_every or steps)

    def loss(p: jax.Array) -> jax.Array:
        rec, x, v = roll(x0, v0, table(p))
        return objective(rec, x, v)

    return loss


def swim_distance(body: Body) -> Loss:
    """Return an objective: minus the distance the centre of mass moved along the heading."""
    w = jnp.asarray(body.mass / body.total_mass, F32)
    fwd = jnp.asarray(body.forward, F32)

    def objective(rec: jax.Array, x: jax.Array, v: jax.Array) -> jax.Array:
        return -jnp.dot(w @ x - w @ rec[0], fwd)

    return objective


def linear_map(objective: Objective) -> tuple[np.ndarray, np.ndarray]:
    """Return (L, c) with full coefficients = L @ free + c (the coupling is affine)."""
    n = objective.dimension
    c = objective.full_coefficients(np.zeros((1, n)))[0].ravel()
    cols = objective.full_coefficients(np.eye(n)).reshape(n, -1) - c
    return cols.T, c


def jax_objective(objective: Objective) -> Callable:
    """Return ``p -> (E, (E_u, E_v))`` in JAX for a free parameter vector p.

    The same terms (``tasks.terms``) as the NumPy objective, on the same records, from the
    same start states (the mean over them), through the JAX simulator.
    """
    from zoetic.learning.objective import control_energy_xp

    # only what objective_inputs lists (the stored program's key), so the key cannot miss one
    (task, body, medium, dt, steps, record_every, (L, c), basis, node_basis, shape, x0, v0, rows,
     h) = objective_inputs(objective)  # fmt: skip
    L, c = jnp.asarray(L, F32), jnp.asarray(c, F32)
    basis = jnp.asarray(basis, F32)  # (T, M)
    node_basis = jnp.asarray(node_basis, F32)
    x0 = jnp.asarray(x0, F32)  # (S, N, 3): one batch of starts
    v0 = jnp.asarray(v0, F32)
    roll = rollout_fn(body, medium, dt, record_every)
    frame = BodyFrame.of(body)
    n_rec = steps // record_every + 1
    times = np.arange(n_rec) * record_every * dt
    level = medium.water_level

    def evaluate(p):
        coef = jnp.reshape(L @ p + c, shape)
        act = jnp.clip(basis @ coef.T, 0.0, 1.0)
        rec, _, _ = roll(x0, v0, act)  # every start under the same activations
        a_rec = jnp.broadcast_to(act[rows][None], (rec.shape[0], *act[rows].shape))
        s = Signals(jnp, frame, rec, a_rec, times, level, task.horizon)
        values = evaluate_terms(jnp, s, task.terms)
        # the mean over the task's starts, as the NumPy objective
        e_v = sum(t.weight * jnp.mean(v) for t, v in zip(task.terms, values, strict=True))
        u = jnp.einsum("jm,am->aj", node_basis, coef)[None]
        e_u = control_energy_xp(jnp, u, h, task.nu1, task.nu2)[0]
        return task.mu1 * e_u + task.mu2 * e_v, (e_u, e_v)

    return evaluate


def objective_inputs(objective: Objective) -> tuple:
    """Return every value ``jax_objective`` builds its function from (its program's key)."""
    n_rec = objective.steps // objective.record_every + 1
    return (
        objective.task,
        objective.body,
        objective.medium,
        objective.dt,
        objective.steps,
        objective.record_every,
        linear_map(objective),
        objective._basis,
        objective._node_basis,
        objective.full_shape,
        objective.starts.positions,
        objective.starts.velocities,
        objective.record_rows(n_rec),
        objective.h,
    )


_COMPILED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # objective -> jitted E, dE


def value_and_grad(objective: Objective, X: np.ndarray) -> tuple[Evaluation, np.ndarray]:
    """Return the Evaluation of points (K, dim) and the gradient of E at each, (K, dim)."""
    from zoetic.learning.objective import Evaluation

    vg = _COMPILED.get(objective)
    if vg is None:
        ref = weakref.ref(objective)  # the cache's entry must not keep its key alive
        vg = StoredProgram(
            lambda: jax.value_and_grad(jax_objective(ref()), has_aux=True),
            fingerprint("value_and_grad", *objective_inputs(objective)),
            compiler_options(),
        )
        _COMPILED[objective] = vg
    out = [vg(jnp.asarray(x, F32)) for x in np.atleast_2d(X)]
    E = np.array([float(o[0][0]) for o in out])
    e_u = np.array([float(o[0][1][0]) for o in out])
    e_v = np.array([float(o[0][1][1]) for o in out])
    G = np.stack([np.asarray(o[1], dtype=np.float64) for o in out])
    failed = ~np.isfinite(E)
    return Evaluation(np.where(failed, np.inf, E), e_u, e_v, {}, failed), G
