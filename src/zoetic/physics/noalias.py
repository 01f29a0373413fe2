"""``njit_noalias``: Numba's njit with every array argument marked ``noalias`` for LLVM.

Numba tells LLVM nothing about which arrays overlap, so a lane loop that writes one node's
force row and reads other rows is vectorised behind run-time overlap tests (60-100 of them
for a spring), whose fixed cost per loop entry made short lane rows, the ones that stay in
L1, slower than long ones. A function compiled by ``njit_noalias`` promises LLVM that no two
of its array arguments share memory (what Numba's own parallel loop bodies promise when it
finds no aliases), so only overlaps within one array (node i's row against node j's) are
left to test. The caller keeps the promise: never pass two views of one buffer, nor one
array twice, where either is written.
"""

from __future__ import annotations

import numba

from zoetic.jitcache import fresh_numba_cache

try:  # Numba internals: absent or renamed in some Numba version, plain njit is used
    from numba.core import cpu
    from numba.core.registry import CPUDispatcher, cpu_target
except ImportError:  # pragma: no cover - depends on the installed Numba
    cpu = None

fresh_numba_cache()


if cpu is not None:

    class _NoAliasOptions(cpu.CPUTargetOptions):
        """The CPU target's options, with Numba's ``noalias`` compiler flag set."""

        def finalize(self, flags, options):
            super().finalize(flags, options)
            flags.noalias = True

    class _NoAliasTarget:
        """The CPU target (same typing and target contexts) with ``_NoAliasOptions``."""

        options = _NoAliasOptions

        def __getattr__(self, name):
            return getattr(cpu_target, name)

    class _NoAliasDispatcher(CPUDispatcher):
        targetdescr = _NoAliasTarget()


def njit_noalias(**options):
    """Return a decorator like ``numba.njit(**options)`` whose function's pointer arguments are
    all ``noalias`` (see the module's docstring for the caller's promise)."""

    if cpu is None:
        return numba.njit(**options)

    def decorate(fn):
        opts = dict(options)
        cache = opts.pop("cache", False)
        disp = _NoAliasDispatcher(py_func=fn, locals={}, targetoptions={**opts, "nopython": True})
        if cache:
            disp.enable_caching()
        return disp

    return decorate
