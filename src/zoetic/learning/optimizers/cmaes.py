"""CMA-ES (the ``cma`` package) as an ask/tell optimizer whose state is ours to save."""

from __future__ import annotations

import pickle
import sys
import warnings

import numpy as np

from zoetic.learning.blas import one_blas_thread
from zoetic.learning.optimizers.base import Optimizer


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
        return {
            "key": s["state"]["key"].tolist(),
            "pos": int(s["state"]["pos"]),
            "has_gauss": int(s["has_gauss"]),
            "gauss": float(s["gauss"]),
        }

    def load(self, s: dict) -> None:
        """Restore a state from ``state``."""
        self.rng.set_state(
            {
                "bit_generator": "MT19937",
                "state": {"key": np.asarray(s["key"], np.uint32), "pos": s["pos"]},
                "has_gauss": s["has_gauss"],
                "gauss": s["gauss"],
            }
        )


# modules cma imports at its own import for what it offers beyond the search itself: a rank
# correlation for its surrogate fitness models (scipy.stats; it has its own NumPy fallback)
# and its plots (matplotlib.pyplot). Neither is used here, and each took longer to import
# than cma itself, in every learning run; a figure imports matplotlib when it is drawn.
_UNUSED_BY_CMA = ("scipy.stats", "matplotlib")


def _cma():
    """Return the ``cma`` module, imported without ``_UNUSED_BY_CMA`` unless they are loaded
    already (cma falls back without them, and warns that its plots are unavailable)."""
    if "cma" in sys.modules:
        import cma

        return cma
    blocked = [m for m in _UNUSED_BY_CMA if m not in sys.modules]
    for name in blocked:
        sys.modules[name] = None  # an import of it raises ImportError
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", "Could not import matplotlib")
            import cma
    except ImportError:
        cma = None  # a cma that needs one of them at import: take it whole, below
    finally:
        for name in blocked:
            del sys.modules[name]
    if cma is None:
        for name in [m for m in sys.modules if m == "cma" or m.startswith("cma.")]:
            del sys.modules[name]  # the half-imported package, imported again in full
        import cma
    return cma


def _ask_in_bounds(es) -> list[np.ndarray]:
    """Return ``es.ask()``: the same candidates, and the same records kept for ``tell``, with
    the box's transformation (cma's ``BoxConstraintsLinQuadTransformation``, the identity
    inside the box and a quadratic fold at its edges) applied to the whole generation at once
    (``_fold_into_box``) instead of candidate by candidate, a tenth of ``ask``'s cost at 32
    candidates of 40 parameters. Anything but that plain case (other bounds, fixed or integer
    variables, scaled coordinates) is ``es.ask()`` itself."""
    cma = _cma()
    handler = es.boundary_handler
    tf = getattr(handler, "bounds_tf", None)
    plain = (
        type(handler) is cma.boundary_handler.BoundTransform
        and type(tf) is cma.transformations.BoxConstraintsLinQuadTransformation
        and es.gp.isidentity
        and not es.opts["integer_variables"]
        and len(tf._lb) == es.N
        and np.isfinite(tf._lb).all()
        and np.isfinite(tf._ub).all()
    )
    if not plain:
        return es.ask()
    if es.countiter == 0:
        es.timer = cma.utilities.utils.ElapsedWCTime()
    else:
        es.timer.tic  # noqa: B018 (a property that restarts the timer, as es.ask reads it)
    geno = es.ask_geno()
    pheno = list(_fold_into_box(np.asarray(geno, dtype=float), tf))
    for x, y in zip(geno, pheno, strict=True):
        es.sent_solutions.insert(y, geno=x, iteration=es.countiter)
    es._round_integer_variables.round_population(pheno)
    return pheno


def _fold_into_box(x: np.ndarray, tf) -> np.ndarray:
    """Return the candidates ``x`` (P, n) mapped into the box as ``tf`` (cma's
    ``BoxConstraintsLinQuadTransformation``) maps each one: far values shifted by whole
    periods, values beyond the margins mirrored back, the margins folded quadratically onto
    the bounds; every step the same arithmetic on the same elements, so the same bits."""
    lb, ub, al, au = tf._lb, tf._ub, tf._al, tf._au
    y = x.copy()
    far = (y < lb - 2 * al - (ub - lb) / 2.0) | (y > ub + 2 * au + (ub - lb) / 2.0)
    if far.any():
        period = 2 * (ub - lb + al + au)
        start = lb - 2 * al - (ub - lb) / 2.0
        y = np.where(far, y - period * ((y - start) // period), y)
    y = np.where(y > ub + au, y - 2 * (y - ub - au), y)
    y = np.where(y < lb - al, y + 2 * (lb - al - y), y)
    y = np.where(y < lb + al, lb + (y - (lb - al)) ** 2 / 4 / al, y)
    return np.where(y > ub - au, ub - (y - (ub + au)) ** 2 / 4 / au, y)


class CMAES(Optimizer):
    """CMA-ES from the ``cma`` package, with its own handling of the box bounds.

    Its state is the pickled strategy (exact resume) plus the mean, step size, covariance and
    evolution paths, from which a fresh strategy is rebuilt (continuing, not bit-identical) if
    a later ``cma`` cannot read the pickle.
    """

    name = "cmaes"

    def __init__(
        self, x0, lower, upper, seed, budget=None, popsize=None, sigma=0.3, diagonal=False
    ):
        """``diagonal``: learn only the covariance's diagonal (separable CMA-ES), whose
        learning rate is about n times a full covariance's: with n = 120 parameters and a few
        thousand evaluations the full one hardly adapts."""
        super().__init__(x0, lower, upper, seed)
        cma = _cma()
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
        if diagonal:
            opts["CMA_diagonal"] = True
        self.es = cma.CMAEvolutionStrategy(list(self.x0), sigma * scale.mean(), opts)

    def ask(self):
        """Return the next generation (popsize, n): samples of CMA-ES's bounded normal."""
        with one_blas_thread():
            return np.array(_ask_in_bounds(self.es), dtype=np.float64)

    def tell(self, X, f, grad=None):
        """Record f; pass it to CMA-ES with failures scored far above the worst finite."""
        self.record(X, f)
        finite = np.isfinite(f)
        worst = np.max(f[finite]) if finite.any() else 1.0
        g = np.where(finite, f, worst + 1e3 * (1 + abs(worst)))
        with one_blas_thread():
            self.es.tell(list(X), list(g))

    def done(self):
        """Return True when CMA-ES meets a stop criterion other than the budget, or the run's
        plateau stop (``Optimizer.done``)."""
        own = bool(self.es.stop()) and "maxfevals" not in self.es.stop()
        return own or super().done()

    def status(self):
        """Return {"sigma": CMA-ES's current overall step size, in parameter units}."""
        return {"sigma": float(self.es.sigma)}

    def _state(self):
        es = self.es
        return {
            "pickle": np.frombuffer(pickle.dumps(es), dtype=np.uint8).copy(),
            "mean": np.array(es.mean, float),
            "sigma": float(es.sigma),
            "C": self._covariance(),
            "pc": np.array(es.pc, float),
            "ps": np.array(getattr(es.adapt_sigma, "ps", np.zeros(self.dimension)), float),
            "countiter": int(es.countiter),
            "countevals": int(es.countevals),
            "rng": es.opts["randn"].state(),
        }

    def _covariance(self) -> np.ndarray:
        """Return the search's covariance shape (n, n): the sampler's, or for the separable
        (diagonal) method the squared per-parameter scaling it adapts instead."""
        es = self.es
        if hasattr(es.sm, "C"):
            return np.array(es.sm.C, float)
        return np.diag(np.asarray(es.sigma_vec.scaling, float) ** 2)

    def _load(self, s):
        try:
            self.es = pickle.loads(np.asarray(s["pickle"], dtype=np.uint8).tobytes())
        except Exception:  # another cma release: rebuild from the numbers
            self._rebuild(s)

    def _rebuild(self, s):
        es = self.es
        es.mean = np.array(s["mean"], float)
        es.sigma = float(s["sigma"])
        if hasattr(es.sm, "C"):
            es.sm.C = np.array(s["C"], float)
            if hasattr(es.sm, "_decompose_C"):
                es.sm._decompose_C()
        else:  # separable: the scaling is the diagonal's square root
            es.sigma_vec.scaling = np.sqrt(np.diag(np.asarray(s["C"], float)))
        es.pc = np.array(s["pc"], float)
        if hasattr(es.adapt_sigma, "ps"):
            es.adapt_sigma.ps = np.array(s["ps"], float)
        es.countevals = int(s["countevals"])  # iterations are counted afresh
        es.opts["randn"].load(s["rng"])
