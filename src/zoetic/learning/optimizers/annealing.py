"""Simulated annealing with the paper's schedule (also the SAN tuner's and the planners')."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from zoetic.errors import ZoeticError
from zoetic.learning.optimizers.base import Optimizer


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

    def __init__(
        self,
        x0,
        lower,
        upper,
        seed,
        budget=None,
        t0=0.5,
        alpha=0.9,
        step=0.1,
        chains=1,
        perturb: Callable | None = None,
        max_steps: int | None = None,
        min_accepts: int | None = None,
        relative: bool = False,
        rng: np.random.Generator | None = None,
        accept_ties: bool = True,
    ):
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
        """Return (chains, n): the starts first, then one perturbed move per chain."""
        if self.f is None:
            return self.x.copy()
        if self.perturb is not None:
            return np.asarray(self.perturb(self.x.copy(), self.rng), dtype=np.float64)
        step = self.rng.uniform(-1.0, 1.0, self.x.shape) * self.delta
        return np.clip(self.x + step, self.lower, self.upper)

    def tell(self, X, f, grad=None):
        """Record f; accept each chain's move by the Metropolis rule; cool T on schedule."""
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
        """Return {"T": temperature, "accept": running (EMA) acceptance rate, 0..1}."""
        return {"T": self.T, "accept": self.acceptance}

    def _state(self):
        return {
            "rng": self.rng.bit_generator.state,
            "T": self.T,
            "x": self.x.copy(),
            "f": None if self.f is None else self.f.copy(),
            "steps_at_T": self.steps_at_T,
            "accepts_at_T": self.accepts_at_T,
            "acceptance": self.acceptance,
            "scale": self.scale,
        }

    def _load(self, s):
        self.rng.bit_generator.state = s["rng"]
        self.T = float(s["T"])
        self.x = np.array(s["x"], dtype=np.float64)
        self.f = None if s["f"] is None else np.array(s["f"], dtype=np.float64)
        self.steps_at_T, self.accepts_at_T = int(s["steps_at_T"]), int(s["accepts_at_T"])
        self.acceptance = float(s["acceptance"])
        self.scale = float(s.get("scale", 1.0))
