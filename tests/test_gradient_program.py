"""The gradient program: compiled under the gradient's XLA options, the same value and
gradient as JAX's default compile of the same objective, to float32 rounding."""

from __future__ import annotations

import numpy as np
import pytest

jax = pytest.importorskip("jax")

import jax.numpy as jnp  # noqa: E402

from zoetic.bodies import load_animal  # noqa: E402
from zoetic.control import time_domain  # noqa: E402
from zoetic.learning.gradient import (  # noqa: E402
    _COMPILED,
    compiler_options,
    jax_objective,
    value_and_grad,
)
from zoetic.learning.objective import Objective  # noqa: E402
from zoetic.tasks import load_task, parse_task  # noqa: E402

HORIZON = 0.4  # s: long enough for the start's wave to reach the tail and the water to push
NODES = 4


@pytest.mark.slow
@pytest.mark.parametrize("animal", ["shark", "ray"])
def test_the_gradient_program_computes_what_the_default_compile_does(animal):
    body = load_animal(animal)
    base = load_task("swim-straight")
    task = parse_task({**base.to_dict(), "horizon": HORIZON, "nodes": NODES}, base.source)
    obj = Objective(task, body, time_domain(body, NODES, HORIZON))
    X = np.random.default_rng(3).uniform(*obj.bounds(), size=(2, obj.dimension))
    ev, grad = value_and_grad(obj, X)
    assert _COMPILED[obj].options == compiler_options()
    default = jax.jit(jax.value_and_grad(jax_objective(obj), has_aux=True))
    for k, x in enumerate(X):
        (e, _), g = default(jnp.asarray(x, jnp.float32))
        g = np.asarray(g, dtype=np.float64)
        assert np.all(np.isfinite(g)) and np.any(g != 0)
        np.testing.assert_allclose(ev.E[k], float(e), rtol=1e-5, atol=1e-6)
        # float32 sums in another order: equal to rounding, relative to the largest component
        assert np.max(np.abs(grad[k] - g)) <= 1e-4 * np.max(np.abs(g))
