"""SAN creatures and their MuJoCo world: loading, validation, physics sanity, metrics."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from zoetic.errors import ZoeticError
from zoetic.san import (
    CreatureError,
    Rollout,
    World,
    creature_to_toml,
    evaluate,
    list_creatures,
    load_creature,
    save_creature,
)
from zoetic.san.creature import ZOO_DIR

# Table 1: links, sensors, actuators
TABLE1 = {
    "crawler": (4, 8, 2),
    "fish": (4, 6, 2),
    "bouncer": (5, 8, 4),
    "luxo": (3, 6, 2),
    "cart": (2, 6, 1),
    "walker": (6, 11, 5),
    "twolink": (2, 6, 1),
    "threelink": (3, 8, 2),
    "fourlink": (4, 11, 3),
    "star": (3, 8, 2),
}
CART = (ZOO_DIR / "cart.toml").read_text()


class Const:
    """Constant commands."""

    def __init__(self, u):
        self.u = np.asarray(u, dtype=float)

    def reset(self):
        pass

    def step(self, sensors, dt):
        return self.u


class RandomSwitch:
    """New random commands every ``period`` seconds, seeded; exposes a ``state``."""

    def __init__(self, n, seed=0, period=0.2):
        self.n, self.seed, self.period = n, seed, period

    def reset(self):
        self.rng = np.random.default_rng(self.seed)
        self.t = 0.0
        self.u = self.rng.uniform(-2, 2, self.n)
        self.state = np.zeros(2)

    def step(self, sensors, dt):
        self.t += dt
        if self.t >= self.period:
            self.t = 0.0
            self.u = self.rng.uniform(-2, 2, self.n)
        self.state = np.array([self.t, sensors.sum()])
        return self.u


class Square:
    """Square waves of period ``period`` with per-actuator phases (fractions of a period)."""

    def __init__(self, period, phase, amp=2.0):
        self.period, self.phase, self.amp = period, np.asarray(phase, dtype=float), amp

    def reset(self):
        self.t = 0.0

    def step(self, sensors, dt):
        self.t += dt
        return np.where((self.t / self.period + self.phase) % 1.0 < 0.5, self.amp, -self.amp)


def _write(tmp_path, text, name="bad.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


# ----------------------------------------------------------------------------- the zoo


def test_zoo_has_the_ten_creatures_of_table_1():
    assert sorted(list_creatures()) == sorted(TABLE1)


@pytest.mark.parametrize("name", sorted(TABLE1))
def test_creature_loads_with_table_1_counts_and_stays_finite(name):
    c = load_creature(name)
    assert (c.n_links, c.n_sensors, c.n_actuators) == TABLE1[name]
    # an absolute usefulness bar: a quarter of Table 1's speed where the paper gives one
    assert c.useful_speed is not None and c.useful_speed > 0
    if c.paper_speed is not None:
        assert c.useful_speed == pytest.approx(c.paper_speed / 4)
    assert c.name == name and c.dt > 0 and c.control_dt >= c.dt
    assert c.seconds == (30.0 if name in ("crawler", "fish") else 6.0)
    assert c.metric == ("follow" if name in ("crawler", "fish") else "distance")
    world = World(c)
    r = world.run(RandomSwitch(c.n_actuators, seed=1), seconds=2.0, record_every=10)
    assert isinstance(r, Rollout) and not r.unstable
    R = len(r.times)
    assert R == 2.0 / c.control_dt / 10 + 1
    assert r.poses.shape == (R, c.n_links, 3) and np.isfinite(r.poses).all()
    assert r.sensors.shape == (R, c.n_sensors) and r.sensors.dtype == bool
    assert r.commands.shape == r.targets.shape == (R, c.n_actuators)
    assert r.states is not None and r.states.shape == (R, 2)
    assert (r.follow is not None) == (c.metric == "follow")
    assert np.isfinite([r.metric, r.distance]).all()
    lo, hi = c.tuning()["actuator_lo"], c.tuning()["actuator_hi"]
    assert np.all(r.targets >= lo - 1e-12) and np.all(r.targets <= hi + 1e-12)


# ----------------------------------------------------------------------------- the format


def test_cart_round_trips_through_toml(tmp_path):
    c = load_creature("cart")
    assert c.actuators[0].lo == pytest.approx(math.radians(-140))
    assert c.actuators[0].ks == pytest.approx(0.002 * 180 / math.pi)  # 0.002 N*m/deg
    assert [ln.mass for ln in c.links] == [0.10, 0.10]
    path = save_creature(c, tmp_path / "cart2.toml")
    back = load_creature(path)
    assert back == c
    assert creature_to_toml(back) == creature_to_toml(c)
    tuned = c.with_tuning(ks=c.tuning()["ks"] * 2, sensor_hi=c.tuning()["sensor_hi"] + 0.001)
    assert load_creature(save_creature(tuned, tmp_path / "t.toml")) == tuned


def test_joint_to_a_missing_link_is_refused_naming_file_and_link(tmp_path):
    path = _write(tmp_path, CART.replace('child = "L2"', 'child = "L9"'))
    with pytest.raises(CreatureError) as e:
        load_creature(path)
    assert str(path) in str(e.value) and "'L9'" in str(e.value) and "J1" in str(e.value)
    assert isinstance(e.value, ZoeticError)


@pytest.mark.parametrize(
    "old, new, words",
    [
        ("lo_deg = -140.0", "lo_deg = 140.0", ["A1", "lo", "below hi"]),
        ("lo_deg = 120.0", "lo_deg = 190.0", ["S6", "below hi"]),
        ("mass = 0.10", "mass = 0.0", ["L1", "mass must be positive"]),
        ("ks_deg = 0.002", "ks_deg = -0.002", ["A1", "ks must be positive"]),
        ('kind = "touch"', 'kind = "smell"', ["S1", "unknown kind 'smell'"]),
        ('name = "S2"', 'name = "S1"', ["duplicate sensor name 'S1'"]),
        ("mass = 0.10", "mass = nan", ["L1", "mass must be finite"]),
        ('target = "J1"', 'target = "J7"', ["S5", "'J7'"]),
        ('joint = "J1"', 'joint = "J7"', ["A1", "'J7'"]),
        ('shape = "capsule"', "", ["L1", "missing required key 'shape'"]),
        ('medium = "ground"', 'medium = "lava"', ["[creature]", "unknown medium 'lava'"]),
        ("radius = 0.01", "radius = 0.01\ncolour = 3", ["L1", "unknown key 'colour'"]),
        ("[[link]]", "[[link]\n", ["not valid TOML"]),
        ("useful_speed_cm_s = 5.75", "useful_speed_cm_s = 0", ["useful_speed_cm_s", "positive"]),
    ],
)
def test_invalid_files_are_refused_with_the_entry_named(tmp_path, old, new, words):
    assert old in CART
    path = _write(tmp_path, CART.replace(old, new, 1))
    with pytest.raises(CreatureError) as e:
        load_creature(path)
    msg = str(e.value)
    assert str(path) in msg
    for w in words:
        assert w in msg, msg


def test_unknown_zoo_name_lists_the_zoo():
    with pytest.raises(CreatureError, match="cart"):
        load_creature("unicorn")


def test_with_tuning_validates_and_changes_only_the_fig8_parameters():
    c = load_creature("bouncer")
    t = c.tuning()
    assert set(t) == {"actuator_lo", "actuator_hi", "ks", "kd", "sensor_lo", "sensor_hi"}
    assert t["ks"].shape == (4,) and t["sensor_lo"].shape == (8,)
    c2 = c.with_tuning(actuator_hi=t["actuator_hi"] + 0.1)
    assert np.allclose(c2.tuning()["actuator_hi"], t["actuator_hi"] + 0.1)
    assert c2.links == c.links and c2 != c
    with pytest.raises(CreatureError, match="below hi"):
        c.with_tuning(actuator_lo=t["actuator_hi"])
    with pytest.raises(CreatureError, match="ks must be positive"):
        c.with_tuning(ks=np.zeros(4))
    with pytest.raises(CreatureError, match="shape"):
        c.with_tuning(kd=np.ones(3))


# ----------------------------------------------------------------------------- physics


@pytest.mark.parametrize("name", ["cart", "fourlink", "bouncer"])
def test_no_actuation_at_rest_has_no_drift(name):
    c = load_creature(name)
    # command 0 holds each servo at the middle of its range; for the cart that is the start
    r = World(c).run(Const(np.zeros(c.n_actuators)), seconds=2.0)
    assert abs(r.distance) < (1e-4 if name != "bouncer" else 5e-3)
    assert not r.fell


def test_a_mirror_symmetric_cart_cannot_move():
    """Crossed at the middle, the cart is mirror-symmetric: whatever it does, its centre of
    mass stays put (the zoo's cart is a T, L2 hinged by its end, for that reason)."""
    l2 = 'name = "L2"\nshape = "capsule"\n'
    sym = CART.replace(l2, l2 + "start = -0.06\n")
    sym = sym.replace("at = 0.0\n", "at = -0.06\n").replace("at = 0.12\n", "at = 0.06\n")
    assert sym.count("= -0.06") == 4 and sym.count("at = 0.06") == 2
    import tomllib

    from zoetic.san.creature_file import creature_from_dict

    c = creature_from_dict(tomllib.loads(sym), "sym.toml")
    r = World(c).run(Square(0.4, [0.0]), seconds=2.0)
    assert abs(r.distance) < 1e-6


def test_touch_sensor_is_on_when_resting_and_off_when_lifted():
    c = load_creature("cart")
    w = World(c)
    m, d = w.model, w.data
    mujoco.mj_resetData(m, d)
    d.qpos[:] = w.qpos0
    mujoco.mj_step(m, d, 200)  # let it settle onto the ground
    mujoco.mj_forward(m, d)
    touch = [i for i, s in enumerate(c.sensors) if s.kind == "touch"]
    assert w.read_sensors()[touch].all()
    d.qpos[1] += 0.05
    mujoco.mj_forward(m, d)
    assert not w.read_sensors()[touch].any()


def test_angle_sensor_follows_the_joint_angle():
    c = load_creature("cart")
    w = World(c)
    m, d = w.model, w.data
    mujoco.mj_resetData(m, d)
    d.qpos[:] = w.qpos0
    j = m.jnt_qposadr[m.joint("J1").id]
    for angle, s5, s6 in ((0.0, False, False), (2.5, False, True), (-2.5, True, False)):
        d.qpos[j] = angle
        mujoco.mj_forward(m, d)
        assert list(w.read_sensors()[4:6]) == [s5, s6]
    d.qpos[j] = 2.5 - 2 * math.pi  # wrapped
    mujoco.mj_forward(m, d)
    assert list(w.read_sensors()[4:6]) == [False, True]


def test_commands_map_linearly_onto_the_actuator_range():
    c = load_creature("threelink")
    lo, hi = c.tuning()["actuator_lo"], c.tuning()["actuator_hi"]
    for u, want in ((-2.0, lo), (2.0, hi), (0.0, (lo + hi) / 2), (5.0, hi)):
        r = World(c).run(Const(np.full(2, u)), seconds=0.05, record_every=1)
        assert np.allclose(r.targets[-1], want)
    w = World(c)
    w.run(Const(np.full(2, 2.0)), seconds=2.0)
    q = w.data.qpos[w.model.jnt_qposadr[w.model.joint("J1").id]]
    assert q == pytest.approx(hi[0], abs=0.1)  # the servo got there (gravity bends it a bit)


def test_crawler_moves_forward_under_a_symmetric_oscillation():
    c = load_creature("crawler")
    r = World(c).run(Square(0.4, [0.0, 0.0]), seconds=4.0, record_every=50)
    assert r.distance > 0.2  # forward (+x), not backward
    assert abs(r.poses[-1, 0, 1]) < 0.05  # both sides alike: no turning
    back = World(c).run(Const(np.zeros(2)), seconds=2.0)
    assert abs(back.distance) < 1e-3


def test_fish_swims_and_is_still_without_actuation():
    c = load_creature("fish")
    w = World(c)
    assert abs(w.run(Const(np.zeros(2)), seconds=2.0).distance) < 1e-6
    r = w.run(Square(0.4, [0.0, 0.25]), seconds=5.0, record_every=100)
    assert abs(r.distance) > 0.05
    assert r.follow is not None and r.follow.shape == (len(r.times), 2)


def test_fish_follow_point_does_not_outrun_a_plain_fish_gait():
    # Fig. 10: the fish must be able to keep up with its point. A square wave on both
    # actuators at the fish's expected cycle, swimming straight with no steering, is a gait a
    # SAN finds easily; a point faster than it leaves every fish behind (the gap grows by
    # the difference, 1.5-5 m over the 30 s run at 0.2 m/s).
    c = load_creature("fish")
    r = World(c, follow=False).run(Square(c.expected_cycle, [0.0, 0.0]), seconds=10.0)
    straight_m_s = r.distance / r.seconds
    assert 0.0 < c.follow_speed <= straight_m_s, (c.follow_speed, straight_m_s)


def test_hand_policies_move_the_ground_creatures():
    # half-range waves for the bouncer (~3 m in 6 s); full swings of its 1 kg body tip it over
    for name, period, phase, amp in (
        ("bouncer", 0.2, [0, 0.125, 0.25, 0.375], 1.0),
        ("luxo", 0.2, [0, 0.75], 2.0),  # hops ~2 m in 6 s; most full-swing waves tip it over
    ):
        c = load_creature(name)
        r = World(c).run(Square(period, phase, amp))
        assert not r.fell and r.metric > 0.5, (name, r.metric)


def test_walker_falls_and_scores_zero_when_it_collapses():
    c = load_creature("walker")
    r = World(c).run(Const([2.0, -2.0, 2.0, -2.0, -2.0]), seconds=3.0)
    assert r.fell and r.metric == 0.0


def test_rollouts_are_reproducible():
    c = load_creature("fourlink")
    w = World(c, terrain="rough", seed=3)
    a = w.run(RandomSwitch(3, seed=5), seconds=2.0, record_every=5)
    b = w.run(RandomSwitch(3, seed=5), seconds=2.0, record_every=5)
    c2 = World(c, terrain="rough", seed=3).run(RandomSwitch(3, seed=5), seconds=2.0, record_every=5)
    for x in (b, c2):
        assert x.metric == a.metric and x.distance == a.distance
        assert np.array_equal(x.poses, a.poses) and np.array_equal(x.sensors, a.sensors)
    fast = w.run(RandomSwitch(3, seed=5), seconds=2.0)
    assert fast.metric == a.metric and len(fast.times) == 0


def test_rough_terrain_differs_from_flat():
    c = load_creature("fourlink")
    flat = World(c).run(RandomSwitch(3, seed=2), seconds=3.0, record_every=10)
    world = World(c, terrain="rough", seed=1)
    rough = world.run(RandomSwitch(3, seed=2), seconds=3.0, record_every=10)
    assert flat.terrain is None and rough.terrain is not None
    assert rough.terrain.shape[1] == 2 and rough.terrain[:, 1].max() > 0.01
    assert rough.distance != flat.distance
    assert World(c, terrain="rough", seed=2).terrain[:, 1].tolist() != rough.terrain[:, 1].tolist()


def test_ground_friction_below_one_is_applied():
    """MuJoCo takes the larger of two geoms' frictions: the links must not mask the ground's."""
    import dataclasses

    c = load_creature("fourlink")
    runs = [
        World(dataclasses.replace(c, friction=mu)).run(RandomSwitch(3, seed=2), seconds=2.0)
        for mu in (0.3, 0.6, 1.0)
    ]
    assert len({r.distance for r in runs}) == 3


def test_hill_is_a_valley_the_creature_must_climb_out_of():
    c = load_creature("bouncer")
    hill = World(c, terrain="hill")
    # flat for |x| < 0.5 m, then 10% uphill either way
    assert np.allclose(hill.ground(np.array([0.0, 0.4, 1.5, -2.5])), [0.0, 0.0, 0.1, 0.2])
    wave = Square(0.2, [0, 0.125, 0.25, 0.375], 1.0)
    flat, up = World(c).run(wave), hill.run(wave)
    assert not flat.fell and not up.fell
    assert abs(up.distance) < 0.6 * abs(flat.distance)  # the same gait climbs more slowly


def test_set_tuning_and_evaluate():
    c = load_creature("twolink")
    w = World(c)
    pol = Square(0.3, [0.0])
    base = w.run(pol).metric
    weak = c.with_tuning(ks=c.tuning()["ks"] * 0.3, kd=c.tuning()["kd"] * 0.3)
    w.set_tuning(weak)
    assert w.run(pol).metric != base
    assert evaluate(weak, pol) == w.run(pol).metric
    with pytest.raises(CreatureError):
        w.set_tuning(load_creature("cart"))
    with pytest.raises(CreatureError, match="terrain"):
        World(c, terrain="swamp")


def test_follow_metric_rewards_approach():
    c = load_creature("crawler")
    w = World(c)
    # slower than the follow point (0.15 m/s): it never overtakes it
    r = w.run(Square(1.0, [0.0, 0.0], amp=1.0), seconds=3.0, record_every=20)
    assert 0 < r.distance < 0.45
    assert r.metric > 0.5 * r.distance  # it crawls towards the point ahead of it
    away = w.run(Square(1.0, [0.0, 0.0], amp=1.0), seconds=3.0)
    assert away.metric == r.metric
    assert np.all(np.diff(r.follow[:, 0]) > 0)


def test_eyes_see_the_follow_point_ahead_at_the_start():
    c = load_creature("fish")
    r = World(c).run(Const(np.zeros(2)), seconds=0.1, record_every=1)
    eyes = r.sensors[0, :4]  # right-far, right-near, left-near, left-far
    assert eyes[1] or eyes[2]
    assert not eyes[0] and not eyes[3]
    assert not World(c, follow=False).run(Const(np.zeros(2)), 0.1, 1).sensors[:, :4].any()


def test_one_sided_stroke_turns_the_crawler():
    c = load_creature("crawler")

    class Left(Square):
        def step(self, sensors, dt):
            return np.array([super().step(sensors, dt)[0], -2.0])

    r = World(c).run(Left(0.4, [0.0, 0.0]), seconds=5.0, record_every=100)
    assert r.distance > 0.2 and r.poses[-1, 0, 2] < -0.3  # forward, turning right


def test_hop_metric_adds_height_to_progress():
    import dataclasses

    c = dataclasses.replace(load_creature("bouncer"), metric="hop", hop_k=10.0)
    r = World(c).run(Const(np.zeros(4)), seconds=2.0)
    # standing still: ~ k * y^2 * T with the centre of mass about 0.45 m up
    assert not r.fell and 10.0 * 0.3**2 * 2.0 < r.metric < 10.0 * 0.6**2 * 2.0


def test_commands_of_the_wrong_shape_are_a_clear_error():
    from zoetic.errors import SimulationError

    with pytest.raises(SimulationError, match="3 actuators"):
        World(load_creature("fourlink")).run(Const(np.zeros(2)), seconds=0.1)


@pytest.mark.parametrize("name", sorted(TABLE1))
def test_every_zoo_creature_round_trips(tmp_path, name):
    c = load_creature(name)
    text = creature_to_toml(c)
    assert text.startswith("# creature") and "[[link]]" in text
    assert load_creature(save_creature(c, tmp_path / f"{name}.toml")) == c


def test_render_frames_yields_rgb_frames_with_a_side_panel():
    from zoetic.viz.san import render_frames

    c = load_creature("bouncer")
    r = World(c, terrain="rough").run(Square(0.2, [0, 0.1, 0.2, 0.3]), 0.2, record_every=20)
    calls = []
    frames = list(render_frames(c, r, side_panel=lambda ax, i: calls.append(i), size=(320, 180)))
    assert len(frames) == len(r.times) == 3 and calls == [0, 1, 2]
    assert frames[0].shape == (180, 320, 3) and frames[0].dtype == np.uint8
    assert frames[0].std() > 10  # something was drawn
    fish = load_creature("fish")
    rf = World(fish).run(Const(np.zeros(2)), 0.1, record_every=10)
    assert next(iter(render_frames(fish, rf))).shape == (360, 640, 3)
    with pytest.raises(ValueError, match="record_every"):
        next(iter(render_frames(c, World(c).run(Const(np.zeros(4)), 0.1))))
