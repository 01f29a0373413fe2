"""Optimizers behind one ask/tell interface (minimisation, box bounds), with state as a value.

``ask()`` returns a batch of candidates (k, n) to evaluate together; ``tell(X, f, grad)`` gives
their scores (and, to an optimizer with ``needs_gradient``, their gradients). A failed
evaluation (+inf or NaN) is never accepted and never becomes the best. Every optimizer is
deterministic given its seed and saves its whole state with ``state_dict()`` (NumPy arrays and
plain values) and restores it with ``load_state_dict()``: a run resumes from that state, so a
new release of SciPy or ``cma`` cannot change what a saved run does next.
"""

from __future__ import annotations

import pickle
from collections.abc import Callable

import numpy as np

from zoetic.errors import ZoeticError


class Optimizer:
    """Shared bookkeeping: bounds, evaluation count, best point so far."""

    name = "base"
    needs_gradient = False

    def __init__(self, x0: np.ndarray, lower: np.ndarray, upper: np.ndarray, seed: int,
                 budget: int | None = None):  # fmt: skip
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

    def record(self, X: np.ndarray, f: np.ndarray) -> np.ndarray:
        """Count evaluations and keep the best finite one; return f with failures as +inf."""
        f = np.where(np.isfinite(f), f, np.inf)
        self.evaluations += len(f)
        k = int(np.argmin(f))
        if f[k] < self.best_f:
            self.best_f = float(f[k])
            self.best_x = np.array(X[k], dtype=np.float64)
        return f

    def tell(self, X: np.ndarray, f: np.ndarray, grad: np.ndarray | None = None) -> None:
        """Record scores; subclasses call this first."""
        self.record(X, f)

    def done(self) -> bool:
        """Return True when the method has nothing more to try (budget aside)."""
        return False

    def status(self) -> dict:
        """Return a few numbers worth showing in a progress bar."""
        return {}

    def close(self) -> None:
        """Release anything held (nothing by default)."""

    def state_dict(self) -> dict:
        """Return the whole state: NumPy arrays and plain values."""
        return {"evaluations": self.evaluations, "best_x": self.best_x.copy(),
                "best_f": self.best_f} | self._state()  # fmt: skip

    def load_state_dict(self, state: dict) -> None:
        """Restore a state saved by ``state_dict`` (same configuration)."""
        best_x = np.asarray(state["best_x"], dtype=np.float64)
        if best_x.shape != self.x0.shape:
            raise ZoeticError(
                f"saved {self.name} state has {best_x.size} parameters, this problem "
                f"{self.dimension}"
            )
        self.evaluations = int(state["evaluations"])
        self.best_x = best_x.copy()
        self.best_f = float(state["best_f"])
        self._load(state)

    def _state(self) -> dict:
        return {}

    def _load(self, state: dict) -> None:
        pass


class Annealing(Optimizer):
    """Simulated annealing as the paper's footnote gives it; the one annealing of zoetic.

    T0 = 0.5 and T <- alpha T (``t0``, ``alpha``: the paper's usual cooling rate is 0.9, its
    Fig. 6(b-c) also runs 0.8 and 0.85); the temperature drops after at most 10NM steps or at
    least NM accepted moves; every parameter is perturbed at each step, uniformly by at most
    ``step`` (10%) of its admissible range, a bound that stays fixed over the run. With
    ``chains`` > 1, that many independent chains share the schedule and are evaluated as one
    batch (``x0`` may give each chain its own start, (chains, n)).

    Other search spaces (macro-controller plans, SAN tuning) keep this acceptance rule and
    schedule and change only what they must: ``perturb(x (chains, n), rng) -> proposals``
    replaces the uniform move, ``max_steps``/``min_accepts`` the 10NM/NM schedule;
    ``relative`` measures T in units of the chains' mean starting cost; ``rng`` shares a
    generator the caller already drew from; ``accept_ties=False`` with ``t0=0`` is greedy
    (strict) hill climbing.
    """

    name = "anneal"

    def __init__(self, x0, lower, upper, seed, budget=None, t0=0.5, alpha=0.9, step=0.1,
                 chains=1, perturb: Callable | None = None, max_steps: int | None = None,
                 min_accepts: int | None = None, relative: bool = False,
                 rng: np.random.Generator | None = None, accept_ties: bool = True):  # fmt: skip
        if not 0.0 <= float(t0) < np.inf:
            raise ZoeticError(f"annealing: the start temperature t0 must be finite, >= 0: {t0}")
        if not 0.0 < float(alpha) <= 1.0:
            raise ZoeticError(f"annealing: the cooling rate alpha must be in (0, 1], got {alpha}")
        starts = np.atleast_2d(np.asarray(x0, dtype=np.float64))
        super().__init__(starts[0], lower, upper, seed)
        self.rng = rng if rng is not None else np.random.default_rng(self.seed)
        self.T = float(t0)
        self.alpha = float(alpha)
        with np.errstate(invalid="ignore", over="ignore"):
            self.delta = float(step) * (self.upper - self.lower)
        self.chains = int(chains)
        self.perturb = perturb
        self.relative = bool(relative)
        self.accept_ties = bool(accept_ties)
        n = self.dimension
        self.max_steps = int(max_steps or 10 * n)
        self.min_accepts = int(min_accepts or n)
        if starts.shape[0] == self.chains:
            self.x = np.clip(starts, self.lower, self.upper)
        else:
            self.x = np.tile(self.x0, (self.chains, 1))
        self.f: np.ndarray | None = None
        self.scale = 1.0
        self.steps_at_T = 0
        self.accepts_at_T = 0
        self.acceptance = 1.0
        self.last_accept = np.zeros(self.chains, bool)

    def ask(self):
        if self.f is None:
            return self.x.copy()
        if self.perturb is not None:
            return np.asarray(self.perturb(self.x.copy(), self.rng), dtype=np.float64)
        step = self.rng.uniform(-1.0, 1.0, self.x.shape) * self.delta
        return np.clip(self.x + step, self.lower, self.upper)

    def tell(self, X, f, grad=None):
        f = self.record(X, f)
        if self.f is None:
            self.f = f.copy()
            if self.relative:
                good = f[np.isfinite(f)]
                self.scale = float(np.mean(np.abs(good))) if len(good) else 1.0
            return
        u = self.rng.random(len(f))
        better = (f <= self.f) if self.accept_ties else (f < self.f)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            accept = np.isfinite(f) & (better | (u < np.exp(-(f - self.f) / (self.T * self.scale))))
        self.last_accept = accept
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

    def _state(self):
        return {"rng": self.rng.bit_generator.state, "T": self.T, "x": self.x.copy(),
                "f": None if self.f is None else self.f.copy(), "steps_at_T": self.steps_at_T,
                "accepts_at_T": self.accepts_at_T, "acceptance": self.acceptance,
                "scale": self.scale}  # fmt: skip

    def _load(self, s):
        self.rng.bit_generator.state = s["rng"]
        self.T = float(s["T"])
        self.x = np.array(s["x"], dtype=np.float64)
        self.f = None if s["f"] is None else np.array(s["f"], dtype=np.float64)
        self.steps_at_T, self.accepts_at_T = int(s["steps_at_T"]), int(s["accepts_at_T"])
        self.acceptance = float(s["acceptance"])
        self.scale = float(s.get("scale", 1.0))


class Simplex(Optimizer):
    """Nelder-Mead (downhill simplex) as an explicit ask/tell state machine.

    Adaptive coefficients for the dimension (Gao and Han 2012, as SciPy's ``adaptive``): reflect
    1, expand 1 + 2/n, contract 0.75 - 1/(2n), shrink 1 - 1/n; points are clipped into the box.
    The first simplex spans ``step`` (10%) of each range and is evaluated as one batch, as is
    each shrink. It stops when the simplex has collapsed (``xatol``, ``fatol``).
    """

    name = "simplex"

    def __init__(self, x0, lower, upper, seed, budget=None, step=0.1, xatol=1e-8, fatol=1e-10):
        super().__init__(x0, lower, upper, seed)
        n = self.dimension
        span = step * (self.upper - self.lower)
        sim = np.tile(self.x0, (n + 1, 1))
        for i in range(n):
            up = self.x0[i] + span[i] <= self.upper[i]
            sim[i + 1, i] += span[i] if up else -span[i]
        self.sim = sim
        self.fsim = np.full(n + 1, np.inf)
        self.rho, self.chi = 1.0, 1.0 + 2.0 / n
        self.psi, self.sigma = 0.75 - 1.0 / (2 * n), 1.0 - 1.0 / n
        self.xatol, self.fatol = float(xatol), float(fatol)
        self.phase = "init"
        self.xr = np.zeros(n)
        self.fr = np.inf

    def _clip(self, x):
        return np.clip(x, self.lower, self.upper)

    def _centroid(self):
        return self.sim[:-1].mean(axis=0)

    def ask(self):
        if self.done():
            return np.empty((0, self.dimension))
        xbar, worst = self._centroid(), self.sim[-1]
        if self.phase == "init":
            return self.sim.copy()
        if self.phase == "reflect":
            return self._clip(xbar + self.rho * (xbar - worst))[None]
        if self.phase == "expand":
            return self._clip(xbar + self.chi * (self.xr - xbar))[None]
        if self.phase == "outside":
            return self._clip(xbar + self.psi * (self.xr - xbar))[None]
        if self.phase == "inside":
            return self._clip(xbar - self.psi * (xbar - worst))[None]
        return self._clip(self.sim[0] + self.sigma * (self.sim[1:] - self.sim[0]))  # shrink

    def _replace_worst(self, x, f):
        self.sim[-1], self.fsim[-1] = x, f
        self._sort()

    def _sort(self):
        order = np.argsort(self.fsim, kind="stable")
        self.sim, self.fsim = self.sim[order], self.fsim[order]
        self.phase = "reflect"

    def tell(self, X, f, grad=None):
        f = self.record(X, f)
        phase = self.phase
        if phase == "init":
            self.sim, self.fsim = np.array(X, dtype=np.float64), f.copy()
            self._sort()
        elif phase == "shrink":
            self.sim[1:], self.fsim[1:] = X, f
            self._sort()
        elif phase == "reflect":
            x, fx = X[0], f[0]
            if fx < self.fsim[0]:
                self.xr, self.fr, self.phase = x.copy(), fx, "expand"
            elif fx < self.fsim[-2]:
                self._replace_worst(x, fx)
            elif fx < self.fsim[-1]:
                self.xr, self.fr, self.phase = x.copy(), fx, "outside"
            else:
                self.phase = "inside"
        elif phase == "expand":
            if f[0] < self.fr:
                self._replace_worst(X[0], f[0])
            else:
                self._replace_worst(self.xr, self.fr)
        elif phase == "outside":
            if f[0] <= self.fr:
                self._replace_worst(X[0], f[0])
            else:
                self.phase = "shrink"
        elif phase == "inside":
            if f[0] < self.fsim[-1]:
                self._replace_worst(X[0], f[0])
            else:
                self.phase = "shrink"

    def done(self):
        if self.phase != "reflect" or not np.all(np.isfinite(self.fsim)):
            return False
        return bool(np.max(np.abs(self.sim[1:] - self.sim[0])) <= self.xatol
                    and np.max(np.abs(self.fsim[1:] - self.fsim[0])) <= self.fatol)  # fmt: skip

    def status(self):
        return {"size": float(np.max(np.abs(self.sim[1:] - self.sim[0])))}

    def _state(self):
        return {"sim": self.sim.copy(), "fsim": self.fsim.copy(), "phase": self.phase,
                "xr": self.xr.copy(), "fr": float(self.fr)}  # fmt: skip

    def _load(self, s):
        self.sim = np.array(s["sim"], dtype=np.float64)
        self.fsim = np.array(s["fsim"], dtype=np.float64)
        self.phase = str(s["phase"])
        self.xr, self.fr = np.array(s["xr"], dtype=np.float64), float(s["fr"])


class _Randn:
    """CMA-ES's normal samples from the optimizer's own generator, not NumPy's global one.

    It is the stream ``cma`` itself would draw after seeding NumPy's global generator (the
    legacy Mersenne Twister), so results are those of plain ``cma``, yet the state is ours.
    """

    def __init__(self, seed: int):
        self.rng = np.random.RandomState(seed)

    def __call__(self, *shape):
        return self.rng.randn(*shape)

    def state(self) -> dict:
        """Return the generator's state as plain values."""
        s = self.rng.get_state(legacy=False)
        return {"key": s["state"]["key"].tolist(), "pos": int(s["state"]["pos"]),
                "has_gauss": int(s["has_gauss"]), "gauss": float(s["gauss"])}  # fmt: skip

    def load(self, s: dict) -> None:
        """Restore a state from ``state``."""
        self.rng.set_state({"bit_generator": "MT19937",
                            "state": {"key": np.asarray(s["key"], np.uint32), "pos": s["pos"]},
                            "has_gauss": s["has_gauss"], "gauss": s["gauss"]})  # fmt: skip


class CMAES(Optimizer):
    """CMA-ES from the ``cma`` package, with its own handling of the box bounds.

    Its state is the pickled strategy (exact resume) plus the mean, step size, covariance and
    evolution paths, from which a fresh strategy is rebuilt (continuing, not bit-identical) if
    a later ``cma`` cannot read the pickle.
    """

    name = "cmaes"

    def __init__(self, x0, lower, upper, seed, budget=None, popsize=None, sigma=0.3):
        super().__init__(x0, lower, upper, seed)
        import cma

        scale = self.upper - self.lower
        opts = {
            "bounds": [list(self.lower), list(self.upper)],
            "seed": self.seed + 1,  # cma treats 0 as "seed from the clock"
            "verbose": -9,
            "CMA_stds": list(scale / scale.mean()),
            "randn": _Randn(self.seed + 1),
        }
        if popsize:
            opts["popsize"] = int(popsize)
        self.es = cma.CMAEvolutionStrategy(list(self.x0), sigma * scale.mean(), opts)

    def ask(self):
        return np.array(self.es.ask(), dtype=np.float64)

    def tell(self, X, f, grad=None):
        self.record(X, f)
        finite = np.isfinite(f)
        worst = np.max(f[finite]) if finite.any() else 1.0
        g = np.where(finite, f, worst + 1e3 * (1 + abs(worst)))
        self.es.tell(list(X), list(g))

    def done(self):
        return bool(self.es.stop()) and "maxfevals" not in self.es.stop()

    def status(self):
        return {"sigma": float(self.es.sigma)}

    def _state(self):
        es = self.es
        return {"pickle": np.frombuffer(pickle.dumps(es), dtype=np.uint8).copy(),
                "mean": np.array(es.mean, float), "sigma": float(es.sigma),
                "C": np.array(es.sm.C, float), "pc": np.array(es.pc, float),
                "ps": np.array(getattr(es.adapt_sigma, "ps", np.zeros(self.dimension)), float),
                "countiter": int(es.countiter), "countevals": int(es.countevals),
                "rng": es.opts["randn"].state()}  # fmt: skip

    def _load(self, s):
        try:
            self.es = pickle.loads(np.asarray(s["pickle"], dtype=np.uint8).tobytes())
        except Exception:  # another cma release: rebuild from the numbers
            self._rebuild(s)

    def _rebuild(self, s):
        es = self.es
        es.mean = np.array(s["mean"], float)
        es.sigma = float(s["sigma"])
        es.sm.C = np.array(s["C"], float)
        if hasattr(es.sm, "_decompose_C"):
            es.sm._decompose_C()
        es.pc = np.array(s["pc"], float)
        if hasattr(es.adapt_sigma, "ps"):
            es.adapt_sigma.ps = np.array(s["ps"], float)
        es.countevals = int(s["countevals"])  # iterations are counted afresh
        es.opts["randn"].load(s["rng"])


def _gradient(*args, **kwargs) -> Optimizer:
    from zoetic.learning.gradient import Gradient

    return Gradient(*args, **kwargs)


OPTIMIZERS: dict[str, Callable[..., Optimizer]] = {
    "anneal": Annealing, "simplex": Simplex, "cmaes": CMAES, "gradient": _gradient,
}  # fmt: skip


def make_optimizer(name: str, x0, lower, upper, seed: int, budget: int, **options) -> Optimizer:
    """Return an optimizer by name (see ``OPTIMIZERS``) over the box [lower, upper]."""
    if name not in OPTIMIZERS:
        raise ZoeticError(f"unknown optimizer {name!r} (choose from {', '.join(OPTIMIZERS)})")
    return OPTIMIZERS[name](x0, lower, upper, seed, budget=budget, **options)
