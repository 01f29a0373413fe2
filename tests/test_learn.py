"""Learning: the objective, the optimizers, checkpoints that resume to the same result."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from conftest import write_short_task
from zoetic.bodies import load_animal
from zoetic.control import rest_controller, time_domain, wave_controller
from zoetic.errors import RunDirError, TaskError, ZoeticError
from zoetic.learning.objective import Objective, control_energy
from zoetic.learning.optimizers import make_optimizer
from zoetic.learning.run import LearnConfig, Run, build
from zoetic.tasks import list_tasks, load_task, parse_task


@pytest.fixture
def short_task(tmp_path):
    return write_short_task(tmp_path, horizon=1.0, nodes=5)


def test_control_energy_matches_section_4_2():
    u = np.array([[[0.0, 1.0, 0.0, 1.0]]])  # one candidate, one actuator, M = 4
    h = 0.5
    e1 = control_energy(u, h, nu1=0.1, nu2=0.0)
    assert e1[0] == pytest.approx(0.1 / (2 * h**2) * 3.0)
    e2 = control_energy(u, h, nu1=0.0, nu2=0.002)
    assert e2[0] == pytest.approx(0.002 / (2 * h**4) * (4.0 + 4.0))


def test_builtin_tasks_load_and_bad_tasks_are_named(tmp_path):
    assert {"swim-straight", "crawl-straight", "turn-left", "reach-goal"} <= set(list_tasks())
    for name in list_tasks():
        assert load_task(name).terms
    with pytest.raises(TaskError, match="unknown kind 'fly'"):
        parse_task({"name": "x", "horizon": 1.0, "terms": [{"kind": "fly"}]}, "x.toml")
    with pytest.raises(TaskError, match="unknown task 'nope'"):
        load_task("nope")


def test_objective_prefers_swimming_to_resting():
    body = load_animal("shark")
    task = load_task("swim-straight")
    wave = wave_controller(body)
    tmpl = time_domain(body, 40, task.horizon)
    # fit the time-domain template to the wave and to rest by sampling at its nodes
    swim = wave.sample(tmpl.node_times()).T.ravel()
    rest = rest_controller(body).sample(tmpl.node_times()).T.ravel()
    ev = Objective(task, body, tmpl, fins="free").evaluate(np.stack([swim, rest]))
    assert ev.E[0] < ev.E[1] - 0.3
    assert not ev.failed.any()


def test_turn_objective_rewards_turning_left_over_right():
    body = load_animal("shark")
    task = load_task("turn-left")
    tmpl = time_domain(body, 40, task.horizon)
    t = tmpl.node_times()
    left = wave_controller(body).sample(t)
    left[:, [k for k, s in enumerate(body.actuator_side) if s == "right"]] *= 0.2
    right = body.mirror_actuators(left)
    obj = Objective(task, body, tmpl, fins="free")
    ev = obj.evaluate(np.stack([left.T.ravel(), right.T.ravel()]))
    assert ev.terms["heading_change"][0] < ev.terms["heading_change"][1]


@pytest.mark.parametrize("name", ["anneal", "simplex", "cmaes"])
def test_optimizers_improve_respect_bounds_and_never_keep_failures(name):
    rng = np.random.default_rng(0)
    lo, hi = np.zeros(6), np.ones(6)
    target = rng.uniform(0.2, 0.8, 6)

    def f(X):
        v = np.sum((X - target) ** 2, axis=1)
        return np.where(X[:, 0] > 0.95, np.inf, v)  # a "blown-up" corner

    opt = make_optimizer(name, np.full(6, 0.9), lo, hi, seed=1, budget=600)
    first = None
    while opt.evaluations < 600 and not opt.done():
        X = opt.ask()
        if len(X) == 0:
            break
        assert np.all(X >= lo) and np.all(X <= hi)
        v = f(X)
        first = v.min() if first is None else first
        opt.tell(X, v)
    assert np.isfinite(opt.best_f)
    assert opt.best_f < 0.5 * first
    assert opt.best_f == pytest.approx(np.sum((opt.best_x - target) ** 2))
    if hasattr(opt, "close"):
        opt.close()


def test_cmaes_does_its_linear_algebra_on_one_blas_thread(monkeypatch):
    """CMA-ES's eigendecomposition runs with BLAS held to one thread (its threads would spin
    against the kernel's), and the limit is lifted again after ask and tell."""
    from threadpoolctl import threadpool_info, threadpool_limits

    from zoetic.learning.optimizers import cmaes

    def blas_threads() -> set[int]:
        return {i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}

    with threadpool_limits(limits=2, user_api="blas"):  # as on 2 cores, even on one
        before = blas_threads()
        seen: list[set[int]] = []
        real_eigh = np.linalg.eigh

        def eigh(a, *args, **kw):
            seen.append(blas_threads())
            return real_eigh(a, *args, **kw)

        monkeypatch.setattr(np.linalg, "eigh", eigh)
        opt = cmaes.CMAES(np.full(8, 0.5), np.zeros(8), np.ones(8), seed=0, popsize=8)
        for _ in range(12):
            X = opt.ask()
            opt.tell(X, np.sum((X - 0.3) ** 2, axis=1))
        assert seen and all(s == {1} for s in seen)
        assert blas_threads() == before == {2}


def test_separable_cmaes_adapts_a_diagonal_and_saves_it():
    from zoetic.learning.optimizers import cmaes

    # a valley 100x steeper along x0: the separable method scales x0 down, x1 up
    opt = cmaes.CMAES(np.full(2, 0.5), np.zeros(2), np.ones(2), seed=0, popsize=8, diagonal=True)
    for _ in range(30):
        X = opt.ask()
        opt.tell(X, 100 * (X[:, 0] - 0.3) ** 2 + (X[:, 1] - 0.6) ** 2)
    state = opt.state_dict()
    diag = np.diag(state["C"])
    assert np.count_nonzero(state["C"] - np.diag(diag)) == 0 and diag[0] < diag[1]
    again = cmaes.CMAES(np.full(2, 0.5), np.zeros(2), np.ones(2), seed=0, popsize=8, diagonal=True)
    again._rebuild(state)  # the numbers alone, as when a later cma cannot read the pickle
    np.testing.assert_allclose(again._covariance(), state["C"])
    again.load_state_dict(state)
    np.testing.assert_array_equal(again.ask(), opt.ask())


def test_annealing_follows_the_papers_schedule():
    opt = make_optimizer("anneal", np.full(4, 0.5), np.zeros(4), np.ones(4), seed=0, budget=100)
    assert opt.T == 0.5 and opt.max_steps == 40 and opt.min_accepts == 4
    X = opt.ask()
    opt.tell(X, np.zeros(1))
    X = opt.ask()
    assert np.all(np.abs(X - 0.5) <= 0.1 + 1e-12)  # every parameter moved by <= 10% of range
    assert np.all(np.abs(X - 0.5) > 0)
    for _ in range(4):  # four accepted (downhill) moves drop the temperature
        opt.tell(X, np.array([-1.0]))
        X = opt.ask()
    assert opt.T == pytest.approx(0.45)


@pytest.mark.parametrize("alpha", [0.8, 0.85])
def test_annealing_cooling_rate_is_a_setting(alpha, tmp_path, short_task):
    # Fig. 6(b-c) varies alpha in T <- alpha T; it reaches the annealer through a run's config
    config = LearnConfig(
        animal="shark",
        task=str(short_task),
        optimizer="anneal",
        budget=4,
        extra={"optimizer": {"alpha": alpha}},
    )
    opt = build(config).optimizer
    assert opt.alpha == alpha and opt.T == 0.5
    for _ in range(opt.min_accepts + 1):  # NM accepted (downhill) moves: one drop
        X = opt.ask()
        opt.tell(X, np.array([-float(opt.evaluations)]))
    assert opt.T == pytest.approx(0.5 * alpha)
    with pytest.raises(ZoeticError, match="cooling rate alpha"):
        make_optimizer("anneal", np.zeros(2), np.zeros(2), np.ones(2), seed=0, budget=9, alpha=1.2)


def _learn(out, task, optimizer, budget=60, stop_at=None):
    config = LearnConfig(
        animal="shark", task=str(task), optimizer=optimizer, budget=budget, seed=3, popsize=8
    )
    run = Run.create(out, config)

    def interrupt(r):
        if stop_at is not None and r.evaluations >= stop_at:
            raise KeyboardInterrupt

    try:
        run.learn(progress=interrupt)
    except KeyboardInterrupt:
        return None
    return run


@pytest.mark.parametrize("optimizer", ["anneal", "cmaes", "simplex"])
def test_interrupted_run_resumes_to_the_same_result(tmp_path, short_task, optimizer):
    whole = _learn(tmp_path / "whole", short_task, optimizer)
    assert _learn(tmp_path / "cut", short_task, optimizer, stop_at=25) is None
    assert (tmp_path / "cut" / "checkpoint.npz").exists()
    resumed = Run.resume(tmp_path / "cut")
    assert 25 <= resumed.evaluations < 60
    resumed.learn()
    assert resumed.evaluations == whole.evaluations
    assert resumed.setup.optimizer.best_f == whole.setup.optimizer.best_f
    assert np.array_equal(resumed.setup.optimizer.best_x, whole.setup.optimizer.best_x)
    for name in ("config.toml", "checkpoint.npz", "history.csv", "controller.json"):
        assert (tmp_path / "cut" / name).exists()


@pytest.mark.parametrize("every_s", [0.0, 1e9])
@pytest.mark.parametrize("optimizer", ["anneal", "cmaes", "simplex"])
def test_a_run_interrupted_inside_a_step_saves_the_state_before_it(
    tmp_path, short_task, optimizer, every_s, monkeypatch
):
    """Ctrl-C while a batch is simulated: the checkpoint holds the log and the optimizer's
    state before that batch's ask (rebuilt from the last saved state and the batches logged
    since), so the resumed run asks the same batch again and ends as an uninterrupted one."""
    whole = _learn(tmp_path / "whole", short_task, optimizer)
    config = LearnConfig(
        animal="shark", task=str(short_task), optimizer=optimizer, budget=60, seed=3, popsize=8
    )
    run = Run.create(tmp_path / "cut", config)
    real = Objective.evaluate
    calls = []

    def evaluate(self, params):
        calls.append(len(params))
        if sum(calls) > 30:
            raise KeyboardInterrupt
        return real(self, params)

    monkeypatch.setattr(Objective, "evaluate", evaluate)
    with pytest.raises(KeyboardInterrupt):
        run.learn(every_s=every_s)  # saved after every step, or only when interrupted
    monkeypatch.setattr(Objective, "evaluate", real)
    resumed = Run.resume(tmp_path / "cut")
    assert resumed.evaluations == sum(calls[:-1]) < 60
    resumed.learn()
    assert resumed.log.E == whole.log.E
    assert np.array_equal(np.array(resumed.log.X), np.array(whole.log.X))
    assert resumed.setup.optimizer.best_f == whole.setup.optimizer.best_f


def test_cmaes_asks_the_generation_cma_asks_folded_into_the_box():
    """The optimizer's batched fold into the box gives cma's own candidates, bit for bit, and
    cma's search continues the same (candidates far outside the box, near it and inside)."""
    import pickle

    from zoetic.learning.optimizers.cmaes import CMAES, _ask_in_bounds

    for sigma, n, seed in [(0.3, 40, 0), (3.0, 15, 1), (10.0, 40, 2)]:
        lo, hi = -np.linspace(0.1, 2.0, n), np.linspace(0.5, 3.0, n)
        ours = CMAES(np.zeros(n), lo, hi, seed, popsize=32, sigma=sigma).es
        theirs = pickle.loads(pickle.dumps(ours))
        for g in range(20):
            X, Y = np.array(_ask_in_bounds(ours)), np.array(theirs.ask())
            assert X.tobytes() == Y.tobytes()
            assert ((lo <= X) & (X <= hi)).all()
            f = list(((X - 0.3) ** 2).sum(axis=1) + 0.01 * np.sin(g + np.arange(32)))
            ours.tell(list(X), f)
            theirs.tell(list(Y), f)
        assert np.array_equal(ours.mean, theirs.mean) and ours.sigma == theirs.sigma


def test_learning_improves_and_writes_a_loadable_controller(tmp_path, short_task):
    from zoetic.control import load_controller

    run = _learn(tmp_path / "r", short_task, "cmaes", budget=120)
    e = np.array(run.log.E)
    assert run.setup.optimizer.best_f < e[:8].min()
    ctrl = load_controller(tmp_path / "r" / "controller.json", load_animal("shark"))
    assert ctrl.kind == "frequency"  # the default periodic gait
    lines = (tmp_path / "r" / "history.csv").read_text().splitlines()
    assert lines[0] == "evaluation,E,E_u,E_v,best_E,wall_time" and len(lines) == len(e) + 1


def test_same_seed_same_result_and_refusals(tmp_path, short_task):
    a = _learn(tmp_path / "a", short_task, "anneal", budget=30)
    b = _learn(tmp_path / "b", short_task, "anneal", budget=30)
    assert a.log.E == b.log.E
    with pytest.raises(RunDirError, match="already holds a run"):
        _learn(tmp_path / "a", short_task, "anneal", budget=30)
    with pytest.raises(RunDirError, match="not a zoetic run"):
        Run.resume(tmp_path / "nothing")
    with pytest.raises(TaskError, match="cannot apply to the snake .*requires water"):
        Run.create(tmp_path / "c", LearnConfig(animal="snake", task=str(short_task)))


@pytest.mark.slow
def test_gradient_run_learns_and_resumes_to_the_same_result(tmp_path, short_task):
    whole = _learn(tmp_path / "whole", short_task, "gradient", budget=8)
    e = np.array(whole.log.E)
    assert whole.setup.optimizer.best_f < e[0] - 0.005  # it swims further than at the start
    assert _learn(tmp_path / "cut", short_task, "gradient", budget=8, stop_at=4) is None
    resumed = Run.resume(tmp_path / "cut")
    assert resumed.evaluations == 4
    resumed.learn()
    assert resumed.setup.optimizer.best_f == pytest.approx(whole.setup.optimizer.best_f, abs=1e-6)


def test_process_pool_evaluator_matches_the_in_process_batch(short_task):
    from zoetic.learning.evaluate import BatchEvaluator, ProcessPoolEvaluator
    from zoetic.learning.run import build

    setup = build(LearnConfig(animal="shark", task=str(short_task), seed=2))
    rng = np.random.default_rng(0)
    X = rng.uniform(*setup.objective.bounds(), size=(6, setup.objective.dimension))
    pool = ProcessPoolEvaluator(workers=2)
    try:
        a = pool(setup.objective, X)
    finally:
        pool.close()
    b = BatchEvaluator()(setup.objective, X)
    assert np.allclose(a.E, b.E, atol=1e-9)


def test_parallel_annealing_chains_and_frequency_controllers(tmp_path, short_task):
    config = LearnConfig(
        animal="shark",
        task=str(short_task),
        optimizer="anneal",
        budget=64,
        chains=8,
        controller="frequency",
        seed=1,
    )
    run = Run.create(tmp_path / "f", config)
    run.learn()
    assert run.log.batches[1:] == [8] * (len(run.log.batches) - 1)
    assert run.setup.optimizer.best_f < run.log.E[0]
    assert run.best_controller().kind == "frequency"


def test_a_task_that_requires_fins_learns_them_and_others_hold_them_level():
    # a dolphin cannot bend left or right: its turn task requires fins, so it banks on them
    from zoetic.learning.run import build

    body = load_animal("dolphin")
    fins = [k for k, kind in enumerate(body.actuator_kind) if kind == "fin"]
    turn = build(LearnConfig(animal="dolphin", task="turn-left-swimming", budget=10))
    ahead = build(LearnConfig(animal="dolphin", task="move-forward", budget=10))
    assert set(fins) <= set(turn.objective.free) and len(turn.objective.held) == 0
    assert set(ahead.objective.held) == set(fins)
    x = turn.optimizer.x0[None]
    assert turn.objective.dimension == ahead.objective.dimension + len(fins) * 5
    tables = turn.objective.tables(x + 0.1 * np.arange(x.size))  # fins move with the params
    assert np.ptp(tables[0][:, fins]) > 0.01


def test_wave_coupling_plays_each_right_actuator_as_its_left_mirror_half_a_stroke_later():
    from zoetic.control import frequency_domain

    body = load_animal("shark")
    task = parse_task({**load_task("swim-straight").to_dict(), "horizon": 1.0, "nodes": 5})
    tmpl = frequency_domain(body, 5, task.horizon, base=body.wave_frequency)
    free = Objective(task, body, tmpl)
    obj = Objective(task, body, tmpl, coupling="wave")
    assert obj.dimension * 2 == free.dimension  # fins held, one parameter set per muscle pair
    x = np.random.default_rng(0).uniform(*obj.bounds())
    ctrl = obj.controller(x)
    t = np.linspace(0.0, 1.0, 57)
    half = 0.5 / body.wave_frequency  # the shark's wave: right phases = left + 0.5
    for k, side in enumerate(body.actuator_side):
        j = body.actuator_mirror[k]
        if side == "right" and body.actuator_kind[k] == "muscle":
            assert np.allclose(ctrl.raw(t)[:, k], ctrl.raw(t - half)[:, j])
    with pytest.raises(Exception, match="periodic"):
        Objective(task, body, time_domain(body, 5, task.horizon), coupling="wave")


def test_auto_defaults_couple_straight_gaits_and_free_the_fins_for_turns():
    from zoetic.learning.run import build

    body = load_animal("shark")
    straight = build(LearnConfig(animal="shark", task="swim-straight", budget=1))
    assert straight.objective.coupling == "wave" and straight.objective.held.size == 2
    turn = build(LearnConfig(animal="shark", task="quick-turn-left", budget=1))
    assert turn.objective.coupling == "none" and turn.objective.held.size == 0
    assert turn.objective.dimension == body.n_actuators * 5
    timed = build(LearnConfig(animal="shark", task="swim-straight", controller="time", budget=1))
    assert timed.objective.coupling == "none"  # a time-domain signal cannot be delayed exactly


def test_a_mirror_symmetric_task_couples_learned_fins_and_a_zero_turn_stays_symmetric():
    dolphin = load_animal("dolphin")  # its muscles lie in the vertical plane: the fins pair up
    fins = [k for k, kind in enumerate(dolphin.actuator_kind) if kind == "fin"]
    for task in ("turn-up", "turn-down"):  # pitched on both fins, never rolled on one
        setup = build(LearnConfig(animal="dolphin", task=task, budget=1))
        assert setup.objective.coupling == "wave" and setup.objective.held.size == 0, task
        x = np.random.default_rng(1).uniform(*setup.objective.bounds())
        table = setup.objective.tables(x[None])[0]
        assert np.allclose(table[:, fins[0]], table[:, fins[1]]), task  # never set apart
    banked = build(LearnConfig(animal="dolphin", task="turn-left-swimming", budget=1))
    assert banked.objective.coupling == "none"  # a turn to one side banks on one fin
    # the snake's straight crawl keeps its heading (a turn of 0 prefers neither side) and is
    # learned mirror-symmetric; its sharp turn is not
    straight = load_task("crawl-straight")
    assert any(t.kind == "heading_change" and t.target == 0.0 for t in straight.terms)
    assert (
        build(LearnConfig(animal="snake", task="crawl-straight", budget=1)).objective.coupling
        == "wave"
    )
    assert (
        build(LearnConfig(animal="snake", task="sharp-turn-left", budget=1)).objective.coupling
        == "none"
    )


def test_cmaes_is_made_without_importing_scipy_stats_or_matplotlib():
    """A fresh process makes and runs CMA-ES without importing scipy.stats (cma's only use of
    it is its surrogate models' rank correlation) or matplotlib (cma's plots), without a
    warning, and can import both after."""
    code = (
        "import sys, numpy as np\n"
        "from zoetic.learning.optimizers.cmaes import CMAES\n"
        "opt = CMAES(np.full(4, 0.5), np.zeros(4), np.ones(4), seed=0, popsize=6)\n"
        "X = opt.ask(); opt.tell(X, np.sum(X**2, axis=1))\n"
        "print('scipy.stats' in sys.modules, 'matplotlib' in sys.modules)\n"
        "import scipy.stats; print(scipy.stats.kendalltau([1, 2, 3], [1, 2, 3])[0])\n"
        "from matplotlib.figure import Figure; print(type(Figure().add_subplot()).__name__)\n"
    )
    run = [sys.executable, "-W", "error", "-c", code]
    out = subprocess.run(run, capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False", "1.0", "Axes"]


def test_a_cma_that_needs_scipy_stats_at_import_is_imported_whole(tmp_path):
    """Should a cma release import scipy.stats unconditionally, the import without it fails
    and the package is imported again in full, not half."""
    fake = tmp_path / "cma"
    fake.mkdir()
    (fake / "__init__.py").write_text("from . import part\nVALUE = part.tau\n")
    (fake / "part.py").write_text("import scipy.stats\ntau = 'whole'\n")
    code = (
        "import sys\n"
        f"sys.path.insert(0, {str(tmp_path)!r})\n"
        "from zoetic.learning.optimizers.cmaes import _cma\n"
        "print(_cma().VALUE, 'scipy.stats' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["whole", "True"]
