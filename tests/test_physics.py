"""Physics checks: conservation, symmetry, convergence, stability, and no free lunch."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.bodies import list_animals, load_animal
from zoetic.control import rest_controller, wave_controller
from zoetic.physics import State, get_medium, rest_state, simulate
from zoetic.physics.reference import simulate_reference


def _undamped(body):
    return body.with_(node_damping=np.zeros(body.n_nodes), spring_damping=np.zeros(body.n_springs))


def _random_smooth(rng, body, steps, hold=20, batch=1):
    """Random activations held for ``hold`` steps: random but not white noise."""
    n = -(-steps // hold)
    a = rng.random((batch, n, body.n_actuators))
    return np.repeat(a, hold, axis=1)[:, :steps]


def _energy(body, x, v, a):
    ke = 0.5 * np.sum(body.mass * np.sum(v * v, axis=-1), axis=-1)
    length = np.linalg.norm(x[..., body.spring_b, :] - x[..., body.spring_a, :], axis=-1)
    act = np.where(body.spring_actuator >= 0, a[body.spring_actuator], 0.0)
    rest = body.relaxed + act * (body.contracted - body.relaxed)
    pe = 0.5 * np.sum(body.stiffness * (length - rest) ** 2, axis=-1)
    return ke + pe


def test_momentum_is_conserved_with_internal_forces_only():
    body = load_animal("shark").with_(node_damping=np.zeros(23))
    rng = np.random.default_rng(0)
    st = rest_state(body, 2, velocity=(0.3, -0.2, 0.1))
    st.velocities[:] += rng.normal(0, 0.2, st.velocities.shape)
    act = _random_smooth(rng, body, 2000, batch=2)
    tr = simulate(body, act, medium="vacuum", state=st)
    p0 = np.einsum("n,bnk->bk", body.mass, st.velocities)
    p1 = np.einsum("n,bnk->bk", body.mass, tr.final.velocities)
    assert np.abs(p1 - p0).max() < 1e-4 * np.abs(p0).max()
    # and the centre of mass moves uniformly
    com = tr.com(body)
    expected = com[:, :1] + tr.times[None, :, None] * (p0 / body.total_mass)[:, None, :]
    assert np.abs(com - expected).max() < 1e-4


def test_energy_does_not_grow_without_damping():
    body = _undamped(load_animal("shark"))
    rng = np.random.default_rng(1)
    st = rest_state(body, 1)
    st.velocities[:] = rng.normal(0, 0.3, st.velocities.shape)
    a = np.full(body.n_actuators, 0.3)
    table = np.tile(a, (50, 1))
    energies = []
    for _ in range(160):  # 40 s in pieces of 0.25 s, sampling the energy between them
        st = simulate(body, table, medium="vacuum", state=st, record_every=50).final
        energies.append(_energy(body, st.positions[0], st.velocities[0], a))
    e = np.array(energies)
    # symplectic Euler: the energy oscillates about a constant, with no drift either way
    assert e[-40:].mean() < e[:40].mean() * 1.01
    assert e[-40:].mean() > e[:40].mean() * 0.99
    assert e.max() < e.min() * 1.25  # bounded: O(omega dt) wobble of the stiffest modes


@pytest.mark.parametrize("name", ["shark", "snake", "ray", "dolphin"])
def test_mirrored_activation_gives_mirrored_trajectory(name):
    body = load_animal(name)
    steps = int(2.0 / body.dt)
    act = wave_controller(body).table(steps, body.dt)
    act[:, : body.n_actuators // 2] *= 0.6  # make it lopsided, so the mirror matters
    tr = simulate(body, np.stack([act, body.mirror_actuators(act)]), record_every=20)
    mirrored = tr.positions[1][:, body.node_mirror] * np.array([1.0, 1.0, -1.0])
    assert np.abs(tr.positions[0] - mirrored).max() < 4e-3  # float32 rounding, not a bias
    assert np.abs(tr.positions[0, -1, :, 2] - tr.positions[0, 0, :, 2]).max() > 1e-3


def test_results_converge_as_dt_halves():
    body = load_animal("shark")
    ctrl = wave_controller(body)
    finals = []
    for dt in (0.003, 0.0015, 0.00075, 0.000375):  # all below the multirate split
        steps = int(round(1.5 / dt))
        tr = simulate(body, ctrl.table(steps, dt), dt=dt, record_every=steps)
        finals.append(tr.final.positions[0])
    errs = [np.abs(f - finals[-1]).max() for f in finals[:-1]]
    assert errs[0] > errs[1] > errs[2]
    assert errs[0] / errs[1] > 1.6 and errs[1] / errs[2] > 1.6  # first order, as Euler is


@pytest.mark.parametrize("name", list_animals())
def test_random_activations_for_30_seconds_stay_finite_and_sane(name):
    body = load_animal(name)
    rng = np.random.default_rng(2)
    steps = int(30.0 / body.dt)
    act = _random_smooth(rng, body, steps, hold=10, batch=4)
    tr = simulate(body, act, record_every=50)
    assert not tr.failed.any()
    p = tr.positions
    assert np.isfinite(p).all()
    length = np.linalg.norm(p[..., body.spring_b, :] - p[..., body.spring_a, :], axis=-1)
    ratio = length / body.relaxed
    assert ratio.min() > 0.5 and ratio.max() < 1.5


# The 10 % rule is ours (docs/animals.md, "The zoo and the numbers we chose"). The papers'
# animals (``*-1995``) carry their references' constants unchanged, and the 1995 shark's
# softer body strains 11 % under one actuator held on: for them the bound is 15 %.
PAPER_SHAPE_LIMIT = 0.15


@pytest.mark.parametrize("name", list_animals())
def test_each_animal_keeps_its_shape_under_its_strongest_muscle_action(name):
    body = load_animal(name)
    steps = int(3.0 / body.dt)
    muscles = [k for k, kind in enumerate(body.actuator_kind) if kind == "muscle"]
    acts = np.zeros((len(muscles), steps, body.n_actuators))
    base = rest_controller(body).table(steps, body.dt)
    for row, k in enumerate(muscles):
        acts[row] = base
        acts[row, :, k] = 1.0
    tr = simulate(body, acts, record_every=10)
    p = tr.positions
    length = np.linalg.norm(p[..., body.spring_b, :] - p[..., body.spring_a, :], axis=-1)
    passive = body.spring_actuator < 0
    strain = np.abs(length[..., passive] / body.relaxed[passive] - 1.0)
    assert strain.max() < (PAPER_SHAPE_LIMIT if name.endswith("-1995") else 0.10)


def test_snake_crawls_forward_only_with_directional_friction():
    body = load_animal("snake")
    steps = int(6.0 / body.dt)
    act = wave_controller(body).table(steps, body.dt)
    ground = get_medium("ground")
    slick = ground.with_(friction_forward=0.0, friction_backward=0.0, friction_lateral=0.0)
    moved = []
    for med in (ground, slick):
        tr = simulate(body, act, medium=med, record_every=steps)
        com = tr.com(body)[0]
        moved.append(com[-1] - com[0])
    assert moved[0][0] > 0.5  # metres along the heading
    assert np.linalg.norm(moved[1][[0, 2]]) < 0.02


@pytest.mark.parametrize("name", ["shark", "shark-1995"])
def test_shark_swims_forward_in_water_and_not_in_vacuum(name):
    body = load_animal(name)
    steps = int(6.0 / body.dt)
    act = wave_controller(body).table(steps, body.dt)
    moved = {}
    for med in ("water", "vacuum"):
        # the nodal damping of equation 1 is a drag against the fixed frame, a weak medium of
        # its own: in vacuum the body has none, so nothing outside it can push it anywhere
        b = body if med == "water" else body.with_(node_damping=np.zeros(body.n_nodes))
        tr = simulate(b, act, medium=med, record_every=steps)
        com = tr.com(b)[0]
        moved[med] = com[-1] - com[0]
    assert moved["water"][0] > 2.0
    assert np.linalg.norm(moved["vacuum"]) < 1e-3


def test_dolphin_leaves_the_water_and_falls_back():
    body = load_animal("dolphin")
    steps = int(3.0 / body.dt)
    # nose up at 60 degrees, half a metre deep, shooting along its axis at 10 m/s
    c, s = np.cos(np.pi / 3), np.sin(np.pi / 3)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    pos = body.rest_pos @ rot.T + np.array([0.0, -0.5, 0.0])
    vel = np.tile(10.0 * rot[:, 0], (body.n_nodes, 1))
    st = State(pos[None], vel[None])
    act = rest_controller(body).table(steps, body.dt)
    tr = simulate(body, act, state=st, record_every=5)
    lowest = tr.positions[0, :, :, 1].min(axis=1)
    assert lowest.max() > 0.1  # the whole body was in the air
    airborne = lowest > 0.05
    com_y = tr.com(body)[0, :, 1]
    # ballistic in the air: the centre of mass accelerates at -g
    t, y = tr.times[airborne], com_y[airborne]
    g = -2 * np.polyfit(t, y, 2)[0]
    assert g == pytest.approx(9.81, rel=0.03)
    # and it came back down into the water (floating: buoyancy 1.05 keeps the top of a
    # 1.7 m dolphin, and maybe its centre of mass, just above the surface)
    assert lowest[-1] < -0.1 and com_y[-1] < 0.2


def test_kernel_matches_numpy_reference():
    rng = np.random.default_rng(3)
    for name in list_animals():
        body = load_animal(name)
        steps = 200
        act = _random_smooth(rng, body, steps, batch=2)
        st = rest_state(body, 2, velocity=(0.2, 0.3 if name == "dolphin" else 0.0, 0.1))
        tr = simulate(body, act, state=st, record_every=steps)
        ref = simulate_reference(body, act, state=st)
        assert np.abs(tr.final.positions - ref.positions).max() < 1e-4, name


def test_blow_up_is_reported_not_passed_on():
    body = load_animal("shark")
    steps = 400
    act = wave_controller(body).table(steps, body.dt)
    # a too-large step is now substepped where stiff (multirate), so blow up a state instead:
    # one node thrown at 1 km/s, far beyond anything a muscle can do
    state = rest_state(body, 2)
    state.velocities[:, 0, 0] = 1000.0
    tr = simulate(body, np.stack([act, act]), state=state)
    assert tr.failed.all()
    assert np.isnan(tr.final.positions).all()
    ok = simulate(body, act[None], record_every=steps)
    assert not ok.failed.any()


def test_a_lane_whose_state_goes_nan_is_reported_as_blown_up():
    """A NaN speed fails the speed check like an infinite one, at the first check after it
    appears (every 8 steps), even while other nodes are still finite: the lane's running
    maximum of squared node speeds must not skip it."""
    body = load_animal("shark")
    act = wave_controller(body).table(200, body.dt)
    state = rest_state(body, 2)
    state.velocities[0, 3, 1] = np.nan  # one node of lane 0
    tr = simulate(body, np.stack([act, act]), state=state)
    assert 0 < tr.failed_step[0] <= 8
    assert np.isnan(tr.final.positions[0]).all()
    assert tr.failed_step[1] == -1 and np.isfinite(tr.final.positions[1]).all()


_PLACE_CHECK = """
import numpy as np
from zoetic.bodies import list_animals, load_animal
from zoetic.physics import simulate
bad = []
for name in list_animals():
    body = load_animal(name)
    act = np.random.default_rng(4).uniform(0, 1, (37, 600, body.n_actuators))
    many = simulate(body, act, record_every=600).final.positions
    for lo, hi in ((7, 8), (0, 5), (3, 20), (30, 37)):
        part = simulate(body, act[lo:hi], record_every=600).final.positions
        if not np.array_equal(part, many[lo:hi]):
            bad.append((name, lo, hi, float(np.abs(part - many[lo:hi]).max())))
print(bad)
"""


def test_a_candidates_result_does_not_depend_on_its_place_in_the_batch():
    """The SIMD body and the scalar remainder loop must compute the same thing: a candidate
    gives the same path alone, first, last or mid-batch (else a seed is not reproducible).
    Checked here and in a fresh process, which runs the kernel from Numba's on-disk cache:
    that code once differed from the freshly compiled one (fast-math reassociation)."""
    import subprocess
    import sys

    scope: dict = {}
    exec(_PLACE_CHECK, scope)
    assert scope["bad"] == [], "in process"
    out = subprocess.run(
        [sys.executable, "-c", _PLACE_CHECK], capture_output=True, text=True, check=True
    )
    assert out.stdout.strip() == "[]", f"from the cache: {out.stdout}"


def test_stiff_springs_are_substepped_and_stay_stable_at_the_animals_step():
    from zoetic.physics.multirate import omega_max, split

    body = load_animal("shark")
    # the stiff caudal fin is beyond the explicit step's limit; its springs are substepped
    assert omega_max(body) * body.dt > 2.0
    slow, fast, substeps = split(body, body.dt)[:3]
    assert 0 < len(fast) < len(slow) and substeps >= 2
    assert omega_max(body, slow) * body.dt < 2.0
    assert omega_max(body) * body.dt / substeps < 2.0
    # at rest for 20 s (float32 round-off seeds every mode: an unstable split grows it) and
    # under the wave, nothing blows up, and 5 ms agrees with a 0.5 ms run as the 5 ms
    # explicit step did before the fin was stiffened (a few cm after 1.5 s)
    steps = 4000
    act = wave_controller(body).table(steps, body.dt)
    tr = simulate(body, np.stack([act * 0.0, act]), record_every=steps)
    assert not tr.failed.any()
    assert np.abs(tr.final.velocities[0]).max() < 1e-3
    fine = simulate(body, wave_controller(body).table(3000, 0.0005), dt=0.0005, record_every=3000)
    coarse = simulate(body, act[:300], record_every=300)
    assert np.abs(coarse.final.positions - fine.final.positions).max() < 0.05


def test_shark_fins_pitch_and_roll_the_right_way_and_mirror():
    body = load_animal("shark")
    steps = 300  # 1.5 s of the wave with the fins held
    wave = wave_controller(body).table(steps, body.dt)
    fl, fr = body.actuator_names.index("fin_left"), body.actuator_names.index("fin_right")
    assert np.allclose(wave[:, [fl, fr]], 0.5)  # not in [wave].phases: held level
    tabs = []
    for a_left, a_right in ((0.5, 0.5), (1.0, 1.0), (0.0, 0.0), (1.0, 0.0)):
        t = wave.copy()
        t[:, fl], t[:, fr] = a_left, a_right
        tabs.append(t)
    tabs.append(body.mirror_actuators(tabs[3]))  # left fin down, right up, wave mirrored
    tr = simulate(body, np.stack(tabs), record_every=steps)
    y = tr.com(body)[:, -1, 1]
    assert abs(y[0]) < 0.02  # level fins: no depth change
    assert y[1] > 0.1 and y[2] < -0.1  # both fins up: rises; both down: sinks
    p = tr.final.positions
    left = [body.node_names.index(n) for n in ("r1_0", "r1_3", "r2_0", "r2_3")]
    right = [body.node_names.index(n) for n in ("r1_1", "r1_2", "r2_1", "r2_2")]
    roll = p[:, left, 1].mean(axis=1) - p[:, right, 1].mean(axis=1)
    assert roll[3] > 0.05 and roll[4] < -0.05  # the left fin up lifts the left side
    # mirrored commands give the mirrored state
    mirror = p[4][body.node_mirror] * np.array([1.0, 1.0, -1.0])
    assert np.abs(mirror - p[3]).max() < 1e-3


def test_per_face_drag_coefficients_scale_the_water_force_in_kernel_and_reference():
    # each face's coefficient multiplies the face law (the dolphin's streamlined head and
    # hydrofoil flukes); kernel and NumPy reference agree, and the coefficient acts
    body = load_animal("shark")
    rng = np.random.default_rng(5)
    odd = body.with_(panel_drag=rng.uniform(0.0, 4.0, len(body.panels)))
    steps = 200
    act = _random_smooth(rng, body, steps, batch=2)
    st = rest_state(body, 2, velocity=(0.5, 0.2, 0.1))
    got = simulate(odd, act, state=st, record_every=steps).final.positions
    ref = simulate_reference(odd, act, state=st).positions
    assert np.abs(got - ref).max() < 1e-4
    plain = simulate(body, act, state=st, record_every=steps).final.positions
    assert np.abs(got - plain).max() > 1e-3
    # faces of coefficient 0 feel no water: a 1 s glide at 1 m/s slows only by the nodal
    # damping (exp(-sum c / m * t)), while the face law at coefficient 1 halves its speed
    dry = body.with_(panel_drag=np.zeros(len(body.panels)))
    rest = rest_controller(body).table(steps, body.dt)
    glide = rest_state(body, 1, velocity=(1.0, 0.0, 0.0))
    speed = {}
    for key, b in (("dry", dry), ("wet", body)):
        v = simulate(b, rest, state=glide, record_every=steps).final.velocities[0, :, 0]
        speed[key] = float(np.sum(body.mass * v) / body.total_mass)
    damped = np.exp(-body.node_damping.sum() / body.total_mass * steps * body.dt)
    assert speed["dry"] == pytest.approx(damped, abs=0.01)
    assert speed["wet"] < 0.7


def test_each_chunk_of_lanes_reads_its_own_activations():
    """The kernel steps lanes in chunks and copies each step's activations for a chunk into
    a row of its own: a lane stepped in a chunk that starts at lane 8 or 16 must move exactly
    as it does in one chunk of all lanes, and as it does alone."""
    from zoetic.physics.kernel import simulate_chunks_serial
    from zoetic.physics.model import compile_model

    body = load_animal("shark")
    model = compile_model(body)
    steps, lanes = 120, 20
    act = np.random.default_rng(5).uniform(0, 1, (steps, body.n_actuators, lanes))
    act = np.ascontiguousarray(act, dtype=np.float32)
    pos0 = np.ascontiguousarray(
        rest_state(body, lanes).positions.transpose(1, 2, 0), dtype=np.float32
    )
    vel0 = np.zeros_like(pos0)

    def run(chunk, a):
        n = a.shape[2]
        out = np.empty((body.n_nodes, 3, n), np.float32)
        rec = np.empty((0, body.n_nodes, 3, n), np.float32)
        failed = -np.ones(n, np.int64)
        simulate_chunks_serial(
            pos0[..., :n].copy(),
            vel0[..., :n].copy(),
            a,
            0,
            chunk,
            np.float32(200.0),
            model,
            rec,
            out,
            np.empty_like(out),
            failed,
        )
        assert (failed < 0).all()
        return out

    whole = run(32, act)
    assert np.array_equal(run(8, act), whole)
    alone = run(8, np.ascontiguousarray(act[..., 13:14]))
    assert np.array_equal(alone[..., 0], whole[..., 13])
    # and the lanes did differ: each followed its own activations
    assert np.abs(whole[..., 13] - whole[..., 3]).max() > 1e-3


def test_a_batch_of_16_lanes_or_more_is_never_cut_into_chunks_of_fewer():
    """Chunks under SPLIT_LANES take the kernel's one-animal path, slow for several lanes: a
    stunt search's 16 plans must run as one chunk of 16, not two of 8 (one per thread)."""
    from zoetic.physics.kernel_terms import SPLIT_LANES
    from zoetic.physics.simulate import chunk_size

    for threads in (1, 2, 3, 4, 16):
        for batch in range(1, 600):
            c = chunk_size(batch, threads)
            assert c % 8 == 0 and 8 <= c <= 512
            assert c * threads >= batch or c == 512  # every lane in one thread's chunk
            if batch >= SPLIT_LANES:
                assert c >= SPLIT_LANES, (batch, threads, c)
            if batch < 2 * SPLIT_LANES:
                assert c >= batch, (batch, threads, c)  # one chunk
    assert chunk_size(16, 2) == 16
