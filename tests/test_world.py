"""The world: lockstep with open-loop simulate, contacts that conserve momentum, state a value."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import zoetic.physics.world as world_module
from zoetic.bodies import load_animal
from zoetic.control import wave_controller
from zoetic.errors import SimulationError
from zoetic.physics import State, simulate
from zoetic.physics.objects import Ball, Box, Cylinder, Food
from zoetic.physics.world import Animal, World, WorldState


def _slices(world, table, period=1 / 30):
    """Step a world through an open-loop table (B, T, A) in slices of ``period``."""
    steps = table.shape[1]
    while world.step_count < steps:
        n = min(world.steps_for(period), steps - world.step_count)
        k = world.step_count
        world.step(n * world.dt, table[:, k : k + n])


def test_world_in_slices_follows_open_loop_simulate():
    body = load_animal("shark")
    steps = 300
    wave = wave_controller(body).table(steps, body.dt)
    table = np.stack([wave, 0.7 * wave[::-1]])  # two different candidates
    traj = simulate(body, table)
    world = World([body], batch=2)
    _slices(world, table)
    assert world.time == pytest.approx(steps * body.dt)
    np.testing.assert_allclose(world.positions(0), traj.final.positions, atol=1e-5)
    np.testing.assert_allclose(world.velocities(0), traj.final.velocities, atol=1e-4)
    # it moved: the comparison is not between two resting sharks
    assert np.abs(world.positions(0) - world.initial_state().positions[0]).max() > 0.05


def _shark_and_ball(medium="vacuum", speed=0.6):
    body = load_animal("shark")
    body = body.with_(node_damping=np.zeros(body.n_nodes))
    nose = body.rest_pos[body.head] + body.start_offset
    ball = Ball(radius=0.1, mass=0.3, position=tuple(nose + 0.25 * body.forward))
    world = World([Animal(body, velocity=tuple(speed * body.forward)), ball], medium=medium)
    return body, world


def test_a_ball_struck_by_the_nose_gains_the_momentum_the_body_loses():
    body, world = _shark_and_ball()

    def momentum():
        p_body = np.einsum("n,bnk->bk", body.mass, world.velocities(0))
        return p_body, world.balls[0].mass * world.ball_velocities[:, 0]

    body0, ball0 = momentum()
    received = np.zeros(3)
    touched = 0
    for _ in range(30):
        c = world.step(1 / 30)
        received += c.on_object(0)[0]
        touched += int(c.count[0])
    body1, ball1 = momentum()
    gained = (ball1 - ball0)[0]
    assert touched > 0
    speed = np.linalg.norm(body0[0]) / body.total_mass
    assert gained[0] > 0.5 * world.balls[0].mass * speed  # the ball was really struck forward
    np.testing.assert_allclose(body1 + ball1, body0 + ball0, atol=1e-4)  # nothing else acts
    np.testing.assert_allclose(received, gained, atol=1e-6)  # the contact record says so
    assert world.ball_positions[0, 0, 0] > world.balls[0].position[0] + 0.1


def test_state_copy_and_restore_reproduce_the_same_continuation(tmp_path):
    body, world = _shark_and_ball(medium="water")
    act = wave_controller(body).sample(np.array([0.3]))[0]
    world.step(0.1, act)
    saved = world.state
    path = saved.save(tmp_path / "state.npz")

    def future():
        out = []
        for _ in range(10):
            world.step(1 / 30, act)
            out.append(np.concatenate([world.positions(0).ravel(), world.ball_positions.ravel()]))
        return np.array(out)

    first = future()
    assert not np.allclose(first[-1], first[0])
    world.restore(saved)
    assert world.time == pytest.approx(saved.time)
    np.testing.assert_array_equal(future(), first)
    world.restore(WorldState.load(path))
    np.testing.assert_array_equal(future(), first)
    # the saved value did not move while the world stepped on
    np.testing.assert_array_equal(saved.positions[0], WorldState.load(path).positions[0])


def test_a_ball_floats_at_the_surface_and_drifts_with_the_current():
    body = load_animal("dolphin")
    light = Ball(radius=0.15, mass=0.5, position=(3.0, -1.0, 0.0))
    heavy = Ball(radius=0.15, mass=30.0, position=(6.0, -1.0, 0.0), name="stone")
    world = World([body, light, heavy], medium="sea", current=(0.2, 0.0, 0.0))
    world.step(8.0)
    (lb, hb) = world.ball_positions[0]
    assert lb[1] - 0.15 < 0.0 < lb[1] + 0.15  # floating: the level y = 0 cuts the ball
    assert hb[1] < -2.0  # the stone sinks
    assert lb[0] > 3.0 + 0.5  # carried by the current


def test_a_shark_cannot_swim_through_a_wall_or_a_post():
    body = load_animal("shark")
    nose = body.rest_pos[body.head] + body.start_offset
    wall = Box(center=tuple(nose + 0.5 * body.forward), half_size=(0.1, 2.0, 2.0))
    world = World([Animal(body, velocity=tuple(2.0 * body.forward)), wall], medium="vacuum")
    hits = 0
    for _ in range(30):
        hits += int(world.step(1 / 30).touching[0, 0, 0])
    assert hits > 0
    assert world.positions(0)[0, :, 0].max() < wall.center[0] - 0.1 + 0.05
    post = Cylinder(center=tuple(nose + 0.5 * body.forward), radius=0.1, length=4.0)
    world = World([Animal(body, velocity=tuple(2.0 * body.forward)), post], medium="vacuum")
    world.step(1.0)
    assert world.positions(0)[0, body.head, 0] < post.center[0]


def test_impulses_take_memory_only_for_the_animals_that_touched_something():
    """Food and untouched animals cost the contact record nothing: an animal that touched
    nothing gets one zero seen through every index, the one that hit the wall its impulses
    at the wall's column only (food never pushes)."""
    body = load_animal("shark")
    nose = body.rest_pos[body.head] + body.start_offset
    wall = Box(center=tuple(nose + 0.5 * body.forward), half_size=(0.1, 2.0, 2.0))
    food = [Food((20.0 + k, 0.5, 20.0)) for k in range(50)]
    far = Animal(body, offset=tuple(body.start_offset + (0.0, 0.0, 10.0)))
    world = World(
        [*food[:25], Animal(body, velocity=tuple(2.0 * body.forward)), wall, far, *food[25:]],
        medium="vacuum",
        batch=2,
    )
    hit = None
    for _ in range(30):
        c = world.step(1 / 30)
        assert c.impulse[1].shape == (2, body.n_nodes, 51, 3)
        assert c.impulse[1].strides == (0, 0, 0, 0) and not c.impulse[1].any()
        if c.touching[:, 0].any():
            hit = c.impulse[0]
    assert hit is not None and hit.strides != (0, 0, 0, 0)
    assert hit[:, :, 25].any() and not np.delete(hit, 25, axis=2).any()


def test_food_drifts_and_is_eaten_by_a_passing_head():
    body = load_animal("shark")
    nose = body.rest_pos[body.head] + body.start_offset
    ahead = Food(position=tuple(nose + 0.3 * body.forward))
    aside = Food(position=(0.0, 0.0, 5.0))
    world = World([Animal(body, velocity=tuple(1.0 * body.forward)), ahead, aside],
                  medium="vacuum", current=(0.0, 0.0, 0.1))  # fmt: skip
    world.step(0.5)
    assert world.food_eaten[0].tolist() == [True, False]
    assert world.food_positions[0, 1, 2] == pytest.approx(5.05)


def test_lanes_restore_on_their_own_and_bad_input_is_refused():
    body = load_animal("snake")
    world = World([body], batch=3)
    world.step(0.2, np.full(body.n_actuators, 0.8))
    moved = world.positions(0)
    world.restore(world.initial_state().take(0), lanes=[1])
    now = world.positions(0)
    np.testing.assert_array_equal(now[[0, 2]], moved[[0, 2]])
    np.testing.assert_allclose(now[1], world.initial_state().positions[0][0], atol=1e-6)
    with pytest.raises(SimulationError, match="actuators"):
        world.step(0.1, np.zeros(body.n_actuators + 1))
    with pytest.raises(SimulationError, match="rows"):
        world.step(0.1, np.zeros((3, 5, body.n_actuators)))
    with pytest.raises(SimulationError, match="2 animals"):
        World([body, body]).step(0.1, np.zeros(body.n_actuators))
    with pytest.raises(SimulationError, match="animals"):
        world.restore(replace(world.state, positions=()))


def test_two_kinds_of_animal_step_together_each_as_on_its_own():
    shark, ray = load_animal("shark"), load_animal("ray")
    steps = 240
    acts = {"shark": wave_controller(shark).table(steps, shark.dt),
            "ray": wave_controller(ray).table(steps, ray.dt)}  # fmt: skip
    world = World([Animal(ray, offset=(0.0, 0.0, 3.0)), shark], medium="water")
    world.step(steps * world.dt, {k: v[None] for k, v in acts.items()})
    alone = simulate(shark, acts["shark"], medium="water")
    np.testing.assert_allclose(world.positions(1), alone.final.positions, atol=1e-5)
    ray_alone = simulate(ray, acts["ray"], medium="water")
    np.testing.assert_allclose(world.positions(0), ray_alone.final.positions + [0, 0, 3], atol=1e-5)


def test_a_big_batch_in_one_long_slice_takes_the_threaded_kernel_and_agrees():
    body = load_animal("snake")
    batch, steps = 16, 600  # 16 x 600 lane-steps: past the threaded kernel's threshold
    rng = np.random.default_rng(1)
    table = np.repeat(rng.random((batch, steps // 50, body.n_actuators)), 50, axis=1)
    world = World([body], batch=batch)
    assert batch * steps >= world_module.PARALLEL_FROM
    world.step(steps * body.dt, table)
    np.testing.assert_allclose(world.positions(0), simulate(body, table).final.positions, atol=1e-5)


def test_many_lanes_in_short_slices_step_chunk_by_chunk_in_place_and_agree():
    body = load_animal("shark")
    batch, steps = 40, 40  # short slices take the one-thread kernel through 2 chunks (24, 16)
    rng = np.random.default_rng(2)
    table = np.repeat(rng.random((batch, steps // 10, body.n_actuators)), 10, axis=1)
    world = World([body], batch=batch)
    assert world._chunk < batch
    before = world.state
    _slices(world, table, period=0.02)
    np.testing.assert_allclose(world.positions(0), simulate(body, table).final.positions, atol=1e-5)
    # the state taken before is a value: stepping in place did not change it
    np.testing.assert_allclose(before.positions[0], world.initial_state().positions[0], atol=1e-6)


def test_a_blow_up_is_reported_with_its_step_and_spares_the_other_lanes():
    body = load_animal("shark")
    steps = 60
    table = np.stack([wave_controller(body).table(steps, body.dt)] * 2)
    world = World([body], batch=2)
    start = world.state
    vel = start.velocities[0].copy()
    vel[0, body.head] = (1e6, 0.0, 0.0)  # far faster than any node may go: lane 0 fails
    world.restore(replace(start, velocities=(vel,)))
    _slices(world, table, period=0.1)
    failed = world.state.failed_step[0]
    alone = simulate(body, table, state=State(start.positions[0], vel))
    assert failed[0] > 0 and failed[1] == -1
    # the kernel checks every 8 steps and at each call's end, so slices can find it sooner
    assert failed[0] <= alone.failed_step[0] and alone.failed_step[1] == -1
    assert np.isnan(world.positions(0)[0]).all() and np.isfinite(world.positions(0)[1]).all()


def test_a_dropped_ball_comes_to_rest_on_a_rock_and_rolls_off_nothing():
    body = load_animal("snake")
    rock = Box(center=(5.0, 0.25, 0.0), half_size=(0.5, 0.25, 0.5))
    ball = Ball(radius=0.1, mass=0.5, position=(5.0, 1.5, 0.0))
    world = World([body, rock, ball], medium="ground")
    world.step(3.0)
    centre = world.ball_positions[0, 0]
    assert centre[1] == pytest.approx(0.5 + 0.1, abs=0.02)  # on top of the rock
    assert abs(centre[0] - 5.0) < 0.01 and abs(world.ball_velocities[0, 0]).max() < 0.05
    # on the floor beside it, it rests at its radius
    world = World([body, Ball(radius=0.1, mass=0.5, position=(7.0, 1.0, 0.0))], medium="ground")
    world.step(3.0)
    assert world.ball_positions[0, 0, 1] == pytest.approx(0.1, abs=0.02)
