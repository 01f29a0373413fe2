"""The ask/tell interface every optimizer shares (minimisation, box bounds).

``ask()`` returns a batch of candidates (k, n) to evaluate together; ``tell(X, f, grad)`` gives
their scores (and, to an optimizer with ``needs_gradient``, their gradients). A failed
evaluation (+inf or NaN) is never accepted and never becomes the best.

An optimizer is a mutable object: ``ask``/``tell`` change it in place. Every optimizer is
deterministic given its seed, and ``state_dict()`` returns a snapshot of everything that
determines what it does next (copies: NumPy arrays and plain values, safe to keep while the
optimizer goes on); ``load_state_dict()`` puts such a snapshot back. A run checkpoints that
snapshot and resumes from it, so a new release of SciPy or ``cma`` cannot change what a saved
run does next.
"""

from __future__ import annotations

import numpy as np

from zoetic.errors import ZoeticError


def plateaued(bests: list[float], generations: int, improvement: float) -> bool:
    """True when the best E improved by at most ``improvement`` times its size over the last
    ``generations`` batches: bests[-1 - generations] - bests[-1] <= improvement * |bests[-1]|.

    ``bests`` is the best E after each batch told; a run shorter than ``generations`` + 1
    batches, or without a finite best ``generations`` batches ago, has not plateaued."""
    if len(bests) <= generations:
        return False
    before, now = bests[-1 - generations], bests[-1]
    if not (np.isfinite(before) and np.isfinite(now)):
        return False
    return before - now <= improvement * abs(now)


class Optimizer:
    """Shared bookkeeping: bounds, evaluation count, best point so far."""

    name = "base"
    needs_gradient = False

    def __init__(
        self,
        x0: np.ndarray,
        lower: np.ndarray,
        upper: np.ndarray,
        seed: int,
        budget: int | None = None,
    ):
        self.lower = np.asarray(lower, dtype=np.float64)
        self.upper = np.asarray(upper, dtype=np.float64)
        self.x0 = np.clip(np.asarray(x0, dtype=np.float64), self.lower, self.upper)
        self.seed = int(seed)
        self.evaluations = 0
        self.best_x = self.x0.copy()
        self.best_f = np.inf
        self.bests: list[float] = []  # the best E after each batch told, in order
        # (generations, improvement) of the run's plateau stop (``plateaued``); None: none
        self.plateau: tuple[int, float] | None = None

    @property
    def dimension(self) -> int:
        """The number n of parameters in a candidate."""
        return int(self.x0.size)

    def ask(self) -> np.ndarray:  # pragma: no cover - abstract
        """Return the next batch of candidates (k, n) to evaluate, within the bounds."""
        raise NotImplementedError

    def record(self, X: np.ndarray, f: np.ndarray) -> np.ndarray:
        """Count evaluations and keep the best finite one; return f with failures as +inf."""
        f = np.where(np.isfinite(f), f, np.inf)
        self.evaluations += len(f)
        k = int(np.argmin(f))
        if f[k] < self.best_f:
            self.best_f = float(f[k])
            self.best_x = np.array(X[k], dtype=np.float64)
        self.bests.append(self.best_f)
        return f

    def tell(self, X: np.ndarray, f: np.ndarray, grad: np.ndarray | None = None) -> None:
        """Record scores; subclasses call this first."""
        self.record(X, f)

    def done(self) -> bool:
        """Return True when the method has nothing more to try (budget aside) or the best E
        has reached a plateau (``plateau``); a method with its own criteria adds them."""
        return self.plateau is not None and plateaued(self.bests, *self.plateau)

    def status(self) -> dict:
        """Return a few numbers worth showing in a progress bar."""
        return {}

    def close(self) -> None:
        """Release anything held (nothing by default)."""

    def state_dict(self) -> dict:
        """Return the whole state: NumPy arrays and plain values."""
        return {
            "evaluations": self.evaluations,
            "best_x": self.best_x.copy(),
            "best_f": self.best_f,
            "bests": np.array(self.bests, dtype=np.float64),
        } | self._state()

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
        # a checkpoint written before the plateau stop kept no bests: counted from here
        self.bests = [float(b) for b in np.asarray(state.get("bests", []), dtype=np.float64)]
        self._load(state)

    def _state(self) -> dict:
        return {}

    def _load(self, state: dict) -> None:
        pass
