"""BLAS held to one thread while learning: the learning's matrices are small, and BLAS's idle
threads spin against the simulation kernel's thread pool on the same cores."""

from __future__ import annotations

import sys
from contextlib import AbstractContextManager
from functools import cache


@cache
def _blas(modules: int):
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()  # the BLAS libraries loaded now (a few ms to list them)


def one_blas_thread() -> AbstractContextManager:
    """Hold BLAS/LAPACK to one thread: a learning step's linear algebra (CMA-ES's
    eigendecomposition of its covariance, n <= a few hundred; the activation tables, a product
    with an inner dimension of a few nodes) is too small to share, and OpenBLAS's threads
    busy-wait after each call, against the kernel's thread pool: with two threads on two busy
    cores one eigh can cost more than the whole generation's rollouts."""
    # listed again once modules were imported since (SciPy brings an OpenBLAS of its own)
    return _blas(len(sys.modules)).limit(limits=1, user_api="blas")
