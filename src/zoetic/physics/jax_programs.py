"""Compiled JAX programs kept between runs: a later process neither traces nor compiles them.

JAX's persistent compilation cache (``jax_backend.use_compilation_cache``) skips XLA's compile
in a later process, but that process still traces and lowers the function to find its cache
entry: for the gradient objective most of its start (JAX's differentiation machinery, in
Python). ``StoredProgram`` keeps the compiled program itself: the first call traces and
compiles it and writes the executable (``jax.experimental.serialize_executable``, a pickle)
into a folder inside JAX's cache directory; a later process whose key matches loads it.
(``jax.export`` would keep portable StableHLO instead, but its serialization needs the
``flatbuffers`` package, not a dependency here.) Like JAX's own cache the store is trusted:
loading a program runs what it holds, so it lives in the user's cache directory only.

The key is everything the program depends on: the caller's fingerprint of the values the
function closes over (``fingerprint``: the model's or the objective's arrays), the
arguments' shapes and dtypes, the backend, JAX's version and the source of the whole
``zoetic`` package (any edit makes new programs) and the XLA compiler options it is compiled
under. With no JAX cache directory there is no store, and a ``StoredProgram`` compiles its
function once a process, as ``jax.jit`` does.
"""

from __future__ import annotations

import dataclasses
import gc
import hashlib
import os
import pickle
import tempfile
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
from jax.experimental.serialize_executable import deserialize_and_load, serialize

from zoetic.jitcache import PACKAGE, source_digest

STORE = "zoetic-programs"  # the folder inside JAX's compilation cache directory


def fingerprint(*parts) -> str:
    """Return a hex digest of ``parts``: arrays (dtype, shape, bytes), numbers, strings,
    None, and tuples, lists, dicts and dataclasses of these, recursively; anything else
    raises TypeError, so that no value a program depends on drops out of its key."""
    h = hashlib.sha256()
    for part in parts:
        _feed(h, part)
    return h.hexdigest()


def _feed(h, q) -> None:
    if isinstance(q, np.ndarray | jax.Array | np.generic):
        a = np.ascontiguousarray(q)
        h.update(f"<a {a.dtype.str} {a.shape}>".encode())
        h.update(a.tobytes())
    elif q is None or isinstance(q, bool | int | float | str):
        h.update(f"<{type(q).__name__} {q!r}>".encode())
    elif dataclasses.is_dataclass(q) and not isinstance(q, type):
        h.update(f"<{type(q).__qualname__}>".encode())
        for f in dataclasses.fields(q):
            _feed(h, getattr(q, f.name))
    elif isinstance(q, tuple | list):
        h.update(f"<{type(q).__qualname__} {len(q)}>".encode())
        for item in q:
            _feed(h, item)
    elif isinstance(q, dict):
        h.update(f"<dict {len(q)}>".encode())
        for k in sorted(q, key=repr):
            _feed(h, k)
            _feed(h, q[k])
    else:
        raise TypeError(f"fingerprint: cannot key a {type(q).__qualname__}")


@lru_cache(maxsize=1)
def code_version() -> str:
    """Return a digest of every ``.py`` file of the ``zoetic`` package and JAX's version."""
    return source_digest(PACKAGE.rglob("*.py"), salt=f"jax {jax.__version__}")


def machine() -> tuple:
    """Return what a compiled program is specific to besides its code: the backend, the
    devices' kind and number, and the XLA flags it was compiled under."""
    devices = jax.devices()
    return (
        jax.default_backend(),
        devices[0].device_kind,
        len(devices),
        os.environ.get("XLA_FLAGS", ""),
    )


def store_dir() -> Path | None:
    """Return where exported programs are kept: ``STORE`` inside JAX's compilation cache
    directory in use, or None when JAX has none (then nothing is stored)."""
    cache = jax.config.jax_compilation_cache_dir
    return Path(cache) / STORE if cache else None


class StoredProgram:
    """The jitted function ``build()`` makes, its compiled program kept in ``store_dir()``
    under ``key`` (the caller's ``fingerprint`` of what that function closes over) and the
    arguments' shapes and dtypes: a later process with the same key loads the program and
    neither builds nor traces the function. Positional array arguments only; one program
    per distinct shapes and dtypes, as ``jax.jit``. ``options`` are XLA compiler options
    (``jax.stages.Lowered.compile``'s ``compiler_options``), part of the key."""

    def __init__(
        self, build: Callable[[], Callable], key: str, options: dict | None = None
    ) -> None:
        self.build, self.key, self.options = build, key, options
        self.programs: dict[tuple, Callable] = {}
        self._compiling = threading.Lock()  # threads calling at once compile a program once

    def __call__(self, *args):
        specs = [jax.ShapeDtypeStruct(np.shape(a), _dtype(a)) for a in args]
        sig = tuple((s.shape, s.dtype.str) for s in specs)
        with self._compiling:
            if sig not in self.programs:
                key = fingerprint(self.key, sig, self.options)
                self.programs[sig] = _program(self.build, key, specs, self.options)
        return self.programs[sig](*args)


def _dtype(a) -> np.dtype:
    """Return the dtype JAX gives argument ``a`` (float64 as float32 unless x64 is on)."""
    dtype = a.dtype if hasattr(a, "dtype") else np.result_type(a)
    return np.dtype(jax.dtypes.canonicalize_dtype(dtype))


def _program(
    build: Callable[[], Callable], key: str, specs: list, options: dict | None = None
) -> Callable:
    """Return the compiled program for ``specs``: loaded from the store, else built, traced,
    compiled under XLA ``options`` and stored (kept only in memory when there is no store)."""
    where = store_dir()
    path = None if where is None else where / f"{fingerprint(key, machine(), code_version())}.bin"
    compiled = None if path is None else _load(path)
    if compiled is None:
        with collector_paused():
            compiled = jax.jit(build()).lower(*specs).compile(compiler_options=options)
        if path is not None:
            try:
                _write(path, pickle.dumps(serialize(compiled)))
            except (ValueError, NotImplementedError):  # a program JAX cannot serialize: not kept
                pass

    def run(*args):
        return compiled(*(jnp.asarray(a, s.dtype) for a, s in zip(args, specs, strict=True)))

    return run


@contextmanager
def collector_paused() -> Iterator[None]:
    """Run the body with Python's cyclic garbage collector paused (restored after, if it was
    on). Tracing and differentiating a program allocates tens of thousands of objects that
    live until the trace ends; with the collector on they set off collections that walk them
    again and again, and a full one walks every object the process holds (docs/performance.md,
    "The gradient's cold compile, second look")."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


def _load(path: Path) -> Callable | None:
    """Return the program stored at ``path``, or None when there is none or it cannot be
    loaded (a broken or foreign file: the caller compiles anew)."""
    try:
        payload, in_tree, out_tree = pickle.loads(path.read_bytes())
        return deserialize_and_load(payload, in_tree, out_tree)
    except Exception:  # whatever a missing, truncated or foreign file raises
        return None


def _write(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` whole or not at all (a rename), so that processes sharing
    the store never read half a program; a store that cannot be written keeps nothing."""
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-")
        with os.fdopen(fd, "wb") as out:
            out.write(data)
        os.replace(tmp, path)
    except OSError:  # a read-only or full cache directory: the program runs, unstored
        if tmp is not None:
            Path(tmp).unlink(missing_ok=True)
