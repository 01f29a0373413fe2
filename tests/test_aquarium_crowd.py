"""A crowded tank: the neighbour searches that replace every-pair loops find what every pair
would, and a tank of more than 60 fishes builds with grown defaults and lives."""

from __future__ import annotations

import numpy as np
import pytest


def _crowd(rng, n: int, half: float):
    """Return noses, centres, unit headings and velocities (n, 3) of fishes in a square."""
    com = rng.uniform(-half, half, (n, 3))
    com[:, 1] *= 0.1
    fwd = rng.normal(size=(n, 3))
    fwd[:, 1] *= 0.2
    fwd /= np.linalg.norm(fwd, axis=1, keepdims=True)
    nose = com + 0.45 * fwd
    vel = fwd * rng.uniform(0.0, 1.2, (n, 1))
    return nose, com, fwd, vel


def test_close_pairs_in_a_crowd_are_the_pairs_close_finds_one_by_one(pairs_one_by_one):
    from zoetic.physics.bodycontact import close_pairs

    rng = np.random.default_rng(5)
    n, m = 80, 6
    centres = rng.uniform(-4.0, 4.0, (n, 1, 3, 2))
    pos = np.ascontiguousarray((centres + 0.25 * rng.normal(size=(n, m, 3, 2))).reshape(-1, 3, 2))
    vel = np.ascontiguousarray(rng.normal(0.0, 1.5, pos.shape))
    off = np.arange(n + 1, dtype=np.int64) * m
    reach = rng.uniform(0.2, 0.5, n)
    found = [tuple(p) for p in close_pairs(pos, vel, off, reach, 0.03, 0.1).tolist()]
    one_by_one = pairs_one_by_one(pos, vel, off, reach, 0.03, 0.1)
    assert found == one_by_one
    assert 0 < len(found) < n * (n - 1) // 4  # some pairs, far from all


def _dense_threats(nose, com, fwd, vel, seen, reach, half_width, anticipation):
    """Every pair's count of centre-line points in the sensitivity box and distance (the
    threat: the most points, the nearest on a tie), computed over all (i, j) at once."""
    from zoetic.behavior.aquarium.routines import CENTRE_LINE, THREAT_TIMES

    n = len(nose)
    f = fwd.copy()
    f[:, 1] = 0.0
    f /= np.linalg.norm(f, axis=1, keepdims=True)
    left = np.stack([-f[:, 2], np.zeros(n), f[:, 0]], axis=1)
    line = nose[None] + np.linspace(0, 1, CENTRE_LINE)[:, None, None] * 2.0 * (com - nose)[None]
    t = np.linspace(0, 1, THREAT_TIMES)[:, None, None] * anticipation[None, :, None]
    rel = line[None, :, None] - nose[None, None, :, None]
    rel = rel + t[:, None, :, :, None] * (vel[None, :] - vel[:, None])[None, None]
    ahead, aside = np.einsum("kpijc,ic->kpij", rel, f), np.einsum("kpijc,ic->kpij", rel, left)
    inside = (ahead > 0) & (ahead < reach[None, None, :, None])
    inside &= np.abs(aside) < half_width[None, None, :, None]
    count = np.where(seen, inside.sum(axis=(0, 1)), 0)
    dist = np.linalg.norm(rel[0], axis=-1).min(axis=0)
    score = np.where(count > 0, count - dist / (dist.max() + 1.0), -np.inf)
    return np.where(count.max(axis=1) > 0, score.argmax(axis=1), -1)


def test_fish_threats_over_the_perceived_pairs_are_every_pairs_threats():
    from zoetic.behavior.aquarium.routines import fish_threats

    rng = np.random.default_rng(7)
    for n, half in ((40, 3.0), (25, 1.5)):
        nose, com, fwd, vel = _crowd(rng, n, half)
        seen = rng.random((n, n)) < 0.6
        np.fill_diagonal(seen, False)
        region = (np.full(n, 1.4), np.full(n, 0.5), np.full(n, 2.0))
        j, side, near = fish_threats(nose, com, fwd, vel, seen, *region)
        assert (j == _dense_threats(nose, com, fwd, vel, seen, *region)).all()
        assert (j >= 0).sum() > 3 and (side[j >= 0] != 0).all()
        assert np.isfinite(near[j >= 0]).all() and np.isinf(near[j < 0]).all()


def test_concessions_asked_for_some_particles_are_those_of_all_particles():
    from zoetic.behavior.aquarium.brain import conceded

    rng = np.random.default_rng(2)
    n, food = 30, rng.uniform(-4, 4, (20, 3))
    nose, _, fwd, _ = _crowd(rng, n, 4.0)
    eating, seen = rng.random(n) < 0.6, rng.random((n, n)) < 0.5
    np.fill_diagonal(seen, False)
    everywhere = conceded(nose, fwd, food, eating, seen)
    wanted = rng.random((n, len(food))) < 0.4
    assert everywhere.any()
    assert (conceded(nose, fwd, food, eating, seen, wanted) == (everywhere & wanted)).all()


def test_near_pairs_are_the_pairs_nearer_than_their_extents():
    from zoetic.behavior.aquarium.bodystate import near_pairs

    rng = np.random.default_rng(4)
    com, extent = rng.uniform(-5, 5, (120, 3)), rng.uniform(0.2, 0.9, 120)
    d = np.linalg.norm(com[:, None] - com[None], axis=-1)
    brute = np.argwhere(np.triu(d < extent[:, None] + extent[None], 1))
    assert len(brute) > 10
    assert (near_pairs(com, extent) == brute).all()
    assert near_pairs(com[:1], extent[:1]).shape == (0, 2)


def test_food_and_obstacles_grow_with_the_fishes_unless_given():
    from zoetic.behavior.aquarium.tank import TankConfig

    assert (TankConfig().food, TankConfig().obstacles) == (15, 5)
    big = TankConfig(fishes=1000)
    assert (big.food, big.obstacles) == (1500, 50)
    assert big.size() > 4 * TankConfig().size()
    assert TankConfig(fishes=1000, food=3, obstacles=0).food == 3


def test_a_tank_of_120_fishes_lives_and_one_of_2001_is_refused():
    from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live
    from zoetic.errors import SimulationError

    tank = build_tank(TankConfig(fishes=120, seconds=0.3, seed=1))
    life = live(tank)
    assert len(tank.fishes) == 120 and life.intentions.shape == (3, 120)
    moved = np.linalg.norm(life.positions[5][-1] - life.positions[5][0], axis=1).mean()
    assert moved > 0.05  # m in 0.3 s: a minnow swims
    with pytest.raises(SimulationError, match="at most 2000 fishes"):
        build_tank(TankConfig(fishes=2001))


def _dense_concessions(nose, forward, food, eating, seen):
    """Tu's focuser's concessions over every fish and every particle (the definition)."""
    to = food[None] - nose[:, None]
    to[..., 1] = 0.0
    dist = np.linalg.norm(to, axis=-1)
    heading = np.einsum("nfc,nc->nf", to, forward) / np.maximum(dist, 1e-9) > 0.7
    out = np.zeros(dist.shape, bool)
    for i, k in zip(*np.nonzero(seen & eating[None]), strict=True):
        out[i] |= heading[k] & (dist[k] < dist[i])
    return out


def test_concessions_over_the_perceiving_pairs_are_the_definitions():
    from zoetic.behavior.aquarium.brain import conceded

    rng = np.random.default_rng(3)
    n, food = 40, rng.uniform(-5, 5, (30, 3))
    nose, _, fwd, _ = _crowd(rng, n, 5.0)
    eating, seen = rng.random(n) < 0.5, rng.random((n, n)) < 0.4
    np.fill_diagonal(seen, False)
    want = _dense_concessions(nose, fwd, food, eating, seen)
    assert want.sum() > 20
    assert (conceded(nose, fwd, food, eating, seen) == want).all()
    assert not conceded(nose, fwd, food, np.zeros(n, bool), seen).any()


def test_every_fishs_ways_to_its_food_at_once_are_each_fishs_own():
    from zoetic.behavior.aquarium.reach import reach_costs, turn_paths

    rng = np.random.default_rng(4)
    n = 60
    nose, _, fwd, _ = _crowd(rng, n, 6.0)
    fwd[0] = (0.0, 1.0, 0.0)  # straight up: no horizontal heading
    radius = rng.uniform(0.5, 2.5, n)
    food = rng.uniform(-6, 6, (25, 3))
    dist = np.where(rng.random((n, 25)) < 0.7, 1.0, np.inf)
    costs = reach_costs(nose, fwd, radius, food, dist)
    assert np.isfinite(costs).sum() > 500
    for i in range(n):
        own = turn_paths(nose[i], fwd[i], radius[i], food).min(axis=0)
        seen = np.isfinite(dist[i])
        assert (costs[i, seen] == own[seen]).all()  # the same numbers, bit for bit
        assert (costs[i, ~seen] == np.inf).all()


def test_every_minds_focus_at_once_is_each_minds_own():
    from zoetic.behavior.mind import focus, focus_many

    rng = np.random.default_rng(5)
    d = np.where(rng.random((300, 8)) < 0.5, rng.uniform(1.0, 3.0, (300, 8)), np.inf)
    d[:20] = np.inf  # none perceived
    previous = rng.integers(-1, 9, 300)  # -1 none, 8 out of range
    many = focus_many(d, previous)
    own = [focus(row, None if p < 0 else int(p)) for row, p in zip(d, previous, strict=True)]
    assert many.tolist() == [-1 if t is None else t for t in own]

    def rule(row, p):  # the focuser's rule, one row in plain Python
        near = min(row.tolist())
        if near == np.inf:
            return -1
        kept = 0 <= p < len(row) and row[p] < np.inf and row[p] <= 1.25 * near
        return int(p) if kept else row.tolist().index(near)

    assert many.tolist() == [rule(row, p) for row, p in zip(d, previous, strict=True)]
    kept = (previous >= 0) & (previous < 8) & (many == previous)
    assert kept.sum() > 30 and (many[20:] != d[20:].argmin(axis=1)).sum() > 10  # kept some
    assert (many[:20] == -1).all()


def test_every_fishs_probes_at_once_are_each_fishs_own():
    from zoetic.behavior.aquarium.routines import Me, probe_reach, probes_ahead, probes_ahead_many

    rng = np.random.default_rng(6)
    n = 30
    nose, com, fwd, vel = _crowd(rng, n, 6.0)
    fwd[0] = (0.0, 1.0, 0.0)  # straight up: no horizontal heading
    cruise = rng.uniform(0.1, 0.4, n)
    meals = [None if k % 3 else float(rng.uniform(0.0, 5.0)) for k in range(n)]
    meals[3] = np.inf
    many = probes_ahead_many(nose, fwd, vel, cruise, meals)
    for i in range(n):
        me = Me(com[i], nose[i], fwd[i], vel[i], float(cruise[i]), 0.43)
        assert np.array_equal(many[i], probes_ahead(me, probe_reach(me, meals[i])))


def test_every_fishs_way_to_its_target_at_once_is_each_fishs_own():
    from zoetic.behavior.aquarium.routines import Around, Me, go_to
    from zoetic.behavior.aquarium.steering import go_to_many

    rng = np.random.default_rng(7)
    n = 80
    nose, com, fwd, vel = _crowd(rng, n, 6.0)
    cruise, top = rng.uniform(0.1, 0.3, n), rng.uniform(0.35, 0.6, n)
    target = rng.uniform(-6, 6, (n, 3))
    target[:10] = nose[:10] + 0.3 * rng.normal(size=(10, 3))  # near: some brake
    moving = rng.random(n) < 0.5
    velocity = np.where(moving[:, None], rng.normal(0, 0.3, (n, 3)), np.nan)
    lead = np.where(moving & (rng.random(n) < 0.5), 0.5, 0.0)
    beside = np.where(moving & (lead == 0.0), 0.6, 0.0)
    speed, turn = go_to_many(nose, com, fwd, cruise, top, target, velocity, lead, beside)
    assert (speed == 0.0).sum() >= 1 and (np.abs(turn) > 0.1).sum() > 20
    for i in range(n):
        me = Me(com[i], nose[i], fwd[i], vel[i], cruise[i], top[i])
        around = Around(target=target[i], target_velocity=velocity[i] if moving[i] else None)
        own = go_to(me, around, rng, float(lead[i]), float(beside[i]))
        assert (own.speed, own.turn) == (speed[i], turn[i])
