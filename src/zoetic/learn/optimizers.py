"""Derivative-free optimizers behind one ask/tell interface (minimisation, box bounds).

``ask()`` returns a batch of candidates (k, n) to evaluate together; ``tell(X, f)`` gives their
scores. A failed evaluation (+inf or NaN) is never accepted and never becomes the best.
Every optimizer is deterministic given its seed, so a run is checkpointed as the log of its
ask/tell exchanges and resumed exactly by replaying that log (see ``learn.run``).
"""

from __future__ import annotations

import queue
import threading

import numpy as np


class Optimizer:
    """Shared bookkeeping: bounds, evaluation count, best point so far."""

    name = "base"

    def __init__(self, x0: np.ndarray, lower: np.ndarray, upper: np.ndarray, seed: int):
        self.lower = np.asarray(lower, dtype=np.float64)
        self.upper = np.asarray(upper, dtype=np.float64)
        self.x0 = np.clip(np.asarray(x0, dtype=np.float64), self.lower, self.upper)
        self.seed = int(seed)
        self.evaluations = 0
        self.best_x = self.x0.copy()
        self.best_f = np.inf

    @property
    def dimension(self) -> int:
        return int(self.x0.size)

    def ask(self) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def tell(self, X: np.ndarray, f: np.ndarray) -> None:
        """Record scores; subclasses call this first."""
        f = np.where(np.isfinite(f), f, np.inf)
        self.evaluations += len(f)
        k = int(np.argmin(f))
        if f[k] < self.best_f:
            self.best_f = float(f[k])
            self.best_x = np.array(X[k], dtype=np.float64)

    def done(self) -> bool:
        """Return True when the method has nothing more to try (budget aside)."""
        return False

    def status(self) -> dict:
        """Return a few numbers worth showing in a progress bar."""
        return {}


class Annealing(Optimizer):
    """Simulated annealing as the paper's footnote gives it.

    T0 = 0.5 and T <- alpha T; the temperature drops after at most 10NM steps or at least NM
    accepted moves; every parameter is perturbed at each step, uniformly by at most ``step``
    (10%) of its admissible range, a bound that stays fixed over the run. With ``chains`` > 1,
    that many independent chains share the schedule and are evaluated as one batch.
    """

    name = "anneal"

    def __init__(self, x0, lower, upper, seed, t0=0.5, alpha=0.9, step=0.1, chains=1):
        super().__init__(x0, lower, upper, seed)
        self.rng = np.random.default_rng(self.seed)
        self.T = float(t0)
        self.alpha = float(alpha)
        self.delta = float(step) * (self.upper - self.lower)
        self.chains = int(chains)
        n = self.dimension
        self.max_steps, self.min_accepts = 10 * n, n
        self.x = np.tile(self.x0, (self.chains, 1))
        self.f: np.ndarray | None = None
        self.steps_at_T = 0
        self.accepts_at_T = 0
        self.acceptance = 1.0

    def ask(self):
        if self.f is None:
            return self.x.copy()
        step = self.rng.uniform(-1.0, 1.0, self.x.shape) * self.delta
        return np.clip(self.x + step, self.lower, self.upper)

    def tell(self, X, f):
        super().tell(X, f)
        f = np.where(np.isfinite(f), f, np.inf)
        if self.f is None:
            self.f = f.copy()
            return
        u = self.rng.random(len(f))
        with np.errstate(over="ignore", invalid="ignore"):
            accept = np.isfinite(f) & ((f <= self.f) | (u < np.exp(-(f - self.f) / self.T)))
        self.x[accept] = X[accept]
        self.f[accept] = f[accept]
        self.steps_at_T += len(f)
        self.accepts_at_T += int(accept.sum())
        self.acceptance = 0.9 * self.acceptance + 0.1 * float(accept.mean())
        if self.steps_at_T >= self.max_steps or self.accepts_at_T >= self.min_accepts:
            self.T *= self.alpha
            self.steps_at_T = self.accepts_at_T = 0

    def status(self):
        return {"T": self.T, "accept": self.acceptance}


class _Stop:
    pass


class Simplex(Optimizer):
    """SciPy's Nelder-Mead (downhill simplex) turned inside out into ask/tell.

    SciPy drives the search and calls back for each point; a worker thread runs it and the
    call blocks until ``tell`` supplies the value. The first simplex spans 10% of each range.
    """

    name = "simplex"

    def __init__(self, x0, lower, upper, seed, budget=10_000, step=0.1):
        super().__init__(x0, lower, upper, seed)
        self._asks: queue.Queue = queue.Queue(maxsize=1)
        self._tells: queue.Queue = queue.Queue(maxsize=1)
        self._finished = False
        n = self.dimension
        span = step * (self.upper - self.lower)
        simplex = np.tile(self.x0, (n + 1, 1))
        for i in range(n):
            up = self.x0[i] + span[i] <= self.upper[i]
            simplex[i + 1, i] += span[i] if up else -span[i]
        self._thread = threading.Thread(target=self._run, args=(simplex, int(budget)), daemon=True)
        self._thread.start()
        self._pending = self._asks.get()

    def _run(self, simplex, budget):
        from scipy.optimize import Bounds, minimize

        def fun(x):
            self._asks.put(np.array(x, dtype=np.float64))
            value = self._tells.get()
            if isinstance(value, _Stop):
                raise SystemExit  # unwinds SciPy when the optimizer is abandoned
            return value

        try:
            minimize(
                fun, self.x0, method="Nelder-Mead",
                bounds=Bounds(self.lower, self.upper),
                options={"initial_simplex": simplex, "maxfev": budget, "xatol": 1e-8,
                         "fatol": 1e-10, "adaptive": True},
            )  # fmt: skip
        except SystemExit:
            return
        self._asks.put(_Stop())

    def ask(self):
        if isinstance(self._pending, _Stop):
            self._finished = True
            return np.empty((0, self.dimension))
        return self._pending[None, :]

    def tell(self, X, f):
        super().tell(X, f)
        value = float(f[0]) if np.isfinite(f[0]) else 1e30
        self._tells.put(value)
        self._pending = self._asks.get()
        if isinstance(self._pending, _Stop):
            self._finished = True

    def done(self):
        return self._finished

    def close(self) -> None:
        """Stop the worker thread."""
        if not self._finished and self._thread.is_alive():
            self._finished = True
            self._tells.put(_Stop())


class CMAES(Optimizer):
    """CMA-ES from the ``cma`` package, with its own handling of the box bounds."""

    name = "cmaes"

    def __init__(self, x0, lower, upper, seed, popsize=None, sigma=0.3):
        super().__init__(x0, lower, upper, seed)
        import cma

        scale = self.upper - self.lower
        opts = {
            "bounds": [list(self.lower), list(self.upper)],
            "seed": self.seed + 1,  # cma treats 0 as "seed from the clock"
            "verbose": -9,
            "CMA_stds": list(scale / scale.mean()),
        }
        if popsize:
            opts["popsize"] = int(popsize)
        self.es = cma.CMAEvolutionStrategy(list(self.x0), sigma * scale.mean(), opts)

    def ask(self):
        return np.array(self.es.ask(), dtype=np.float64)

    def tell(self, X, f):
        super().tell(X, f)
        finite = np.isfinite(f)
        worst = np.max(f[finite]) if finite.any() else 1.0
        g = np.where(finite, f, worst + 1e3 * (1 + abs(worst)))
        self.es.tell(list(X), list(g))

    def done(self):
        return bool(self.es.stop()) and "maxfevals" not in self.es.stop()

    def status(self):
        return {"sigma": float(self.es.sigma)}


OPTIMIZERS = {"anneal": Annealing, "simplex": Simplex, "cmaes": CMAES}


def make_optimizer(name: str, x0, lower, upper, seed: int, budget: int, **options) -> Optimizer:
    """Return an optimizer by name ('anneal', 'simplex', 'cmaes') over the box [lower, upper]."""
    from zoetic.errors import ZoeticError

    if name == "anneal":
        return Annealing(x0, lower, upper, seed, **options)
    if name == "simplex":
        return Simplex(x0, lower, upper, seed, budget=budget, **options)
    if name == "cmaes":
        return CMAES(x0, lower, upper, seed, **options)
    raise ZoeticError(f"unknown optimizer {name!r} (choose from anneal, simplex, cmaes, gradient)")
