"""Gradient descent (Adam in box bounds, ``learning.gradient.GradientDescent``) as an ask/tell
optimizer that needs the gradient of each point it asks (JAX is imported with this module)."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from zoetic.learning.gradient import GradientDescent
from zoetic.learning.optimizers.base import Optimizer


class Gradient(Optimizer):
    """Adam in box bounds (``GradientDescent``) as an ask/tell optimizer that needs gradients."""

    name = "gradient"
    needs_gradient = True

    def __init__(self, x0, lower, upper, seed, budget=None, learning_rate=0.02, max_grad_norm=1.0):
        super().__init__(x0, lower, upper, seed)
        self.gd = GradientDescent(learning_rate, max_grad_norm)
        self.state = self.gd.init(self.x0, self.lower, self.upper, seed)

    def ask(self):
        """Return the current point (1, n); its loss and gradient are needed back."""
        return self.gd.x(self.state)[None]

    def tell(self, X, f, grad=None):
        """Record f; one clipped Adam step with grad (1, n), or halfway back to the best."""
        if grad is None:
            raise ValueError("the gradient optimizer needs the gradient of each point it asks")
        self.record(X, f)
        f0, g0 = jnp.asarray(f[0], jnp.float32), jnp.asarray(grad[0], jnp.float32)
        self.state = self.gd._update(self.state, f0, g0)

    def status(self):
        """Return {"|g|": the last gradient's norm in unit-box coordinates, unclipped}."""
        return {"|g|": float(self.state.grad_norm)}

    def _state(self):
        return {f"gd_{k}": v for k, v in self.gd.state_to_numpy(self.state).items()}

    def _load(self, s):
        arrays = {k[3:]: np.asarray(v) for k, v in s.items() if k.startswith("gd_")}
        self.state = self.gd.state_from_numpy(arrays)
