"""The law's two JAX forms of reading and spreading node rows (incidence matrices and gathers)
step every animal alike and give the same gradients."""

from __future__ import annotations

import numpy as np
import pytest

jax = pytest.importorskip("jax")

import jax.numpy as jnp  # noqa: E402

from zoetic.bodies import list_animals, load_animal  # noqa: E402
from zoetic.physics import law  # noqa: E402
from zoetic.physics.model import compile_model  # noqa: E402
from zoetic.physics.simulate import rest_state  # noqa: E402

STEPS = 300
# Both forms are float32 and differ only in the order of the sums onto a node (a matrix
# product against a scatter-add): a few ulps a step on ~1 m bodies (measured: below 1e-6 m
# after 200 steps).
TOL = 1e-5  # m


def _rollout(m, x, v, acts, dense: bool, monkeypatch):
    """Return the final (x, v) (N, 3, B) of ``STEPS`` law steps in the chosen form."""
    monkeypatch.setattr(law, "DENSE_NODES", 10**6 if dense else -1)

    def run(x, v, acts):
        def one(carry, a):
            return law.step_soa(jnp, m, *carry, a), None

        return jax.lax.scan(one, (x, v), acts)[0]

    return jax.jit(run)(x, v, acts)  # traced anew: a new function each call


def _start(body, rng, batch: int):
    """Return the rest state moving at 0.2 m/s and smooth random activations: a start whose
    motion is not chaotic (a random deformation on the floor is: there a 1e-7 m change of
    the start moves the snake's nodes by 2 mm within 300 steps)."""
    st = rest_state(body, batch, velocity=(0.2, 0.0, 0.1))
    acts = np.repeat(rng.random((STEPS // 20, body.n_actuators, batch)), 20, axis=0)
    x, v = (law.to_soa(jnp, jnp.asarray(q, jnp.float32)) for q in (st.positions, st.velocities))
    return (x, v), jnp.asarray(acts, jnp.float32)


@pytest.mark.parametrize("name", list_animals())
@pytest.mark.parametrize("batch", [2, 16])  # the gradient's narrow batch and a wide one
def test_dense_and_gathered_steps_move_every_animal_alike(name, batch, monkeypatch):
    body = load_animal(name)
    m = compile_model(body)
    assert law.dense(jnp, body.n_nodes)  # every animal of the zoo steps densely
    (x, v), acts = _start(body, np.random.default_rng(5), batch)
    xd, vd = _rollout(m, x, v, acts, True, monkeypatch)
    xg, vg = _rollout(m, x, v, acts, False, monkeypatch)
    moved = np.abs(np.asarray(xg) - np.asarray(x)).max()
    assert moved > 100 * TOL  # the bodies move, so equal positions say something
    lanes = np.abs(np.asarray(xd) - np.asarray(xg)).max(axis=(0, 1))  # (B,)
    if not m.floor:
        assert lanes.max() < TOL
        assert np.abs(np.asarray(vd) - np.asarray(vg)).max() < 100 * TOL
    else:  # a node touching y = 0 a step apart (the floor's onset is discontinuous): a jump
        # of at most a step's penalty (measured 4.7e-4 m in one lane of 16), else ulps
        assert lanes.max() < 1e-3 and np.mean(lanes < TOL) >= 0.75


@pytest.mark.parametrize("name", ["shark", "snake"])  # water with fins; the floor
def test_dense_and_gathered_steps_give_the_same_gradient(name, monkeypatch):
    body = load_animal(name)
    m = compile_model(body)
    (x, v), acts = _start(body, np.random.default_rng(6), 2)
    acts = acts[:100]

    def grad(dense: bool):
        monkeypatch.setattr(law, "DENSE_NODES", 10**6 if dense else -1)

        def nose_x(acts):
            def one(carry, a):
                return law.step_soa(jnp, m, *carry, a), None

            xf, _ = jax.lax.scan(one, (x, v), acts)[0]
            return jnp.sum(xf[body.head, 0])

        return np.asarray(jax.jit(jax.grad(nose_x))(acts))

    gd, gg = grad(True), grad(False)
    assert np.all(np.isfinite(gd)) and np.abs(gg).max() > 0
    assert np.abs(gd - gg).max() < 1e-3 * np.abs(gg).max()


def test_incidence_matrices_read_and_spread_as_the_gathers_do():
    rng = np.random.default_rng(3)
    a, b = np.array([0, 2, 4, 4]), np.array([1, 4, 0, 3])
    nodes = np.array([[4, 0, 2, 2], [1, 3, 4, 0]])  # a triangle repeats its third corner
    w = np.array([[0.25, 0.25, 0.5, 0.0], [0.25, 0.25, 0.25, 0.25]])
    q = rng.normal(size=(5, 3, 7))
    f, s = rng.normal(size=(4, 3, 7)), rng.normal(size=(2, 7))
    np.testing.assert_allclose(
        np.asarray(law.edges(jnp, jnp.asarray(q, jnp.float32), a, b)), q[b] - q[a], atol=1e-6
    )
    spread = np.zeros((5, 3, 7))
    np.add.at(spread, a, f)
    np.add.at(spread, b, -f)
    got = law.onto_ends(jnp, jnp.asarray(f, jnp.float32), a, b, 5)
    np.testing.assert_allclose(np.asarray(got), spread, atol=1e-5)
    shares = np.zeros((5, 3, 7))
    for k in range(2):
        for c in range(4):
            shares[nodes[k, c]] += w[k, c] * s[k] * f[k]
    got = law.onto_corners(jnp, jnp.asarray(s), jnp.asarray(f[:2]), nodes, w, 5)
    np.testing.assert_allclose(np.asarray(got), shares, atol=1e-5)
    assert not law.dense(np, 5)  # the float64 reference sums in order, through the gathers
