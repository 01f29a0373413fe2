"""The JAX backend: conformance with the Numba kernel, gradients, Adam, compile-once."""

from __future__ import annotations

import io
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

jax = pytest.importorskip("jax")
pytest.importorskip("optax")

import jax.numpy as jnp  # noqa: E402

import zoetic  # noqa: E402
from zoetic.bodies import list_animals, load_animal  # noqa: E402
from zoetic.control import frequency_domain, time_domain, wave_controller  # noqa: E402
from zoetic.control.jax_sampling import jax_table  # noqa: E402
from zoetic.learning.gradient import (  # noqa: E402
    GradientDescent,
    make_loss,
    optimize_gradient,
    swim_distance,
)
from zoetic.physics import rest_state, simulate  # noqa: E402
from zoetic.physics.jax_backend import blown_up, make_rollout  # noqa: E402
from zoetic.physics.reference import simulate_reference  # noqa: E402

# Both backends step in float32 from the same arrays; they differ only in the order of
# floating-point operations, so each step adds a few ulps (float32 eps 6e-8 on ~1 m bodies)
# and 400 steps stay well within 2e-5 m (measured: at most 1e-6 m, snake on the ground and
# dolphin at the surface included). Over thousands of steps friction and surface crossings
# are discontinuous, and tiny differences can grow, so the horizon is kept at 400 steps.
CONFORMANCE_STEPS = 400
CONFORMANCE_TOL = 2e-5  # m


def _random_smooth(rng, body, steps, hold=20, batch=1):
    n = -(-steps // hold)
    a = rng.random((batch, n, body.n_actuators))
    return np.repeat(a, hold, axis=1)[:, :steps]


@pytest.mark.parametrize("name", list_animals())
def test_jax_matches_numba_kernel(name):
    body = load_animal(name)
    rng = np.random.default_rng(11)
    steps = CONFORMANCE_STEPS
    act = _random_smooth(rng, body, steps, batch=2)
    st = rest_state(body, 2, velocity=(0.2, 0.3 if name == "dolphin" else 0.0, 0.1))
    tr = simulate(body, act, state=st, record_every=100)
    rec, x, v = make_rollout(body, record_every=100)(st.positions, st.velocities, act)
    assert np.asarray(rec).shape == tr.positions.shape
    assert np.abs(np.asarray(x) - tr.final.positions).max() < CONFORMANCE_TOL
    assert np.abs(np.asarray(rec) - tr.positions).max() < CONFORMANCE_TOL
    assert np.abs(np.asarray(v) - tr.final.velocities).max() < 100 * CONFORMANCE_TOL
    assert not np.asarray(blown_up(x, v)).any()


def test_jax_tables_match_controller_tables():
    body = load_animal("shark")
    rng = np.random.default_rng(2)
    steps, dt = 240, body.dt
    a = body.n_actuators
    ctrls = [
        time_domain(body, 5, 1.0, rng.uniform(-0.2, 1.2, (a, 5))),  # clipped, past duration
        time_domain(body, 6, 1.2, rng.uniform(0, 1, (a, 6)), interp="bspline"),
        frequency_domain(body, 5, 0.8, rng.uniform(-0.4, 0.6, (a, 5))),
        wave_controller(body),
    ]
    for ctrl in ctrls:
        table = jax_table(ctrl, steps, dt, t0=0.1)(jnp.asarray(ctrl.params(), jnp.float32))
        assert np.abs(np.asarray(table) - ctrl.table(steps, dt, t0=0.1)).max() < 1e-5, ctrl.kind


@pytest.mark.slow
def test_gradient_matches_finite_differences():
    body = load_animal("shark")
    steps, dt = 150, body.dt
    ctrl = time_domain(body, 5, steps * dt)
    p = np.random.default_rng(0).uniform(0.2, 0.8, ctrl.params().size)
    head = body.head
    loss = make_loss(body, ctrl, steps, lambda rec, x, v: x[head, 0])
    value, grad = jax.jit(jax.value_and_grad(loss))(jnp.asarray(p, jnp.float32))
    grad = np.asarray(grad)
    # central differences of the float64 NumPy reference, all 2n runs as one batch
    eps = 1e-4
    ps = np.concatenate([p + eps * np.eye(p.size), p - eps * np.eye(p.size)])
    acts = np.stack([ctrl.with_params(q).table(steps, dt) for q in ps])
    nose = simulate_reference(body, acts, state=rest_state(body, len(ps))).positions[:, head, 0]
    fd = (nose[: p.size] - nose[p.size :]) / (2 * eps)
    assert np.all(np.isfinite(grad))
    assert np.linalg.norm(grad - fd) / np.linalg.norm(fd) < 0.05  # measured ~4e-6
    ref = simulate_reference(body, ctrl.with_params(p).table(steps, dt)).positions[0, head, 0]
    assert abs(float(value) - ref) < 1e-5


@pytest.mark.slow
def test_adam_makes_the_shark_swim_farther():
    body = load_animal("shark")
    steps = 200
    ctrl = time_domain(body, 5, steps * body.dt)
    x0 = np.random.default_rng(1).uniform(0.3, 0.7, ctrl.params().size)
    lower, upper = ctrl.bounds()
    loss = make_loss(body, ctrl, steps, swim_distance(body))
    best_x, best_f, history = optimize_gradient(loss, x0, lower, upper, steps=8, learning_rate=0.05)
    assert len(history) == 8
    assert best_f < history[0]["value"] - 1e-3  # at least 1 mm farther in 1 s
    assert np.all(best_x >= lower) and np.all(best_x <= upper)
    assert abs(float(loss(jnp.asarray(best_x, jnp.float32))) - best_f) < 1e-6


@pytest.mark.slow
def test_compiles_once_and_reuses_the_compiled_code():
    body = load_animal("shark")
    steps = 50
    traces = []

    def objective(rec, x, v):
        traces.append(1)  # runs only while JAX traces
        return jnp.sum(x[:, 0])

    ctrl = time_domain(body, 5, steps * body.dt)
    vg = jax.jit(jax.value_and_grad(make_loss(body, ctrl, steps, objective)))
    for p in (0.4, 0.6, 0.5):
        jax.block_until_ready(vg(jnp.full(ctrl.params().size, p, jnp.float32)))
    assert len(traces) == 1
    roll = make_rollout(body, record_every=10)
    st = rest_state(body, 3)
    rng = np.random.default_rng(3)
    for _ in range(3):
        jax.block_until_ready(roll(st.positions, st.velocities, rng.random((3, steps, 6))))
    assert len(roll.programs) == 1


def test_gradient_state_saves_and_resumes_exactly():
    opt = GradientDescent(learning_rate=0.1)

    def vg(x):
        return jax.value_and_grad(lambda y: jnp.sum((y - 0.3) ** 2))(x)

    st = opt.init(np.array([2.0, -1.0, 0.5]), [-3.0, -3.0, 0.0], [3.0, 3.0, 1.0], seed=4)
    for _ in range(3):
        st = opt.step(st, vg)
    buf = io.BytesIO()
    np.savez(buf, **opt.state_to_numpy(st))
    buf.seek(0)
    restored = opt.state_from_numpy(dict(np.load(buf)))
    a, b = opt.step(st, vg), opt.step(restored, vg)
    assert np.array_equal(opt.x(a), opt.x(b))
    assert float(a.best_f) == float(b.best_f)


def test_non_finite_loss_never_becomes_the_best_and_bounds_hold():
    opt = GradientDescent(learning_rate=0.5)
    good = jax.value_and_grad(lambda y: jnp.sum(y))
    st = opt.step(opt.init(np.full(2, 0.5), np.zeros(2), np.ones(2)), good)
    best = float(st.best_f)
    st = opt.step(st, lambda x: (jnp.nan, jnp.full(2, jnp.nan)))
    assert float(st.best_f) == best and int(st.failures) == 1
    for _ in range(5):
        st = opt.step(st, good)
    x = opt.x(st)
    assert np.all(x >= 0.0) and np.all(x <= 1.0) and np.all(np.isfinite(x))
    assert int(st.failures) == 0


def test_blow_up_is_detected():
    body = load_animal("shark")
    act = wave_controller(body).table(300, body.dt)[None]
    st = rest_state(body, 1)
    # a too-large step is substepped where stiff (multirate), so tear the body apart instead
    st.positions[:, 0, 1] += 100.0
    _, x, v = make_rollout(body, record_every=300)(st.positions, st.velocities, act)
    assert np.asarray(blown_up(x, v)).all()


def test_core_packages_do_not_import_jax():
    code = (
        "import sys, zoetic.bodies, zoetic.control, zoetic.physics, zoetic.physics.reference;"
        "sys.exit('jax' in sys.modules)"
    )
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


def test_a_batch_in_chunks_matches_the_kernel_and_shared_activations_match_one_by_one(
    monkeypatch,
):
    from zoetic.physics import jax_backend
    from zoetic.physics.jax_backend import rollout_fn

    monkeypatch.setattr(jax_backend, "CPU_LANES", 2)  # 5 candidates: 3 chunks, one padded
    body = load_animal("shark")
    rng = np.random.default_rng(5)
    act = _random_smooth(rng, body, 120, batch=5)
    st = rest_state(body, 5, velocity=(0.1, 0.0, 0.2))
    tr = simulate(body, act, state=st, record_every=40)
    rec, x, _ = make_rollout(body, record_every=40)(st.positions, st.velocities, act)
    assert np.asarray(rec).shape == tr.positions.shape
    assert np.abs(np.asarray(rec) - tr.positions).max() < CONFORMANCE_TOL
    # one activation table (T, A) for a batch of starts: as each start rolled out alone
    roll = rollout_fn(body, record_every=40)
    rec_b, _, _ = roll(st.positions[:3], st.velocities[:3], act[0])
    for k in range(3):
        rec_k, _, _ = roll(st.positions[k], st.velocities[k], act[0])
        assert np.abs(np.asarray(rec_b[k]) - np.asarray(rec_k)).max() < 1e-6
    # the chunked rollout with one table for every start, as (T, A) or (1, T, A): as the
    # table repeated for each start
    rollout = make_rollout(body, record_every=40)
    rec_all, _, _ = rollout(st.positions, st.velocities, np.repeat(act[:1], 5, axis=0))
    for table in (act[0], act[:1]):
        rec_one, _, _ = rollout(st.positions, st.velocities, table)
        assert np.asarray(rec_one).shape == tr.positions.shape
        assert np.abs(np.asarray(rec_one) - np.asarray(rec_all)).max() < 1e-6


def test_cache_dir_follows_the_environment(monkeypatch, tmp_path):
    from zoetic.physics.jax_backend import CACHE_ENV, cache_dir

    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "mine"))
    assert cache_dir() == tmp_path / "mine"
    monkeypatch.setenv(CACHE_ENV, "")
    assert cache_dir() is None  # empty: no persistent cache
    monkeypatch.delenv(CACHE_ENV)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_dir() == tmp_path / "xdg" / "zoetic" / "jax"


def _cache_dir_in_a_fresh_process(env: dict) -> str:
    code = (
        "import jax, jax.numpy as jnp\n"
        "import zoetic.physics.jax_backend as jb\n"
        "from zoetic.bodies import load_animal\n"
        "from zoetic.physics import rest_state\n"
        "body = load_animal('shark')\n"
        "st = rest_state(body, 1)\n"
        "act = jnp.zeros((1, 3, body.n_actuators))\n"
        "jb.make_rollout(body)(st.positions, st.velocities, act)\n"
        "print(jax.config.jax_compilation_cache_dir)\n"
    )
    full = {k: v for k, v in os.environ.items() if not k.startswith(("JAX_", "ZOETIC_JAX"))}
    full.update(env, JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS="0")
    full["PYTHONPATH"] = str(Path(zoetic.__file__).parents[1])  # this checkout's package
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=full)
    assert out.returncode == 0, out.stderr
    return out.stdout.strip().splitlines()[-1]


def test_compiled_programs_persist_where_zoetic_or_the_user_says(tmp_path):
    ours = tmp_path / "ours"
    assert _cache_dir_in_a_fresh_process({"ZOETIC_JAX_CACHE": str(ours)}) == str(ours)
    assert any(ours.iterdir())  # the rollout's compiled program was written there
    theirs = tmp_path / "theirs"
    env = {"ZOETIC_JAX_CACHE": str(ours), "JAX_COMPILATION_CACHE_DIR": str(theirs)}
    assert _cache_dir_in_a_fresh_process(env) == str(theirs)  # the user's own setting wins
    assert any(theirs.iterdir())
    assert _cache_dir_in_a_fresh_process({"ZOETIC_JAX_CACHE": ""}) == "None"


def test_the_bench_times_a_cold_cache_and_restores_the_users(tmp_path):
    from zoetic.bench.jax_sim import compile_cold_and_cached, fresh_compilation_cache

    before = jax.config.jax_compilation_cache_dir
    seen = []

    def make():
        seen.append(jax.config.jax_compilation_cache_dir)
        return lambda: jax.jit(lambda q: q * 2.0 + 1.0)(jnp.ones(3))

    cold, cached = compile_cold_and_cached(make)
    assert cold > 0 and cached > 0
    assert len(seen) == 2 and seen[0] == seen[1] != before  # one fresh directory for both
    assert jax.config.jax_compilation_cache_dir == before
    with fresh_compilation_cache():
        assert jax.config.jax_compilation_cache_dir != before
    assert jax.config.jax_compilation_cache_dir == before


def test_the_suite_keeps_compiled_programs_out_of_the_users_cache():
    from conftest import JAX_TEST_CACHE
    from zoetic.physics.jax_backend import cache_dir

    assert cache_dir() == Path(JAX_TEST_CACHE)
    assert jax.config.jax_compilation_cache_dir == JAX_TEST_CACHE
