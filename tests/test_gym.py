"""Gymnasium: the registered environments pass check_env, render, and the native vector env
runs the same numbers as SyncVectorEnv."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import zoetic.gym
from zoetic.control import rest_controller, wave_controller

# our observations are unbounded on purpose; check_env says so for every space
pytestmark = pytest.mark.filterwarnings("ignore:.*Box observation space:UserWarning")


@pytest.mark.parametrize("env_id", sorted(zoetic.gym.ENVS))
def test_every_environment_passes_check_env(env_id):
    env = gymnasium.make(env_id)
    check_env(env.unwrapped, skip_render_check=True)
    obs, _ = env.reset(seed=1)
    assert env.observation_space.contains(obs)
    assert obs.shape == (zoetic.gym.envs.N_OBS + env.action_space.shape[0],)


def test_rgb_array_rendering_shows_the_animal():
    env = gymnasium.make("zoetic/SharkSwim-v0", render_mode="rgb_array", render_size=(160, 120))
    env.reset(seed=0)
    env.step(env.action_space.sample())
    img = env.render()
    assert img.shape == (120, 160, 3) and img.dtype == np.uint8
    assert img.reshape(-1, 3).std(axis=0).max() > 5  # not a blank picture


def test_native_vector_env_equals_sync_vector_env_through_autoresets():
    n, horizon = 5, 12
    kw = {"num_envs": n, "max_episode_steps": horizon}
    sync = gymnasium.make_vec("zoetic/SharkTurn-v0", vectorization_mode="sync", **kw)
    native = gymnasium.make_vec(
        "zoetic/SharkTurn-v0", vectorization_mode="vector_entry_point", **kw
    )
    assert isinstance(native, zoetic.gym.ZoeticVectorEnv)
    o_sync, _ = sync.reset(seed=3)
    o_nat, _ = native.reset(seed=3)
    np.testing.assert_allclose(o_nat, o_sync, atol=1e-5)
    rng = np.random.default_rng(0)
    ended = 0
    for _ in range(2 * horizon + 3):
        a = rng.random((n, native.single_action_space.shape[0])).astype(np.float32)
        s, v = sync.step(a), native.step(a)
        np.testing.assert_allclose(v[0], s[0], atol=1e-5)  # observations
        np.testing.assert_allclose(v[1], s[1], atol=1e-5)  # rewards
        np.testing.assert_array_equal(v[2], s[2])  # terminated
        np.testing.assert_array_equal(v[3], s[3])  # truncated
        ended += int(s[3].sum())
    assert ended >= n  # every lane went through an autoreset


def test_the_crawl_reward_pays_for_crawling_not_for_resting():
    env = gymnasium.make("zoetic/SnakeCrawl-v0")
    body = env.unwrapped.core.body
    totals = {}
    for name, ctrl in (("wave", wave_controller(body)), ("rest", rest_controller(body))):
        env.reset(seed=0)
        period = env.unwrapped.core.period
        totals[name] = sum(env.step(ctrl.sample(np.array([k * period]))[0])[1] for k in range(60))
    assert totals["wave"] > 0.05
    assert abs(totals["rest"]) < 0.01


@pytest.mark.parametrize("env_id", ["zoetic/SharkSwim-v0", "zoetic/SharkTurn-v0"])
def test_observations_are_the_sensors_readings_of_the_world(env_id):
    from zoetic.control.sensors import observe

    env = gymnasium.make(env_id)
    env.reset(seed=2)
    rng = np.random.default_rng(5)
    for _ in range(3):
        obs = env.step(rng.random(env.action_space.shape[0]).astype(np.float32))[0]
    core = env.unwrapped.core
    goal = core.goal if core.kind == "swim" else None
    s = observe(core.world, 0, target=goal)
    want = [s["pitch"][0], s["roll"][0], s["depth"][0]]
    np.testing.assert_array_equal(obs[3:6], np.float32(want))
    # the heading frame is the sensors' heading (kept unwrapped across steps)
    assert np.isclose(np.angle(np.exp(1j * (core.heading[0] - s["heading"][0]))), 0.0)
    if core.kind == "swim":
        bearing, dist = s["target_bearing"][0], s["target_distance"][0]
        np.testing.assert_allclose(obs[6:9], [np.cos(bearing), np.sin(bearing), dist], rtol=1e-6)
    v, h = s["velocity"][0], s["heading"][0]
    fwd, left = np.cos(h) * v[0] + np.sin(h) * v[2], -np.sin(h) * v[0] + np.cos(h) * v[2]
    np.testing.assert_allclose(obs[:3], [fwd, v[1], left], rtol=1e-5, atol=1e-7)


def test_rewards_are_the_change_of_the_tasks_terms():
    from zoetic.tasks.signals import BodyFrame, Signals
    from zoetic.tasks.terms import TERMS, TermParams

    env = gymnasium.make("zoetic/SharkSwim-v0")
    env.reset(seed=0)
    core = env.unwrapped.core
    frame = BodyFrame.of(core.body)

    def distance() -> float:
        pos = core.world.positions(0)[:, None]
        s = Signals(np, frame, pos, np.zeros((1, 1, core.n_act)), np.zeros(1), 0.0, 1.0)
        return float(TERMS["goal_distance_xz"].fn(np, s, TermParams(0.0, core.goal))[0])

    ctrl = wave_controller(core.body)
    for k in range(4):
        before = distance()
        reward = env.step(ctrl.sample(np.array([k * core.period]))[0])[1]
        assert reward == pytest.approx(before - distance(), abs=1e-12)
