"""Nelder-Mead (downhill simplex) as an ask/tell optimizer."""

from __future__ import annotations

import numpy as np

from zoetic.learning.optimizers.base import Optimizer


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
        """Return the simplex (n+1, n), a shrink (n, n) or one trial (1, n); (0, n) done."""
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
        """Record f and advance Nelder-Mead: keep or reject the trial(s), re-sort."""
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
        """Return True when the simplex has collapsed below ``xatol`` and ``fatol``, or the
        run's plateau stop (``Optimizer.done``)."""
        if super().done():
            return True
        if self.phase != "reflect" or not np.all(np.isfinite(self.fsim)):
            return False
        return bool(
            np.max(np.abs(self.sim[1:] - self.sim[0])) <= self.xatol
            and np.max(np.abs(self.fsim[1:] - self.fsim[0])) <= self.fatol
        )

    def status(self):
        """Return {"size": the simplex's largest coordinate offset from its best vertex}."""
        return {"size": float(np.max(np.abs(self.sim[1:] - self.sim[0])))}

    def _state(self):
        return {
            "sim": self.sim.copy(),
            "fsim": self.fsim.copy(),
            "phase": self.phase,
            "xr": self.xr.copy(),
            "fr": float(self.fr),
        }

    def _load(self, s):
        self.sim = np.array(s["sim"], dtype=np.float64)
        self.fsim = np.array(s["fsim"], dtype=np.float64)
        self.phase = str(s["phase"])
        self.xr, self.fr = np.array(s["xr"], dtype=np.float64), float(s["fr"])
