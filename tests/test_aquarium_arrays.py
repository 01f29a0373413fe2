"""The aquarium's paths over all fishes at once equal the per-fish ones they replace.

The tank computes perception (compiled), situations and drives for every fish in one step;
each must give exactly what the per-fish formulas give for each fish alone.
"""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.behavior.aquarium.perception import (
    STEP,
    blocked,
    in_view,
    obstacle_distance,
    perceive,
)
from zoetic.behavior.mind import MindState, drives, drives_many, fear, focus
from zoetic.physics.objects import Box, Cylinder, pack_statics


def _scene(rng, n=7, m=9, f=6):
    kind, center, size = pack_statics(
        [
            Box((0.0, 0.0, 0.0), (1.0, 2.0, 0.6)),
            Cylinder((3.0, 0.0, -2.0), 0.7, 4.0, "y"),
            Box((-3.0, 0.0, 2.5), (0.4, 2.0, 1.2)),
            Box((9.25, 0.0, 0.0), (0.25, 2.0, 9.5)),
        ]
    )

    def points(k):
        return np.column_stack(
            [rng.uniform(-6, 6, k), rng.uniform(-1, 1, k), rng.uniform(-6, 6, k)]
        )

    fwd = rng.normal(size=(n, 3))
    fwd /= np.linalg.norm(fwd, axis=1, keepdims=True)
    return points(n), fwd, points(m), points(f), kind, center, size


def _blocked_by_points(eyes, targets, ask, kind, center, size):
    """The definition: k - 1 points i/k along each asked segment, k from the longest."""
    out = np.zeros(ask.shape, bool)
    ii, jj = np.nonzero(ask)
    if len(ii) == 0:
        return out
    seg = targets[jj] - eyes[ii]
    k = max(2, int(np.ceil(np.linalg.norm(seg, axis=-1).max() / STEP)))
    u = (np.arange(1, k) / k)[None, :, None]
    pts = eyes[ii][:, None, :] + u * seg[:, None, :]
    out[ii, jj] = (obstacle_distance(pts, kind, center, size) < 0).any(axis=(-1, -2))
    return out


def _oracle(eyes, fwd, fish, alive, food, left, kind, center, size, va, vr, sr):
    """The oracle's formulas, every eye against every target in numpy: (fish, food,
    obstacles) distances perceived (inf where not)."""
    rel = fish[None] - eyes[:, None]
    d = np.linalg.norm(rel, axis=-1)
    cos = (rel * fwd[:, None]).sum(-1) / np.maximum(d, 1e-9)
    half = np.cos(np.radians(va) / 2)[:, None]
    vf = (d <= vr[:, None]) & (cos >= half) & alive[None]
    vf &= ~_blocked_by_points(eyes, fish, vf, kind, center, size)
    np.fill_diagonal(vf, False)
    rel = food[None] - eyes[:, None]
    dd = np.linalg.norm(rel, axis=-1)
    cos = (rel * fwd[:, None]).sum(-1) / np.maximum(dd, 1e-9)
    vd = (dd <= vr[:, None]) & (cos >= half) & left[None]
    vd &= ~_blocked_by_points(eyes, food, vd, kind, center, size)
    vd = (vd | (dd <= sr[:, None])) & left[None]
    do = obstacle_distance(eyes, kind, center, size)
    to_c = center[None] - eyes[:, None]
    cos = (to_c * fwd[:, None]).sum(-1) / np.maximum(np.linalg.norm(to_c, axis=-1), 1e-9)
    seen = (do <= vr[:, None]) & ((cos >= half) | (do < 1.0))
    return np.where(vf, d, np.inf), np.where(vd, dd, np.inf), np.where(seen, do, np.inf)


def _perceived_as_the_oracle(*args):
    """Return ``perceive(*args)`` after checking that fishes, food and obstacles are what
    the oracle's formulas give, every entry equal."""
    pc = perceive(*args)
    want_fish, want_food, want_obstacles = _oracle(*args)
    assert np.array_equal(pc.fish, want_fish)
    assert np.array_equal(pc.food, want_food)
    assert np.array_equal(pc.obstacles, want_obstacles)
    return pc


@pytest.mark.parametrize("seed", range(4))
def test_compiled_perception_equals_the_oracles_formulas(seed):
    rng = np.random.default_rng(seed)
    eyes, fwd, fish, food, kind, center, size = _scene(rng)
    fish[: len(eyes)] = eyes + 0.3 * fwd  # the fishes' own centres behind their noses
    alive = rng.random(len(fish)) > 0.2
    left = rng.random(len(food)) > 0.3
    va = rng.uniform(200, 330, len(eyes))
    vr = rng.uniform(4, 12, len(eyes))
    sr = rng.uniform(0, 3, len(eyes))
    pc = _perceived_as_the_oracle(
        eyes, fwd, fish, alive, food, left, kind, center, size, va, vr, sr
    )
    # the scene is not trivial: some sight lines are blocked, some targets out of view
    assert np.isfinite(pc.fish).sum() > 5 and (np.isinf(pc.fish).sum() > len(eyes))
    every = np.ones((len(eyes), len(fish)), bool)
    assert _blocked_by_points(eyes, fish, every, kind, center, size).any()


@pytest.mark.parametrize("seed", range(3))
def test_perception_of_a_wide_crowd_equals_every_pair_tested(seed):
    # a tank 60 m wide, ranges a tenth of it: the oracle tests only the pairs its grid
    # finds near each other (``neighbours``), and must perceive exactly what testing every
    # pair perceives, fishes exactly at the range's edge included
    rng = np.random.default_rng(seed)
    eyes, fwd, fish, food, kind, center, size = _scene(rng, n=150, m=150, f=200)
    eyes = np.round(eyes * [20.0, 4.0, 20.0]) / 4.0  # quarter metres: the edges exact
    food *= [5.0, 1.0, 5.0]
    vr = rng.choice([3.0, 6.0], len(eyes))
    fish = eyes + 0.3 * fwd
    fish[:20] = eyes[20:40] + [[6.0, 0.0, 0.0]]  # at the edge of eye 20-39's view (if 6 m)
    fish[20:40] = eyes[20:40] + 0.3 * fwd[20:40]
    food[:20] = eyes[40:60] - [[0.0, 0.0, 3.0]]  # at the edge of the smell (3 m)
    alive = rng.random(len(fish)) > 0.1
    left = rng.random(len(food)) > 0.1
    va = rng.uniform(200, 330, len(eyes))
    sr = np.full(len(eyes), 3.0)
    pc = _perceived_as_the_oracle(
        eyes, fwd, fish, alive, food, left, kind, center, size, va, vr, sr
    )
    assert (pc.fish == 6.0).any() and (pc.food == 3.0).any()  # edge pairs perceived
    assert np.isfinite(pc.fish).sum() > 100 and np.isfinite(pc.food).sum() > 50


def test_blocked_with_bounding_boxes_equals_every_point_against_every_obstacle():
    rng = np.random.default_rng(7)
    eyes, _, targets, _, kind, center, size = _scene(rng, n=20, m=30)
    ask = rng.random((20, 30)) > 0.3
    want = _blocked_by_points(eyes, targets, ask, kind, center, size)
    assert np.array_equal(blocked(eyes, targets, kind, center, size, ask), want)
    assert want.any() and not want.all()
    # segments that end just short of a box's face, or graze its corner, are not blocked
    e = np.array([[-3.0, 0.0, 0.0], [-3.0, 0.0, 0.6 + 1e-6]])
    t = np.array([[-1.0 - 1e-6, 0.0, 0.0], [3.0, 0.0, 0.6 + 1e-6], [3.0, 0.0, 0.0]])
    got = blocked(e, t, kind, center, size)
    assert np.array_equal(got, _blocked_by_points(e, t, np.ones((2, 3), bool), kind, center, size))
    assert not got[0, 0] and not got[1, 1] and got[0, 2]


def test_sight_lines_just_inside_a_face_are_blocked():
    # a box (half sizes 1, 0.5, 0.6) at the origin and a cylinder (radius 0.7) at x = 4:
    # (half length 0.5): lines parallel to their sides, 5 cm inside each side (the bounding
    # boxes must keep them)
    kind, center, size = pack_statics(
        [Box((0.0, 0.0, 0.0), (1.0, 0.5, 0.6)), Cylinder((4.0, 0.0, 0.0), 0.7, 1.0, "y")]
    )
    segments = [
        ((-0.95, 0.0, -3.0), (-0.95, 0.0, 3.0)),
        ((0.95, 0.0, -3.0), (0.95, 0.0, 3.0)),
        ((-3.0, 0.0, -0.55), (1.4, 0.0, -0.55)),
        ((-3.0, 0.0, 0.55), (1.4, 0.0, 0.55)),
        ((-3.0, -0.45, 0.0), (1.4, -0.45, 0.0)),
        ((-3.0, 0.45, 0.0), (1.4, 0.45, 0.0)),
        ((3.35, 0.0, -3.0), (3.35, 0.0, 3.0)),
        ((4.65, 0.0, -3.0), (4.65, 0.0, 3.0)),
        ((2.5, 0.0, -0.3), (5.4, 0.0, -0.3)),
        ((2.5, 0.45, 0.3), (5.4, 0.45, 0.3)),
    ]
    eyes, targets = (np.array(x, float) for x in zip(*segments, strict=True))
    got = blocked(eyes, targets, kind, center, size, np.eye(len(eyes), dtype=bool))
    assert got.diagonal().all()


def test_in_view_equals_the_cone_and_range_formulas():
    rng = np.random.default_rng(3)
    eyes, fwd, targets, _, _, _, _ = _scene(rng, n=5, m=12)
    d, ok = in_view(eyes, fwd, targets, 300.0, 6.0)
    rel = targets[None] - eyes[:, None]
    want = np.linalg.norm(rel, axis=-1)
    cos = (rel * fwd[:, None]).sum(-1) / np.maximum(want, 1e-9)
    assert np.array_equal(d, want)
    assert np.array_equal(ok, (want <= 6.0) & (cos >= np.cos(np.radians(300.0) / 2)))


class _C:  # mind constants
    hunger_rate, alpha, libido_rate, fear_distance = 0.01, 1.0, 0.02, 2.0


def test_drives_many_equals_drives_of_each_mind():
    rng = np.random.default_rng(1)
    n = 9
    minds = [
        MindState(
            eaten=float(rng.integers(0, 4)),
            meal_time=float(rng.uniform(-80, 30)),
            mating_time=float(rng.uniform(-40, 30)),
        )
        for _ in range(n)
    ]
    # perceived predators: up to three a fish, the rest of each row unperceived
    pred = np.where(rng.random((n, 6)) < 0.35, rng.uniform(0.0, 9.0, (n, 6)), np.inf)
    pred[0] = np.inf
    pred[1, :3] = [0.5, 4.0, 1e-12]
    c = _C()
    h, lib, f = drives_many(
        [m.eaten for m in minds],
        [m.meal_time for m in minds],
        [m.mating_time for m in minds],
        30.0,
        c.hunger_rate,
        c.alpha,
        c.libido_rate,
        c.fear_distance,
        pred,
    )
    for i, m in enumerate(minds):
        row = tuple(float(x) for x in pred[i] if np.isfinite(x))
        want = drives(m, 30.0, c, row)
        assert (h[i], lib[i], f[i]) == (want.hunger, want.libido, want.fear)
    assert f[0] == 0.0 and f[1] == 1.0 and h.min() < h.max() and lib.max() > 0.0
    # a few predators summed in plain floats, many in numpy: the same formula
    assert fear((8.0, 10.0, 4.0), 2.0) == fear(np.array([8.0, 10.0, 4.0]), 2.0)


def test_focus_keeps_its_rules():
    assert focus(np.array([np.inf, np.inf])) is None
    assert focus(np.array([])) is None
    assert focus(np.array([3.0, 2.0, 5.0])) == 1
    assert focus(np.array([3.0, 2.6, 5.0]), previous=0) == 0  # within 1.25x: kept
    assert focus(np.array([3.0, 2.0, 5.0]), previous=0) == 1  # 1.5x farther: switch
    assert focus(np.array([np.inf, 2.0]), previous=0) == 1  # lost from view


def _situation_of(brain, d, food, obst, masks, collision):
    """One fish's Situation by the definitions, fish by fish (the reference)."""
    from zoetic.behavior.mind import Situation

    same, hunters, prey = masks
    ps, crowd = brain.species.habits.personal_space, brain.species.habits.crowd
    seen = np.isfinite(d)
    return Situation(
        collision=collision,
        predator_distances=tuple(float(x) for x in d[hunters & seen]),
        food_distance=float(food.min()) if len(food) else np.inf,
        mate_distance=float(d[same].min(initial=np.inf)),
        prey_distance=float(d[prey].min(initial=np.inf)),
        crowded=int(np.sum(d < ps)) > crowd,
        alone=not seen.any(),
        near_obstacle=bool(len(obst)) and float(obst.min()) < ps,
    )


def test_situations_of_all_fishes_equal_each_fishs_own():
    from zoetic.behavior.aquarium.brain import FishBrain, View, situations
    from zoetic.behavior.aquarium.routines import Me
    from zoetic.behavior.aquarium.species import load_species
    from zoetic.behavior.mind import Situations
    from zoetic.bodies import load_animal

    minnow, shark = load_species("minnow"), load_species("shark")
    names = ("shark", "minnow", "minnow", "minnow", "minnow", "minnow")
    hunted = {"shark": frozenset(), "minnow": frozenset({"shark"})}
    kinds = {s.name: FishBrain(s, load_animal(s.body), hunted[s.name]) for s in (minnow, shark)}
    brains = [kinds[nm] for nm in names]
    rng = np.random.default_rng(5)
    n = len(names)
    for trial in range(6):
        fish = np.where(rng.random((n, n)) < 0.6, rng.uniform(0.2, 6.0, (n, n)), np.inf)
        np.fill_diagonal(fish, np.inf)
        if trial == 0:
            fish[2] = np.inf  # a fish that sees no one
        food = np.where(rng.random((n, 4)) < 0.5, rng.uniform(0.5, 9.0, (n, 4)), np.inf)[
            :, : trial % 5
        ]
        obst = rng.uniform(0.0, 3.0, (n, 3))
        hits = (rng.random(n) < 0.3).tolist()
        masks = [b.kinds(names) for b in brains]
        sits, pred = situations(
            fish,
            food,
            obst,
            *(np.array([m[k] for m in masks]) for k in range(3)),
            np.array([b.species.habits.personal_space for b in brains]),
            np.array([b.species.habits.crowd for b in brains]),
            hits,
        )
        me = Me(np.zeros(3), np.zeros(3), np.array([1.0, 0, 0]), np.zeros(3), 0.2, 0.4)
        for i, b in enumerate(brains):
            v = View(
                me,
                fish[i],
                np.zeros((n, 3)),
                np.zeros((n, 3)),
                np.zeros((n, 3)),
                names,
                food[i],
                np.zeros((food.shape[1], 3)),
                obst[i],
                hits[i],
                None,
            )
            own, own_pred = b._situation(v)
            ref = _situation_of(b, fish[i], food[i], obst[i], masks[i], hits[i])
            for k in Situations.__dataclass_fields__:
                assert getattr(sits, k)[i] == getattr(own, k)[0] == getattr(ref, k), k
            assert np.array_equal(pred[i], np.where(masks[i][1], fish[i], np.inf))
            assert np.array_equal(own_pred[0], pred[i])
            assert tuple(pred[i][np.isfinite(pred[i])]) == ref.predator_distances


def test_world_reads_all_positions_at_once_and_names_the_animals_it_tested_for_contact():
    from zoetic.behavior.aquarium.species import load_species
    from zoetic.bodies import load_animal
    from zoetic.physics.world import Animal, World

    body = load_animal(load_species("minnow").body)
    com = body.mass @ body.rest_pos / body.total_mass
    size = np.ptp(body.rest_pos, axis=0)
    # one minnow swimming into a rock just ahead of its nose, one far from everything
    rock = Box((com[0] + 0.6 * size[0], com[1], com[2]), (0.1, 1.0, 1.0), name="rock")
    world = World(
        [Animal(body, (0.0, 0.0, 0.0), 0.0, (1.5, 0.0, 0.0)), Animal(body, (0.0, 0.0, 6.0)), rock],
        medium="water",
    )
    touched = []
    for _ in range(10):
        c = world.step(0.05)
        all_pos, off = world.node_positions(), world.offsets
        for a in range(2):
            assert np.array_equal(all_pos[off[a] : off[a + 1]], world.positions(a)[0])
        touched.append(c.touching[0])
        assert c.near is not None and 1 not in c.near
        for a in range(2):  # an animal not tested got no impulse
            assert a in c.near or not c.touching[0, a].any()
    assert np.array(touched)[:, 0, 0].any()  # the first minnow did hit the rock


def test_every_minds_thought_at_once_is_each_minds_own():
    from zoetic.behavior.aquarium.species import load_species
    from zoetic.behavior.mind import (
        INTENTIONS,
        Drives,
        Situation,
        Situations,
        Tempers,
        think,
        think_many,
    )

    minnow, shark = load_species("minnow"), load_species("shark")
    rng = np.random.default_rng(9)
    n = 400
    kinds = [shark if k % 7 == 0 else minnow for k in range(n)]
    consts = [s.fear_constants() for s in kinds]
    tempers = Tempers.of(consts, [s.habits for s in kinds], [s.predator for s in kinds])
    minds = [
        MindState(
            intention=str(rng.choice(INTENTIONS)),
            since=float(rng.uniform(8.0, 10.0)),
            reflex=bool(rng.random() < 0.5),
            threatened=float(rng.uniform(9.0, 10.0)),
        )
        for _ in range(n)
    ]
    far = lambda: float(rng.choice([np.inf, rng.uniform(0.02, 3.0)]))  # noqa: E731
    sits = [
        Situation(
            bool(rng.random() < 0.2),
            (),
            far(),
            far(),
            far(),
            bool(rng.random() < 0.3),
            bool(rng.random() < 0.3),
            bool(rng.random() < 0.3),
            bool(rng.random() < 0.5),
        )  # fmt: skip
        for _ in range(n)
    ]
    hunger, libido, fear = rng.uniform(0, 1, (3, n)).round(1)  # ties between hunger and libido
    many = think_many(minds, 10.0, tempers, Situations.of(sits), hunger, libido, fear)
    for k in range(n):
        d = Drives(float(hunger[k]), float(libido[k]), float(fear[k]))
        own, _ = think(minds[k], 10.0, consts[k], kinds[k].habits, sits[k], kinds[k].predator, d)
        assert many[k] == own
    assert len({m.intention for m in many}) >= 7  # every branch met
    assert sum(m.intention != s.intention for m, s in zip(many, minds, strict=True)) > 50
