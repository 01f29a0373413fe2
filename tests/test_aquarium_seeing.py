"""Several seeing predators (``--seeing``): their retinas rendered and recognised in one batch
give the same images, detections, sightings and pursuit as each fish's eyes alone."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from zoetic.behavior.aquarium import tank as tk
from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live
from zoetic.behavior.aquarium.vision import FishEyes, TankEyes, _look, _stack, render_eyes
from zoetic.cli import main
from zoetic.cli.aquarium import seeing_count
from zoetic.errors import SimulationError, ZoeticError
from zoetic.perception.eyes import look
from zoetic.perception.gaze import _gray, target_image
from zoetic.perception.pursuit import FOG
from zoetic.perception.recognition import histogram, locate, recognise
from zoetic.physics.world import Animal, World


def _tank(seconds=1.0, seeing=3):
    """Three sharks in a row heading +x, each with a minnow ahead of it a little to the left,
    and a fourth minnow behind them all, in an empty tank."""
    cfg = TankConfig(
        fishes=7,
        predators=3,
        food=0,
        obstacles=0,
        seconds=seconds,
        seed=3,
        half_size=10.0,
        perception="vision",
        seeing=seeing,
    )
    t = build_tank(cfg)
    sharks = [k for k, f in enumerate(t.fishes) if f.species.predator]
    minnows = [k for k, f in enumerate(t.fishes) if not f.species.predator]
    at = {}
    for n, k in enumerate(sharks):
        at[k] = np.array([-3.0, 0.0, 3.0 * (n - 1)])
        at[minnows[n]] = at[k] + np.array([2.3, 0.0, 0.5])
    at[minnows[3]] = np.array([-8.0, 0.0, 0.0])
    animals = []
    for k, f in enumerate(t.fishes):
        com0 = f.body.mass @ f.body.rest_pos / f.body.total_mass
        animals.append(Animal(f.body, tuple(at[k] - com0), 0.0, (0.2, 0.0, 0.0)))
    world = World([*animals, *t.world.statics], medium="water")
    return tk.Tank(cfg, world, t.fishes, t.kind, t.center, t.size, t.static_names)


def _prey(tank, eyes):
    minnows = np.array([k for k, f in enumerate(tank.fishes) if not f.species.predator])
    return {a: minnows for a in eyes.animals}


def test_the_batched_retinas_are_each_eyes_own_render_pixel_for_pixel():
    tank = _tank()
    eyes = tk._eyes(tank)
    assert len(eyes.eyes) == 3
    world = tank.world
    aims = [e.aim(world) for e in eyes.eyes]
    mesh = eyes.scenery.mesh(world)
    spec = eyes.eyes[0].gaze.spec
    batch = render_eyes(mesh, _stack([c for _, c in aims]), spec)
    assert batch.shape == (3, 2, spec.levels, spec.size, spec.size, 3)
    for k, (e, (frame, _)) in enumerate(zip(eyes.eyes, aims, strict=True)):
        alone, _ = look(mesh, frame, e.state.angles, spec, FOG)
        assert np.array_equal(batch[k], alone)
    # each shark sees its own minnow: the prey's colour somewhere in every shark's images
    found = recognise(
        batch.reshape(-1, spec.size, spec.size, 3),
        np.repeat(np.stack([e.gaze.model for e in eyes.eyes]), 2 * spec.levels, 0),
    )
    strength = np.array([d.strength for d in found.detections]).reshape(3, -1)
    assert (strength.max(1) >= eyes.eyes[0].gaze.threshold).all()
    # the three sharks' images differ: each camera drew its own view
    assert not np.array_equal(batch[0], batch[1]) and not np.array_equal(batch[1], batch[2])


def test_recognising_a_batch_gives_each_images_histogram_and_detection():
    rng = np.random.default_rng(0)
    tank = _tank()
    eyes = tk._eyes(tank)
    spec = eyes.eyes[0].gaze.spec
    _, cams = eyes.eyes[0].aim(tank.world)
    imgs = render_eyes(eyes.scenery.mesh(tank.world), cams, spec).reshape(
        -1, spec.size, spec.size, 3
    )
    noise = rng.integers(0, 256, (3, spec.size, spec.size, 3), dtype=np.uint8)
    imgs = np.concatenate([imgs, noise])
    models = rng.dirichlet(np.ones(2048), len(imgs))
    models[: len(imgs) - 3] = eyes.eyes[0].gaze.model
    got = recognise(imgs, models)
    for k, img in enumerate(imgs):
        assert np.array_equal(got.histograms[k], histogram(img))
        assert got.detections[k] == locate(img, models[k])
        assert np.array_equal(got.grays[k], _gray(img))
        assert np.array_equal(got.targets[k], target_image(img, models[k]))


def test_the_coarse_levels_are_drawn_only_for_a_fish_whose_fine_levels_miss_its_prey():
    tank = _tank()
    eyes = tk._eyes(tank)
    world = tank.world
    eyes.eyes[1].state.angles[:, 1] = np.radians(40.0)  # the middle shark looks up, away
    aims = [e.aim(world) for e in eyes.eyes]
    mesh = eyes.scenery.mesh(world)
    spec = eyes.eyes[0].gaze.spec
    n, s = spec.levels, spec.size
    images, found = _look(mesh, eyes.eyes, [c for _, c in aims], spec)
    full = render_eyes(mesh, _stack([c for _, c in aims]), spec)
    assert np.array_equal(images[:, :, n - 2 :], full[:, :, n - 2 :])
    assert np.array_equal(images[1], full[1])  # its minnow only in its periphery: all drawn
    assert not images[[0, 2], :, : n - 2].any()  # the others see theirs in the fine levels
    models = np.repeat(np.stack([e.gaze.model for e in eyes.eyes]), 2 * n, 0)
    whole = recognise(full.reshape(-1, s, s, 3), models)
    for k in range(3):
        drawn = range(2 * n) if k == 1 else [i for i in range(2 * n) if i % n >= n - 2]
        for i in drawn:
            assert found[k].detections[i] == whole.detections[2 * n * k + i]
            assert np.array_equal(found[k].histograms[i], whole.histograms[2 * n * k + i])
    strength = [d.strength for d in found[1].detections]
    assert max(strength[: n - 2]) >= eyes.eyes[1].gaze.threshold > max(strength[n - 2 : n])


def test_batched_eyes_see_and_move_as_each_fishs_eyes_alone():
    tank = _tank()
    batched = tk._eyes(tank)
    alone = copy.deepcopy(batched.eyes)
    prey = _prey(tank, batched)
    world = tank.world
    sights = 0
    for _ in range(4):
        together = batched.see(world, prey)
        for e in alone:
            s = e.see(world, prey[e.animal])
            b = together[e.animal]
            assert (s is None) == (b is None)
            if s is not None:
                sights += 1
                assert s.fish == b.fish and s.distance == b.distance
                assert np.array_equal(s.point, b.point)
        for e, f in zip(alone, batched.eyes, strict=True):
            assert np.array_equal(e.state.angles, f.state.angles)
            assert np.array_equal(e.state.locked, f.state.locked)
        world.step(0.1, None)
    assert sights >= 6  # the sharks do see their minnows


def test_a_tank_of_seeing_sharks_hunts_as_with_each_fishs_eyes_alone(monkeypatch):
    runs = []
    for batched in (True, False):
        if not batched:

            def one_by_one(self, world, prey):
                return {
                    e.animal: e.see(world, prey[e.animal]) for e in self.eyes if e.animal in prey
                }

            monkeypatch.setattr(TankEyes, "see", one_by_one)
        tank = _tank(seconds=1.5)
        runs.append(live(tank))
    a, b = runs
    assert np.array_equal(a.intentions, b.intentions)
    assert np.array_equal(a.targets, b.targets)
    assert np.array_equal(a.positions, b.positions)
    sharks = [0, 1, 2]
    hunting = a.intentions[-5:, sharks] == tk.INTENTIONS.index("hunt")
    assert hunting.all() and (a.targets[-5:, sharks] >= 3).all()


def test_only_the_first_seeing_predators_get_eyes():
    tank = _tank(seeing=2)
    eyes = tk._eyes(tank)
    assert eyes.animals == [k for k, f in enumerate(tank.fishes) if f.species.predator][:2]
    assert all(isinstance(e, FishEyes) for e in eyes.eyes)


def test_a_bad_seeing_count_is_refused():
    with pytest.raises(SimulationError, match="--seeing"):
        build_tank(TankConfig(fishes=4, predators=2, perception="vision", seeing=3))
    with pytest.raises(SimulationError, match="--seeing"):
        build_tank(TankConfig(fishes=4, predators=2, perception="vision", seeing=0))
    assert seeing_count("all", 4) == 4 and seeing_count("2", 4) == 2
    for bad in ("0", "-1", "two", "1.5", ""):
        with pytest.raises(ZoeticError, match="--seeing"):
            seeing_count(bad, 4)


@pytest.mark.parametrize("value", ["0", "x", "3"])
def test_the_cli_exits_2_naming_seeing(value, capsys):
    args = ["bench", "aquarium", "--perception", "vision", "--predators", "2", "--seeing", value]
    assert main([*args, "--seconds", "0.5", "--fishes", "4"]) == 2
    err = capsys.readouterr().err
    assert "--seeing" in err and "Traceback" not in err
