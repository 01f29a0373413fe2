"""Dynamic plants (physics.plants): seaweed strands that stand up, sway and part around fishes."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.bodies import load_animal
from zoetic.errors import SimulationError
from zoetic.physics.bodycontact import skin_distances
from zoetic.physics.media import get_medium
from zoetic.physics.plants import Plants, Skins, Weed

DT = 0.005  # s: the tank's world step
WATER = get_medium("water")


def _strand(dt: float = DT, surge=(0.0, 0.0, 0.0), current=(0.0, 0.0, 0.0), n: int = 1):
    """n strands 2.5 m tall anchored on a seabed at y = -2, 1 m apart along z."""
    anchors = np.array([[0.0, -2.0, float(k)] for k in range(n)])
    return Plants(anchors, np.full(n, 2.5), Weed(), WATER, current, dt, surge, 7.0)


def _bend(p: Plants, tip_offset: float = 0.8) -> None:
    """Lean the strand over: node j moves sideways (x) in proportion to its height."""
    p.pos[:, :, 0] += np.linspace(0.0, tip_offset, p.pos.shape[1])


def test_a_strand_in_still_water_stands_up_and_stays_still():
    p = _strand()
    start = p.nodes
    for _ in range(1000):  # 5 s
        p.step()
    # buoyancy only stretches it a little along its own line: it stays upright and at rest
    assert np.abs(p.pos[:, :, [0, 2]] - start[:, :, [0, 2]]).max() < 1e-9
    # segment j carries the net buoyancy of the M + 1 - j nodes above it: the tip rises by
    # lift * M (M + 1) / 2 / stretch
    m = p.weed.segments
    rise = float(p.lift[0, 0]) * m * (m + 1) / 2 / p.weed.stretch
    assert p.pos[0, -1, 1] - start[0, -1, 1] == pytest.approx(rise, rel=0.02)
    assert np.abs(p.vel).max() < 1e-3


def test_a_bent_strand_rises_back_under_buoyancy():
    p = _strand()
    _bend(p)
    tip0 = p.pos[0, -1].copy()
    for _ in range(4000):  # 20 s: drag makes the rise slow, as for real kelp
        p.step()
    assert abs(p.pos[0, -1, 0]) < 0.25 * abs(tip0[0])
    assert p.pos[0, -1, 1] > tip0[1]


def test_energy_never_grows_in_still_water_at_the_tanks_dt():
    p = _strand()
    _bend(p)
    energy = [p.energy()]
    for _ in range(3000):
        p.step()
        energy.append(p.energy())
    e = np.array(energy)
    # springs, dashpots and drag only take energy away; the step does not add any
    assert np.diff(e).max() <= 1e-9
    assert e[-1] < e[0] - 0.1


def test_the_strands_sway_boundedly_in_the_surging_current():
    p = _strand(surge=(0.12, 0.0, 0.05), current=(0.02, 0.0, 0.0))
    tips = []
    for _ in range(6000):  # 30 s, four surge periods
        p.step()
        tips.append(p.pos[0, -1].copy())
    tips = np.array(tips)
    sway = np.ptp(tips[:, 0])
    assert 0.1 < sway < 1.0  # visibly, and no more than the water could carry it
    # the second half sways as much as the first: nothing builds up or dies away
    half = len(tips) // 2
    assert np.ptp(tips[half:, 0]) == pytest.approx(np.ptp(tips[:half, 0]), rel=0.15)
    assert np.isfinite(p.pos).all() and p.energy() < 1.0


def test_halving_dt_changes_the_trajectory_little():
    tips = {}
    for dt in (DT, DT / 2):
        p = _strand(dt=dt, surge=(0.12, 0.0, 0.05), current=(0.02, 0.0, 0.0))
        _bend(p, 0.4)
        rows = []
        for _ in range(int(round(4.0 / dt))):
            p.step()
            rows.append(p.pos[0].copy())
        tips[dt] = np.array(rows)[:: int(round(0.1 / dt))]  # every 0.1 s
    moved = np.abs(tips[DT] - tips[DT][0]).max()
    diff = np.abs(tips[DT] - tips[DT / 2]).max()
    assert moved > 0.1
    assert diff < 0.01 and diff < 0.05 * moved


def _fish_through(offset: float, steps: int = 400):
    """Drive a shark's rest body 3 m along x at 1 m/s through a strand at x = 0, its centre
    ``offset`` m beside the strand (+z) at y = -0.5, beside a strand without a fish; return
    the strand's largest displacement (m) from the fishless one along x, y, z (signed, the
    largest magnitude), the deepest any of its nodes went inside the fish (m) and the strand."""
    body = load_animal("shark")
    rest = body.rest_pos - body.rest_pos.mean(0)
    skins = Skins.of([body], np.array([0, len(rest)]))
    p, alone = _strand(), _strand()
    moved, worst = np.zeros(3), 0.0
    dx = 3.0 / steps
    for k in range(steps):
        a = rest + [-1.5 + k * dx, -0.5, offset]
        p.advance(1, skins, a, a + [dx, 0.0, 0.0])
        alone.step()
        pts = np.ascontiguousarray(p.pos[0, 1:])
        dist = skin_distances(pts, np.zeros(len(pts), np.int64), a + [dx, 0, 0], skins.faces,
                              skins.face_off)[0]  # fmt: skip
        worst = max(worst, float(-dist.min()))
        d = (p.pos - alone.pos).reshape(-1, 3)
        d = d[np.abs(d).argmax(axis=0), [0, 1, 2]]
        moved = np.where(np.abs(d) > np.abs(moved), d, moved)
    return moved, worst, p


def test_a_fish_passing_through_a_strand_pushes_it_aside():
    moved, worst, p = _fish_through(0.05)
    # the strand parts: pushed out of the fish's way to the near side (-z), by at least the
    # 7 cm between it and the fish's flank, and a little along the fish's path
    assert moved[2] < -0.07
    assert moved[0] > 0.0
    assert worst == 0.0  # no node was left inside the fish
    assert np.isfinite(p.pos).all()


def test_a_fish_passing_a_metre_away_leaves_the_strand_alone():
    moved, _, _ = _fish_through(1.0)
    assert np.abs(moved).max() == 0.0


def test_strands_step_the_same_for_the_same_inputs():
    runs = []
    for _ in range(2):
        p = _strand(surge=(0.12, 0.0, 0.05), n=3)
        _bend(p)
        for _ in range(200):
            p.step()
        runs.append(p.nodes)
    assert np.array_equal(runs[0], runs[1])


def test_springs_too_stiff_for_the_step_are_refused():
    with pytest.raises(SimulationError, match="too stiff"):
        Plants(np.zeros((1, 3)), np.ones(1), Weed(stretch=1e5), WATER, (0, 0, 0), DT)
    with pytest.raises(SimulationError, match="positive"):
        Weed(width=0.0)
