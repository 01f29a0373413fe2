"""A run does not depend on how its steps are sliced: the world decides its broad phase and
its food test on its own grid, and the aquarium takes a period's events at the period's end."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live, summarize
from zoetic.bodies import load_animal
from zoetic.control import wave_controller
from zoetic.physics.objects import Box, Food
from zoetic.physics.world import Animal, World


def _busy_world() -> tuple[World, np.ndarray]:
    """Two sharks swimming nose to nose, a third into a rock, food on the first's way and
    drifting in a current; return the world and a wave (T, A) for 0.6 s."""
    body = load_animal("shark")
    sharks = [
        Animal(body, (0.0, 0.0, 0.0), 0.0, (1.0, 0.0, 0.0)),
        Animal(body, (1.3, 0.0, 0.1), np.pi, (-1.0, 0.0, 0.0)),
        Animal(body, (0.0, 0.0, 3.0), 0.0, (1.5, 0.0, 0.0)),
    ]
    rock = Box((0.9, 0.0, 3.0), (0.2, 1.0, 1.0), name="rock")
    food = [Food((0.25, 0.02, -0.05), 0.1), Food((0.45, 0.0, 2.96), 0.1)]
    world = World([*sharks, rock, *food], medium="water", current=(0.0, 0.0, 0.13))
    table = wave_controller(body).table(world.steps_for(0.6), world.dt)
    return world, table


def _run(slices: list[float]):
    """Step the busy world through ``slices`` (s); return its final state, the (animal,
    object) pairs and animal pairs that touched, and which particles were eaten after each
    call (by step)."""
    world, table = _busy_world()
    touched, between, eaten = set(), np.zeros((3, 3), bool), {0: world.food_eaten[0]}
    for seconds in slices:
        t0 = world.step_count
        steps = world.steps_for(seconds)
        c = world.step(seconds, [table[None, t0 : t0 + steps]] * 3)
        touched |= {tuple(x) for x in np.argwhere(c.touching[0])}
        if c.between is not None:
            between |= c.between[0] > 0.0
        eaten[world.step_count] = world.food_eaten[0]
    return world.state, touched, between, eaten


def test_splitting_the_steps_changes_nothing_in_the_world():
    whole = _run([0.1] * 6)
    state, touched, between, eaten = whole
    # the scene does what it is for: a rock and a fish touched, food eaten
    assert (2, 0) in touched and between[0, 1] and between[1, 0]
    assert eaten[120].all() and not eaten[40].all() and not eaten[0].any()
    for slices in ([0.05] * 12, [0.03] * 20, [0.035, 0.1, 0.015, 0.2, 0.05, 0.2]):
        other = _run(slices)
        for a in range(3):
            np.testing.assert_array_equal(other[0].positions[a], state.positions[a])
            np.testing.assert_array_equal(other[0].velocities[a], state.velocities[a])
        np.testing.assert_array_equal(other[0].food_positions, state.food_positions)
        np.testing.assert_array_equal(other[0].food_eaten, state.food_eaten)
        assert other[1] == touched and np.array_equal(other[2], between)
        # eaten on the world's grid (every 20 steps), whenever the caller looks
        for step, e in other[3].items():
            np.testing.assert_array_equal(e, eaten[step // 20 * 20])


# seeds whose 4 s hold a collision (16: a minnow touches a rock; 2: a minnow the wall)
@pytest.mark.parametrize("seed", [16, 2])
def test_the_record_period_does_not_change_an_aquarium_run(seed):
    def run(record):
        cfg = TankConfig(
            fishes=6,
            food=8,
            obstacles=3,
            half_size=5.0,
            food_margin=2.0,
            seconds=4.0,
            seed=seed,
            record_period=record,
        )
        tank = build_tank(cfg)
        life = live(tank)
        return life, summarize(tank, life)

    (base, s0), *others = [run(r) for r in (0.1, 0.05, 0.03)]
    kinds = {e[2] for e in base.events}
    assert "collision" in kinds and ("eat" in kinds or seed != 2)
    for life, s in others:
        assert life.events == base.events
        assert {k: v for k, v in s.items() if k not in ("wall_seconds", "realtime_factor")} == {
            k: v for k, v in s0.items() if k not in ("wall_seconds", "realtime_factor")
        }
        # positions at the record times the runs share, bit for bit
        steps = [np.round(x.times / 0.005).astype(int) for x in (life, base)]
        common, i, j = np.intersect1d(*steps, return_indices=True)
        assert len(common) >= 10
        for p, q in zip(life.positions, base.positions, strict=True):
            np.testing.assert_array_equal(p[i], q[j])
        np.testing.assert_array_equal(life.intentions, base.intentions)


def test_an_aquarium_records_on_its_grid_and_at_its_end_and_decides_every_period():
    cfg = TankConfig(fishes=2, predators=1, food=1, obstacles=0, seconds=0.37, record_period=0.03)
    tank = build_tank(cfg)
    dt, end = tank.world.dt, tank.world.steps_for(cfg.seconds)
    every, period = round(cfg.record_period / dt), round(cfg.control_period / dt)
    assert end % every and end % period  # the run ends between records and mid-period
    life = live(tank)
    assert np.round(life.times / dt).astype(int).tolist() == [*range(0, end, every), end]
    assert np.round(life.brain_times / dt).astype(int).tolist() == list(range(0, end, period))
    assert all(len(p) == len(life.times) for p in [*life.positions, life.food, life.eaten])
