"""``zoetic learn --optimizer gradient``: Adam on the task objective through the JAX simulator.

The task's E = mu1 E_u + mu2 E_v is rebuilt in JAX term by term (the same formulas as
``learn.objective``), the controller's parameters map linearly to its activation table (and
through the coupling, if any), and ``jax.value_and_grad`` differentiates the whole rollout.
A run directory looks like any other; its checkpoint also holds the optimizer's state.
"""

from __future__ import annotations

import io
import time
from pathlib import Path

import numpy as np

from zoetic.errors import RunDirError
from zoetic.io import atomic_write_bytes, read_toml, write_toml
from zoetic.learn.objective import Evaluation, Objective
from zoetic.learn.run import LearnConfig, Log, Run, Setup, build
from zoetic.tasks import Task, parse_task


def linear_map(objective: Objective) -> tuple[np.ndarray, np.ndarray]:
    """Return (L, c) with full coefficients = L @ free + c (the coupling is affine)."""
    n = objective.dimension
    c = objective.full_coefficients(np.zeros((1, n)))[0].ravel()
    cols = objective.full_coefficients(np.eye(n)).reshape(n, -1) - c
    return cols.T, c


def jax_objective(objective: Objective):
    """Return ``p -> (E, E_u, E_v)`` in JAX for a free parameter vector p."""
    import jax.numpy as jnp

    from zoetic.physics.jax_backend import rollout_fn
    from zoetic.physics.simulate import rest_state

    task, body = objective.task, objective.body
    L, c = (jnp.asarray(a, jnp.float32) for a in linear_map(objective))
    basis = jnp.asarray(objective._basis, jnp.float32)  # (T, M)
    node_basis = jnp.asarray(objective._node_basis, jnp.float32)
    shape = objective.full_shape
    start = objective.start if objective.start is not None else rest_state(body, 1)
    x0 = jnp.asarray(start.positions[0], jnp.float32)
    v0 = jnp.asarray(start.velocities[0], jnp.float32)
    roll = rollout_fn(body, objective.medium, objective.dt, objective.record_every)
    w = jnp.asarray(body.mass / body.total_mass, jnp.float32)
    h = objective.h

    def xz_unit(v):
        q = v[..., jnp.array([0, 2])]
        return q / jnp.sqrt(jnp.sum(q * q, axis=-1, keepdims=True) + 1e-12)

    def terms(rec):
        com = jnp.einsum("rnd,n->rd", rec, w)
        disp = com[-1] - com[0]
        h0 = xz_unit(rec[0, body.head] - com[0])
        left0 = jnp.array([-h0[1], h0[0]])
        along = jnp.dot(disp[jnp.array([0, 2])], h0)
        e_v = 0.0
        for t in task.terms:
            if t.kind == "distance_along_heading":
                v = along
            elif t.kind == "lateral_deviation":
                v = jnp.dot(disp[jnp.array([0, 2])], left0) ** 2
            elif t.kind == "depth_keeping":
                v = jnp.mean((com[:, 1] - com[0, 1]) ** 2)
            elif t.kind == "heading_change":
                hd = xz_unit(rec[:, body.head] - com)
                ang = jnp.unwrap(jnp.arctan2(hd[:, 1], hd[:, 0]))
                v = (ang[-1] - ang[0] - t.target) ** 2
            elif t.kind == "goal_distance2":
                goal = rec[0, body.head] + jnp.asarray(t.goal, jnp.float32)
                v = jnp.sum((rec[-1, body.head] - goal) ** 2)
            else:  # speed_deviation
                v = (along / task.horizon - t.target) ** 2
            e_v = e_v + t.weight * v
        return e_v

    def control_cost(coef):
        u = jnp.einsum("jm,am->aj", node_basis, coef)
        e = 0.0
        if task.nu1:
            e = e + task.nu1 / (2 * h**2) * jnp.sum(jnp.diff(u, axis=-1) ** 2)
        if task.nu2:
            d2 = u[:, 2:] - 2 * u[:, 1:-1] + u[:, :-2]
            e = e + task.nu2 / (2 * h**4) * jnp.sum(d2**2)
        return e

    def evaluate(p):
        coef = jnp.reshape(L @ p + c, shape)
        act = jnp.clip(basis @ coef.T, 0.0, 1.0)
        rec, _, _ = roll(x0, v0, act)
        e_v = terms(rec)
        e_u = control_cost(coef)
        return task.mu1 * e_u + task.mu2 * e_v, (e_u, e_v)

    return evaluate


class GradientOptimizer:
    """Adapts ``learn.gradient.GradientDescent`` to what a Run and its progress bar read."""

    name = "gradient"

    def __init__(self, objective: Objective, x0, lower, upper, seed: int, learning_rate=0.02):
        import jax

        from zoetic.learn.gradient import GradientDescent

        self.gd = GradientDescent(learning_rate=learning_rate)
        self.state = self.gd.init(x0, lower, upper, seed)
        self.x0 = np.asarray(x0, float)
        evaluate = jax_objective(objective)
        self._vg = jax.jit(jax.value_and_grad(evaluate, has_aux=True))
        self.last_aux = (np.nan, np.nan)

    def value_and_grad(self, x):
        (f, aux), g = self._vg(x)
        self.last_aux = tuple(float(a) for a in aux)
        return f, g

    def step(self) -> tuple[np.ndarray, float]:
        """Evaluate the loss and its gradient at the current point and take one Adam step."""
        x = self.gd.x(self.state)
        self.state = self.gd.step(self.state, self.value_and_grad)
        return x, float(self.state.value)

    @property
    def evaluations(self) -> int:
        return int(self.state.step)

    @property
    def best_f(self) -> float:
        return float(self.state.best_f)

    @property
    def best_x(self) -> np.ndarray:
        return self.gd.best_x(self.state)

    def done(self) -> bool:
        return False

    def status(self) -> dict:
        return {"|g|": float(self.state.grad_norm)}


class GradientRun(Run):
    """A Run whose optimizer is gradient descent through the differentiable simulator."""

    @staticmethod
    def _setup(config: LearnConfig, task: Task | None = None) -> Setup:
        base = build(LearnConfig(**{**config.to_dict(), "optimizer": "anneal"}), task)
        lo, hi = base.objective.bounds()
        opt = GradientOptimizer(base.objective, base.optimizer.x0, lo, hi, config.seed)
        return Setup(config, base.task, base.objective, opt, base.template)

    @classmethod
    def create(cls, out: Path, config: LearnConfig) -> GradientRun:
        out = Path(out)
        if (out / "checkpoint.npz").exists():
            raise RunDirError(
                f"{out} already holds a run; resume it with --resume {out} or choose another --out"
            )
        setup = cls._setup(config)
        out.mkdir(parents=True, exist_ok=True)
        write_toml(out / "config.toml", {"run": config.to_dict(), "task": setup.task.to_dict()})
        return cls(out, setup)

    @classmethod
    def resume_gradient(cls, out: Path) -> GradientRun:
        """Rebuild a gradient run and restore its optimizer state and log."""
        doc = read_toml(Path(out) / "config.toml", what="run configuration")
        config = LearnConfig(**doc["run"])
        setup = cls._setup(config, parse_task(doc["task"], str(Path(out) / "config.toml")))
        log = Log.load(Path(out) / "checkpoint.npz")
        state_file = Path(out) / "gradient_state.npz"
        if state_file.exists():
            with np.load(state_file) as z:
                setup.optimizer.state = setup.optimizer.gd.state_from_numpy(dict(z))
        return cls(out, setup, log)

    def checkpoint(self) -> None:
        buf = io.BytesIO()
        np.savez(buf, **self.setup.optimizer.gd.state_to_numpy(self.setup.optimizer.state))
        atomic_write_bytes(self.out / "gradient_state.npz", buf.getvalue())
        super().checkpoint()

    def step(self, evaluator) -> int:
        opt = self.setup.optimizer
        x, f = opt.step()
        e_u, e_v = opt.last_aux
        ev = Evaluation(np.array([f]), np.array([e_u]), np.array([e_v]), {}, np.array([False]))
        self.log.add(x[None], ev, time.perf_counter() - self.t_start)
        return 1


def bench_gradient(base: dict, target: float, max_seconds: float) -> dict:
    """Return the gradient path's compile time and wall time to reach E <= target."""
    setup = GradientRun._setup(LearnConfig(optimizer="gradient", budget=10**6, **base))
    opt = setup.optimizer
    t0 = time.perf_counter()
    opt.value_and_grad(opt.x0)  # compile outside the clock
    compile_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    reached = None
    while time.perf_counter() - t0 < max_seconds:
        opt.step()
        if opt.best_f <= target:
            reached = time.perf_counter() - t0
            break
    return {
        "gradient_compile_seconds": round(compile_s, 2),
        "gradient_seconds_to_match_anneal": None if reached is None else round(reached, 3),
        "gradient_steps": opt.evaluations,
        "gradient_best_E": round(opt.best_f, 4),
    }
