"""The optimizers, by name: one module each behind one ask/tell interface (``base.Optimizer``).

    anneal    annealing.Annealing   simulated annealing, the paper's schedule
    simplex   simplex.Simplex       Nelder-Mead
    cmaes     cmaes.CMAES           CMA-ES (the ``cma`` package)
    gradient  gradient.Gradient     Adam through the JAX simulator (imported on first use)

``make_optimizer(name, x0, lower, upper, seed, budget, **options)`` builds one; ``OPTIMIZERS``
lists the names. An optimizer is a mutable object (see ``base``).
"""

from __future__ import annotations

from collections.abc import Callable

from zoetic.errors import ZoeticError
from zoetic.learning.optimizers.annealing import Annealing
from zoetic.learning.optimizers.base import Optimizer
from zoetic.learning.optimizers.cmaes import CMAES
from zoetic.learning.optimizers.simplex import Simplex

__all__ = ["CMAES", "OPTIMIZERS", "Annealing", "Optimizer", "Simplex", "make_optimizer"]


def _gradient(*args, **kwargs) -> Optimizer:
    from zoetic.learning.optimizers.gradient import Gradient  # JAX only when asked for

    return Gradient(*args, **kwargs)


OPTIMIZERS: dict[str, Callable[..., Optimizer]] = {
    "anneal": Annealing,
    "simplex": Simplex,
    "cmaes": CMAES,
    "gradient": _gradient,
}


def make_optimizer(name: str, x0, lower, upper, seed: int, budget: int, **options) -> Optimizer:
    """Return an optimizer by name (see ``OPTIMIZERS``) over the box [lower, upper]."""
    if name not in OPTIMIZERS:
        raise ZoeticError(f"unknown optimizer {name!r} (choose from {', '.join(OPTIMIZERS)})")
    return OPTIMIZERS[name](x0, lower, upper, seed, budget=budget, **options)
