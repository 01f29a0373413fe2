"""Sensor-actuator networks: the node of Fig. 6/7, files, random generation, search and tuning.

These tests use a tiny fake creature and world (a point that the actuator pushes along a line),
so they check the SAN code alone; tests/test_san_cli.py runs the real MuJoCo creatures.
"""

from __future__ import annotations

import json
import sys
import types
from dataclasses import dataclass, field, replace

import numpy as np
import pytest

from zoetic.errors import ZoeticError
from zoetic.san import load_creature
from zoetic.san.network import (
    Network,
    NetworkError,
    SanPolicy,
    check_fits,
    load_network,
    random_network,
    save_network,
)
from zoetic.san.search import SearchResult, search, useful_mask, useful_threshold_cm_s
from zoetic.san.tune import MeanEvaluator, WorldEvaluator, tunable_parameters, tune

# --- a fake creature and world ------------------------------------------------------------


@dataclass(frozen=True)
class FakeSensor:
    kind: str


@dataclass(frozen=True)
class FakeCreature:
    name: str = "dot"
    n_sensors: int = 3
    n_actuators: int = 1
    expected_cycle: float = 0.5
    seconds: float = 2.0
    metric: str = "distance"
    control_dt: float = 1 / 64
    lo: tuple = (-1.0,)
    hi: tuple = (1.0,)
    ks: tuple = (1.0,)
    kd: tuple = (0.1,)
    slo: tuple = (0.0, -0.2, 0.1)
    shi: tuple = (0.0, 0.2, 0.5)
    sensors: tuple = field(
        default=(FakeSensor("touch"), FakeSensor("length"), FakeSensor("length"))
    )

    def tuning(self) -> dict[str, np.ndarray]:
        return {
            "actuator_lo": np.array(self.lo),
            "actuator_hi": np.array(self.hi),
            "ks": np.array(self.ks),
            "kd": np.array(self.kd),
            "sensor_lo": np.array(self.slo),
            "sensor_hi": np.array(self.shi),
        }

    def with_tuning(
        self, actuator_lo=None, actuator_hi=None, ks=None, kd=None, sensor_lo=None, sensor_hi=None
    ) -> FakeCreature:
        t = self.tuning()
        pick = lambda v, k: tuple(float(x) for x in (t[k] if v is None else v))  # noqa: E731
        return replace(
            self,
            lo=pick(actuator_lo, "actuator_lo"),
            hi=pick(actuator_hi, "actuator_hi"),
            ks=pick(ks, "ks"),
            kd=pick(kd, "kd"),
            slo=pick(sensor_lo, "sensor_lo"),
            shi=pick(sensor_hi, "sensor_hi"),
        )


@dataclass(frozen=True)
class FakeRollout:
    metric: float
    fell: bool
    distance: float


class FakeWorld:
    """A point x with velocity v pulled by a PD 'muscle' toward the commanded position."""

    builds = 0

    def __init__(self, creature, terrain="flat", seed=0, follow=None, mirror=False):
        FakeWorld.builds += 1
        self.creature = creature

    def set_tuning(self, creature):
        self.creature = creature

    def run(self, policy, seconds=None, record_every=0):
        c = self.creature
        dt = c.control_dt
        x = v = 0.0
        policy.reset()
        for _ in range(round((seconds or c.seconds) / dt)):
            sensors = np.array(
                [abs(v) < 0.05, c.slo[1] <= x <= c.shi[1], c.slo[2] <= v <= c.shi[2]], dtype=bool
            )
            u = float(policy.step(sensors, dt)[0])
            target = c.lo[0] + (u + 2.0) / 4.0 * (c.hi[0] - c.lo[0])
            v += dt * (c.ks[0] * (target - x) - c.kd[0] * v) + dt * 0.3 * abs(u) * np.sign(v)
            x += dt * v
        return FakeRollout(abs(x), False, x)


@pytest.fixture
def fake_world(monkeypatch):
    mod = types.ModuleType("zoetic.san.world")
    mod.World = FakeWorld
    monkeypatch.setitem(sys.modules, "zoetic.san.world", mod)
    import zoetic.san as san_pkg

    monkeypatch.setattr(san_pkg, "world", mod, raising=False)
    return mod


def _net(weights, n_hidden, t_on=0.125, t_off=0.125, creature="dot") -> Network:
    w = np.asarray(weights)
    n = w.shape[0]
    return Network(creature, w, np.full(n, 1 / t_on), np.full(n, -1 / t_off), n_hidden)


# --- the node (Fig. 6 and 7) ---------------------------------------------------------------


def test_node_switches_on_after_t_on_and_off_after_t_off():
    # 1 sensor, 1 hidden node (reads the sensor with weight 1), 1 actuator reading the hidden
    # node with weight 2: the command shows the hidden node's output.
    net = _net([[1, 0, 0], [0, 2, 0]], n_hidden=1, t_on=0.1, t_off=0.25)
    pol = SanPolicy(net)
    dt = 0.01
    outs, cmds = [], []
    for k in range(60):
        cmds.append(pol.step(np.array([k < 30]), dt)[0])
        outs.append(pol.outputs[0])
    outs = np.array(outs)
    on = int(np.argmax(outs == 1))
    assert on + 1 == pytest.approx(0.1 / dt, abs=1)  # on after T_on = 1/k1 = 0.1 s
    assert outs[:on].max() == 0
    off = 30 + int(np.argmax(outs[30:] == 0))
    assert off - 30 + 1 == pytest.approx(0.25 / dt, abs=1)  # off after T_off = -1/k2 = 0.25 s
    assert outs[on:off].min() == 1
    # the actuator's sum (2 x hidden output) is the command, bounded to [-2, 2]
    assert cmds[on + 1] == 2.0 and cmds[0] == 0.0
    # internal state starts at 0 and stays in [0, 1]
    pol.reset()
    assert np.all(pol.state == 0)


def test_hysteresis_ignores_momentary_contact():
    net = _net([[1, 0, 0], [0, 2, 0]], n_hidden=1, t_on=0.1, t_off=0.1)
    pol = SanPolicy(net)
    for k in range(40):  # sensor flickers on 1 tick in 3: the state drifts down, never on
        pol.step(np.array([k % 3 == 0]), 0.01)
        assert pol.outputs[0] == 0


def _reference(net: Network, sensor_seq: np.ndarray, dt: float):
    """Fig. 7 written out literally, node by node."""
    n, h = net.n_nodes, net.n_hidden
    istate, out = np.zeros(n), np.zeros(n)
    cmds, states = [], []
    for s in sensor_seq:
        x = np.concatenate([s.astype(float), out])
        sums = net.weights.astype(float) @ x
        cmds.append(np.clip(sums[h:], -2, 2))
        new_out = out.copy()
        for i in range(n):
            istate[i] += (net.k1[i] if sums[i] > 0 else net.k2[i]) * dt
            istate[i] = min(max(istate[i], 0.0), 1.0)
            if out[i] == 1 and istate[i] == 0.0:
                new_out[i] = 0
            if out[i] == 0 and istate[i] == 1.0:
                new_out[i] = 1
        out = new_out
        states.append(np.concatenate([istate, out]))
    return np.array(cmds), np.array(states)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_policy_matches_literal_figure_7(seed):
    rng = np.random.default_rng(seed)
    creature = FakeCreature(n_sensors=6, n_actuators=2, expected_cycle=0.5)
    net = random_network(creature, rng, n_hidden=5)  # delays 0.125 s, k*dt exact with dt=1/64
    seq = np.repeat(rng.random((60, 6)) < 0.5, rng.integers(1, 6, 60), axis=0)
    ref_cmds, ref_states = _reference(net, seq, 1 / 64)
    pol = SanPolicy(net, creature)
    cmds, states = [], []
    for s in seq:
        cmds.append(pol.step(s, 1 / 64).copy())
        states.append(pol.state)
    np.testing.assert_array_equal(np.array(cmds), ref_cmds)
    np.testing.assert_array_equal(np.array(states), ref_states)
    assert len(np.unique(ref_states[:, -net.n_nodes :], axis=0)) > 3  # the nodes did switch


def test_a_san_is_a_policy_of_the_one_protocol_and_acts_as_it_steps():
    from zoetic.control.policy import Period, Policy

    rng = np.random.default_rng(3)
    creature = FakeCreature(n_sensors=6, n_actuators=2, expected_cycle=0.5)
    net = random_network(creature, rng, n_hidden=5)
    seq = np.repeat(rng.random((30, 6)) < 0.5, rng.integers(1, 6, 30), axis=0)
    ref_cmds, _ = _reference(net, seq, 1 / 64)
    pol = SanPolicy(net, creature)
    assert isinstance(pol, Policy) and pol.sensors == ("san_sensors",)
    pol.reset(seed=0)
    cmds = [
        pol.act({"san_sensors": s[None]}, Period(k, 1, 1 / 64))[0].copy() for k, s in enumerate(seq)
    ]
    np.testing.assert_array_equal(np.array(cmds), ref_cmds)


# --- validation and files -------------------------------------------------------------------


def test_weights_out_of_range_or_not_integer_are_refused():
    with pytest.raises(NetworkError, match=r"weight \[1, 2\] = 3 is out of range \[-2, 2\]"):
        _net([[0, 0, 0], [0, 0, 3]], 1)
    with pytest.raises(NetworkError, match="not an integer"):
        _net([[0, 0.5, 0], [0, 0, 0]], 1)
    with pytest.raises(NetworkError, match="k2 must be finite and negative"):
        Network("dot", np.zeros((2, 3)), np.ones(2), np.ones(2), 1)
    assert issubclass(NetworkError, ZoeticError)


def test_bad_file_is_refused_naming_the_file(tmp_path):
    creature = FakeCreature()
    net = random_network(creature, np.random.default_rng(0))
    data = net.to_dict()
    data["weights"][0][2] = -5
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    with pytest.raises(NetworkError, match=r"bad\.json: weight \[0, 2\] = -5 is out of range"):
        load_network(path)
    path.write_text("{not json")
    with pytest.raises(NetworkError, match=r"bad\.json: not valid JSON"):
        load_network(path)


def test_network_that_does_not_fit_its_creature_is_refused(tmp_path):
    creature = FakeCreature(n_sensors=3, n_actuators=1)
    net = random_network(creature, np.random.default_rng(0))
    other = FakeCreature(name="dot", n_sensors=4, n_actuators=1)
    with pytest.raises(NetworkError, match="has 3 sensors and 1 actuators; creature 'dot' has 4"):
        SanPolicy(net, other)
    path = save_network(net, tmp_path / "n.json")
    with pytest.raises(NetworkError, match=r"n\.json: network is for creature 'dot', not 'cat'"):
        load_network(path, FakeCreature(name="cat"))
    check_fits(net, creature)  # fits its own


def test_save_load_round_trip_keeps_tuning(tmp_path):
    creature = FakeCreature()
    net = random_network(creature, np.random.default_rng(3))
    tuned = net.with_params(tuning=creature.with_tuning(ks=[2.5]).tuning(), k1=net.k1 * 1.1)
    back = load_network(save_network(tuned, tmp_path / "t.json"), creature)
    assert back == tuned and back != net
    assert back.tuned_creature(creature).ks == (2.5,)
    assert back.weights.dtype == np.int8


def test_random_network_shape_range_and_delays():
    creature = FakeCreature(name="cart", n_sensors=6, n_actuators=1, expected_cycle=0.4)
    a = random_network(creature, np.random.default_rng(7))
    b = random_network(creature, np.random.default_rng(7))
    assert a == b
    assert a.n_hidden == 5 and a.weights.shape == (6, 12)  # Table 1: cart has 5 hidden nodes
    assert set(np.unique(a.weights)) == {-2, -1, 0, 1, 2}
    np.testing.assert_allclose(a.t_on, 0.1)  # 0.25 x expected cycle
    np.testing.assert_allclose(a.t_off, 0.1)


# --- phase 1 search (fake world) -----------------------------------------------------------


def test_search_is_reproducible_whatever_the_worker_count(fake_world):
    creature = FakeCreature()
    one = search(creature, trials=24, seed=5, workers=1, seconds=1.0)
    two = search(creature, trials=24, seed=5, workers=2, seconds=1.0)
    np.testing.assert_array_equal(one.metrics, two.metrics)
    assert all(a == b for a, b in zip(one.networks, two.networks, strict=True))
    other = search(creature, trials=24, seed=6, workers=1, seconds=1.0)
    assert not np.array_equal(one.metrics, other.metrics)
    assert one.metrics[one.top(3)[0]] == one.metrics.max()
    assert list(np.sort(one.metrics)[::-1]) == list(one.metrics[one.order])


def test_useful_means_within_a_factor_two_of_the_best_without_falling():
    creature = FakeCreature(seconds=5.0)
    metrics = np.array([0.5, 0.2, 0.26, 0.0, 0.9, 0.01])  # m in 5 s: 10, 4, 5.2, 0, 18, 0.2 cm/s
    fell = np.array([False, False, False, True, True, False])
    res = SearchResult(creature, [], metrics, fell, metrics, 5.0, "flat", 0, 0.0, 1)
    assert useful_threshold_cm_s(res) == pytest.approx(5.0)  # the fallen 18 cm/s does not count
    assert useful_mask(res).tolist() == [True, False, True, False, False, False]


# --- phase 2 tuning ------------------------------------------------------------------------


def test_tunable_parameters_are_those_of_figure_8():
    creature = FakeCreature()
    net = random_network(creature, np.random.default_rng(0), n_hidden=4)
    names = [p.key for p in tunable_parameters(net, creature)]
    # 2 per hidden node, 4 per actuator, 2 per sensor with a range (the touch sensor has none)
    assert len(names) == 2 * 4 + 4 * 1 + 2 * 2
    assert "sensor_lo" in names and names.count("k1") == 4


def _bowl(net: Network, creature) -> float:
    """A smooth test metric with its peak at ks = 2, actuator_hi = 1.5, k1 = 10."""
    return -((creature.ks[0] - 2) ** 2) - (creature.hi[0] - 1.5) ** 2 - 0.01 * (net.k1[0] - 10) ** 2


@pytest.mark.parametrize("method", ["sga", "anneal"])
def test_tuning_improves_never_worsens_and_is_reproducible(method):
    creature = FakeCreature()
    net = random_network(creature, np.random.default_rng(0), n_hidden=2)
    a = tune(net, creature, method=method, trials=300, seed=1, evaluate=_bowl)
    b = tune(net, creature, method=method, trials=300, seed=1, evaluate=_bowl)
    assert a.after == b.after and a.network == b.network
    assert a.after > a.before + 0.5
    assert np.all(np.diff(a.best) >= 0) and a.best[-1] == a.after
    assert _bowl(a.network, a.network.tuned_creature(creature)) == a.after
    np.testing.assert_array_equal(a.network.weights, net.weights)  # weights are kept


def test_tuning_never_returns_worse_than_start():
    creature = FakeCreature()
    net = random_network(creature, np.random.default_rng(0), n_hidden=2)

    def everything_worse(n, c):  # the start (ks = 1, k1 = 8) is the peak
        return -abs(c.ks[0] - 1.0) - abs(n.k1[0] - 8.0) - abs(c.hi[0] - 1.0)

    res = tune(net, creature, method="anneal", trials=50, seed=0, evaluate=everything_worse)
    assert res.after >= res.before
    assert res.network.tuned_creature(creature).ks == creature.ks


def test_tuning_in_the_fake_world_is_at_least_as_fast(fake_world):
    creature = FakeCreature(seconds=1.0)
    res = search(creature, trials=8, seed=0, workers=1)
    net = res.networks[res.top(1)[0]]
    tuned = tune(net, creature, method="sga", trials=20, seed=0)
    assert tuned.before == pytest.approx(res.metrics.max())
    assert tuned.after >= tuned.before


def test_tuning_runs_on_the_one_annealing_of_learn(monkeypatch):
    from zoetic.learning.optimizers import Annealing

    told = []
    tell = Annealing.tell
    monkeypatch.setattr(
        Annealing, "tell", lambda self, X, f, grad=None: (told.append(len(f)), tell(self, X, f))
    )
    creature = FakeCreature()
    net = random_network(creature, np.random.default_rng(0), n_hidden=2)
    for method in ("anneal", "sga"):
        told.clear()
        tune(net, creature, method=method, trials=7, seed=1, evaluate=_bowl)
        assert told == [1] * 8  # the start, then one per trial


def test_mean_evaluator_scores_pursuit_over_several_splines():
    # a follow creature's metric depends on its spline; the mean over splines is what the
    # Fig. 10 experiment tunes, so one lucky path does not decide the SAN
    fish = load_creature("fish")
    net = random_network(fish, np.random.default_rng(3))
    each = [WorldEvaluator(seed=s, seconds=3.0)(net, fish) for s in (0, 2)]
    assert each[0] != each[1]
    assert MeanEvaluator((0, 2), seconds=3.0)(net, fish) == pytest.approx(np.mean(each))
    with pytest.raises(ZoeticError, match="at least one seed"):
        MeanEvaluator(())
