"""The one physical model: one compiled Model per body, one force law for NumPy and JAX, and
the Numba kernel equal to it."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.bodies import list_animals, load_animal
from zoetic.physics import State, law, simulate
from zoetic.physics.model import Model, compile_model

MEDIA = (None, "sea", "ground", "vacuum")


def _state(body, rng, batch=2):
    """A moving, slightly deformed state, a few cm under water or on the floor."""
    x = body.rest_pos + body.start_offset + rng.normal(0.0, 0.01, (batch, body.n_nodes, 3))
    v = rng.normal(0.0, 0.3, (batch, body.n_nodes, 3))
    a = rng.random((batch, body.n_actuators))
    return x, v, a


def test_a_model_is_built_once_per_body_object_never_by_name():
    body = load_animal("shark")
    m = compile_model(body)
    assert compile_model(body, body.medium, body.dt) is m
    assert compile_model(body, dt=body.dt / 2) is not m
    twin = body.with_(stiffness=body.stiffness * 2)  # same name, other content
    assert twin.name == body.name and compile_model(twin) is not m
    np.testing.assert_array_equal(compile_model(twin).stiffness, 2 * m.stiffness)
    assert compile_model(body, dtype=np.float64).mass.dtype == np.float64
    assert not m.mass.flags.writeable  # shared by every caller: read-only


@pytest.mark.parametrize("name", list_animals())
def test_every_model_has_the_kernels_numba_type(name):
    from numba import typeof

    from zoetic.physics.kernel import MODEL

    for med in MEDIA:
        assert typeof(compile_model(load_animal(name), med)) == MODEL


@pytest.mark.parametrize("name", list_animals())
def test_numpy_and_jax_run_the_same_force_law(name):
    jnp = pytest.importorskip("jax.numpy")
    body = load_animal(name)
    rng = np.random.default_rng(7)
    for med in MEDIA:
        m32, m64 = compile_model(body, med), compile_model(body, med, dtype=np.float64)
        x, v, a = _state(body, rng)
        every = np.arange(body.n_springs)
        f_np = law.forces(np, m64, x, v, a, every)
        f_jx = law.forces(jnp, m32, *(jnp.asarray(q, jnp.float32) for q in (x, v, a)), every)
        scale = np.abs(f_np).max()
        assert np.abs(np.asarray(f_jx) - f_np).max() < 1e-5 * scale, med
        xs_np, vs_np = law.step(np, m64, x, v, a)
        xs_jx, vs_jx = law.step(jnp, m32, *(jnp.asarray(q, jnp.float32) for q in (x, v, a)))
        assert np.abs(np.asarray(xs_jx) - xs_np).max() < 1e-5, med
        assert np.abs(np.asarray(vs_jx) - vs_np).max() < 1e-4 * np.abs(vs_np).max(), med


@pytest.mark.parametrize("name", list_animals())
def test_the_numba_kernel_takes_the_law_s_step(name):
    body = load_animal(name)
    rng = np.random.default_rng(8)
    for med in MEDIA:
        x, v, a = _state(body, rng)
        tr = simulate(body, a[:, None, :], medium=med, state=State(x, v), check_step=False)
        xs, vs = law.step(np, compile_model(body, med, dtype=np.float64), x, v, a)
        assert np.abs(tr.final.positions - xs).max() < 2e-6, med
        assert np.abs(tr.final.velocities - vs).max() < 1e-4 * np.abs(vs).max(), med


def test_the_law_leaves_its_inputs_alone():
    body = load_animal("shark")
    x, v, a = _state(body, np.random.default_rng(9))
    before = [q.copy() for q in (x, v, a)]
    law.step(np, compile_model(body, dtype=np.float64), x, v, a)
    for q, q0 in zip((x, v, a), before, strict=True):
        np.testing.assert_array_equal(q, q0)


def test_model_fields_are_named_once():
    # every backend reads the model by field name; its fields cover the medium's constants
    from dataclasses import fields

    from zoetic.physics.media import Medium

    medium = {f.name for f in fields(Medium)} - {"name"}
    assert medium <= set(Model._fields)


def test_jax_scatters_onto_nodes_what_numpy_sums_through_the_incidence_table():
    jnp = pytest.importorskip("jax.numpy")
    rng = np.random.default_rng(3)
    targets = np.array([4, 0, 4, 2, 4, 0])  # node 1 and 3 get nothing, node 4 three rows
    values = rng.normal(size=(targets.size, 3, 5))
    expected = np.zeros((5, 3, 5))
    for k, node in enumerate(targets):
        expected[node] += values[k]
    got_np = law.gather_sum(np, values, targets, 5)
    got_jx = law.gather_sum(jnp, jnp.asarray(values, jnp.float32), targets, 5)
    assert np.allclose(got_np, expected, rtol=0, atol=1e-12)
    assert np.allclose(np.asarray(got_jx), expected, rtol=0, atol=1e-5)
    empty = law.gather_sum(jnp, jnp.zeros((0, 3, 5)), np.zeros(0, dtype=np.int64), 5)
    assert empty.shape == (5, 3, 5) and not np.asarray(empty).any()
