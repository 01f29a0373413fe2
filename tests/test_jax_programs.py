"""Compiled JAX programs kept between runs: loaded, not traced, under the right key only."""

from __future__ import annotations

import gc
from dataclasses import dataclass

import numpy as np
import pytest

jax = pytest.importorskip("jax")

import jax.numpy as jnp  # noqa: E402

from zoetic.bench.jax_sim import compilation_cache_in, fresh_compilation_cache  # noqa: E402
from zoetic.physics.jax_programs import (  # noqa: E402
    StoredProgram,
    collector_paused,
    fingerprint,
    store_dir,
)

X = np.linspace(0.0, 1.0, 12, dtype=np.float32).reshape(3, 4)
Y = np.full((3, 4), 0.5, dtype=np.float32)


def _counted(scale: float):
    """Return a builder of f(x, y) = (sin(x) * scale + y, sum(x)) and the list its calls
    append to (a build is what tracing needs)."""
    builds: list[int] = []

    def build():
        builds.append(1)
        return lambda x, y: (jnp.sin(x) * scale + y, jnp.sum(x))

    return build, builds


def _stored() -> list:
    return sorted(store_dir().iterdir())


def test_a_program_with_the_same_key_is_loaded_and_computes_the_same():
    with fresh_compilation_cache():
        build, builds = _counted(2.0)
        first = StoredProgram(build, fingerprint("f", 2.0))(X, Y)
        assert len(builds) == 1 and len(_stored()) == 1
        later, later_builds = _counted(2.0)
        again = StoredProgram(later, fingerprint("f", 2.0))(X, Y)
        assert later_builds == []  # loaded from the store: never built, never traced
        expected = jax.jit(build())(X, Y)
        for a, b, c in zip(first, again, expected, strict=True):
            np.testing.assert_array_equal(np.asarray(a), np.asarray(c))
            np.testing.assert_array_equal(np.asarray(b), np.asarray(c))


def test_a_new_key_or_new_shapes_make_a_new_program():
    with fresh_compilation_cache():
        build, builds = _counted(2.0)
        StoredProgram(build, fingerprint("f", 2.0))(X, Y)
        other, other_builds = _counted(3.0)
        out = StoredProgram(other, fingerprint("f", 3.0))(X, Y)
        assert len(other_builds) == 1  # another key: its own program, not the first one's
        np.testing.assert_allclose(np.asarray(out[0]), np.sin(X) * 3.0 + Y, rtol=1e-6)
        wide = StoredProgram(build, fingerprint("f", 2.0))
        wide(X[:, :2], Y[:, :2])
        wide(X[:, :2].astype(np.float64), Y[:, :2])  # float64 is float32 to JAX: same program
        assert len(builds) == 2 and len(wide.programs) == 1 and len(_stored()) == 3


def test_a_broken_stored_program_is_compiled_anew_and_replaced():
    with fresh_compilation_cache():
        build, _ = _counted(2.0)
        StoredProgram(build, fingerprint("f", 2.0))(X, Y)
        (path,) = _stored()
        path.write_bytes(b"not a program")
        again, builds = _counted(2.0)
        out = StoredProgram(again, fingerprint("f", 2.0))(X, Y)
        assert len(builds) == 1
        np.testing.assert_allclose(np.asarray(out[0]), np.sin(X) * 2.0 + Y, rtol=1e-6)
        third, third_builds = _counted(2.0)
        StoredProgram(third, fingerprint("f", 2.0))(X, Y)
        assert third_builds == []  # the rewritten file loads


def test_without_a_cache_directory_nothing_is_stored():
    with compilation_cache_in(None):
        assert store_dir() is None
        build, builds = _counted(2.0)
        program = StoredProgram(build, fingerprint("f", 2.0))
        out = program(X, Y)
        program(X, Y)
        assert len(builds) == 1  # compiled once, in this process only
        np.testing.assert_allclose(np.asarray(out[1]), X.sum(), rtol=1e-6)


@dataclass
class _Part:
    name: str
    values: np.ndarray


def test_a_fingerprint_sees_every_value_dtype_and_shape():
    a = np.arange(6, dtype=np.float32)
    key = fingerprint(_Part("p", a), (1.0, 2), {"k": None})
    assert fingerprint(_Part("p", a.copy()), (1.0, 2), {"k": None}) == key
    changed = a.copy()
    changed[3] = np.nextafter(changed[3], np.float32(10.0))  # one ulp of one element
    assert fingerprint(_Part("p", changed), (1.0, 2), {"k": None}) != key
    assert fingerprint(_Part("p", a.astype(np.float64)), (1.0, 2), {"k": None}) != key
    assert fingerprint(_Part("p", a.reshape(2, 3)), (1.0, 2), {"k": None}) != key
    assert fingerprint(_Part("p", a), (1, 2), {"k": None}) != key  # 1 is not 1.0
    assert fingerprint(_Part("q", a), (1.0, 2), {"k": None}) != key
    with pytest.raises(TypeError, match="cannot key"):
        fingerprint(_Part("p", a), object())


def test_compiler_options_are_part_of_the_key():
    with fresh_compilation_cache():
        level1 = {"xla_backend_optimization_level": 1}
        build, builds = _counted(2.0)
        first = StoredProgram(build, fingerprint("f", 2.0), level1)(X, Y)
        plain, plain_builds = _counted(2.0)
        StoredProgram(plain, fingerprint("f", 2.0))(X, Y)
        assert len(plain_builds) == 1  # compiled under other options: its own program
        again, again_builds = _counted(2.0)
        out = StoredProgram(again, fingerprint("f", 2.0), dict(level1))(X, Y)
        assert again_builds == [] and len(_stored()) == 2  # the same options: loaded
        np.testing.assert_allclose(np.asarray(out[0]), np.asarray(first[0]), rtol=1e-6)
        np.testing.assert_allclose(np.asarray(out[0]), np.sin(X) * 2.0 + Y, rtol=1e-6)


def test_a_program_is_traced_with_the_collector_paused_and_restored_after():
    seen: list[bool] = []

    def build():
        def f(x):
            seen.append(gc.isenabled())  # runs while JAX traces f
            return jnp.cos(x)

        return f

    assert gc.isenabled()
    with fresh_compilation_cache():
        StoredProgram(build, fingerprint("gc"))(X)
    assert seen == [False] and gc.isenabled()
    gc.disable()
    try:
        with collector_paused():
            pass
        assert not gc.isenabled()  # a collector the caller had paused stays paused
    finally:
        gc.enable()


def test_the_collector_is_back_on_after_a_failed_trace():
    assert gc.isenabled()
    with pytest.raises(RuntimeError), collector_paused():
        assert not gc.isenabled()
        raise RuntimeError("a trace that fails")
    assert gc.isenabled()
