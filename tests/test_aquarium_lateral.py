"""The lateral line (``lateral.flank_threats``): a fish with nothing ahead feels another whose
head is about to strike its flank and turns away from it, swimming on out of its way."""

from __future__ import annotations

import numpy as np

from zoetic.behavior.aquarium.lateral import FLANK_HORIZON, flank_threats

FELT = ~np.eye(2, dtype=bool)


def _pair(z: float, speed: float) -> tuple[np.ndarray, ...]:
    """Fish 0 still at the origin heading +x; fish 1, its centre ``z`` m to the side (+z:
    left), swimming straight at fish 0's flank at ``speed`` m/s. Bodies 1 m long."""
    fwd = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -np.sign(z)]])
    com = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, z]])
    return 0.5 * fwd + com, com, fwd, speed * np.array([[0.0, 0.0, 0.0], fwd[1]])


def test_a_fish_struck_in_the_flank_feels_the_striker_and_turns_away_from_it():
    for z, away in ((1.1, -1), (-1.1, 1)):  # from the left: turn right; from the right: left
        strike, side = flank_threats(*_pair(z, 0.4), FELT, np.array([-1, -1]))
        assert strike[0] == 1 and side[0] == away


def test_a_fish_too_far_or_too_slow_to_strike_within_the_horizon_is_not_felt():
    # the head 0.8 m from the centre line, closing at 0.4 m/s: 0.4 m off after 1 s
    strike, _ = flank_threats(*_pair(1.3, 0.4), FELT, np.array([-1, -1]))
    assert strike[0] == -1
    # faster, it is felt: within CONTACT (0.35 m) before the horizon
    strike, _ = flank_threats(*_pair(1.3, 0.5 / FLANK_HORIZON), FELT, np.array([-1, -1]))
    assert strike[0] == 1


def test_a_fish_with_a_threat_ahead_or_not_feeling_the_other_is_left_alone():
    pair = _pair(1.1, 0.4)
    strike, _ = flank_threats(*pair, FELT, np.array([1, -1]))  # its box already has one
    assert strike[0] == -1
    strike, _ = flank_threats(*pair, np.zeros((2, 2), bool), np.array([-1, -1]))
    assert strike[0] == -1


def _struck_from_the_side(monkeypatch, feeling: bool):
    """Two sated minnows (no food, no courting) for 4 s: fish 1 swims +x at half its cruise
    speed; fish 0 cruises +z at its flank from 0.9 m to its right. ``feeling`` False: no fish
    feels a strike into its flank (``flank_threats`` answers none)."""
    from dataclasses import replace

    from zoetic.behavior.aquarium import shoal
    from zoetic.behavior.aquarium import tank as tk
    from zoetic.behavior.aquarium.brain import tank_brains
    from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live
    from zoetic.behavior.mind import initial_mind
    from zoetic.physics.world import placed_pose

    def brains(*args):
        out = tank_brains(*args)
        for b in out:  # sated, no courting: the two only meet
            b.mind = initial_mind(0.0, b.species.mind.hunger_rate)
            b.constants = replace(b.constants, libido_rate=0.0)
        return out

    def numb(nose, *args):
        return np.full(len(nose), -1), np.zeros(len(nose), int)

    with monkeypatch.context() as m:
        m.setattr(tk, "tank_brains", brains)
        if not feeling:
            m.setattr(shoal, "flank_threats", numb)
        cfg = TankConfig(
            fishes=2, predators=0, food=0, obstacles=0, seconds=4.0, seed=0, half_size=8.0
        )
        tank = build_tank(cfg)
        body, world = tank.fishes[0].body, tank.world
        cruise = tank.fishes[0].species.motor.cruise_speed
        poses = [((0.2, 0.0, -0.9), np.pi / 2), ((0.0, 0.0, 0.0), 0.0)]
        speeds = (cruise, 0.5 * cruise)
        state = world.state
        world.restore(
            replace(
                state,
                positions=tuple(placed_pose(body, p, yaw)[None] for p, yaw in poses),
                velocities=tuple(
                    np.zeros_like(v) + s * np.array([np.cos(yaw), 0.0, np.sin(yaw)])
                    for v, s, (_, yaw) in zip(state.velocities, speeds, poses, strict=True)
                ),
            )
        )
        return live(tank)


def test_a_fish_approached_from_the_side_moves_out_of_the_way(monkeypatch):
    from zoetic.behavior.mind import INTENTIONS

    avoid = INTENTIONS.index("avoid")
    # numb, fish 1 never senses fish 0 (outside its box ahead) and keeps its line
    numb = _struck_from_the_side(monkeypatch, feeling=False)
    assert not (numb.intentions[:, 1] == avoid).any()
    assert abs(numb.positions[1].mean(axis=1)[-1, 2]) < 0.1
    # feeling it, fish 1 avoids at once and moves off its line away from fish 0 (+z)
    life = _struck_from_the_side(monkeypatch, feeling=True)
    assert life.intentions[0, 1] == avoid
    assert life.positions[1].mean(axis=1)[-1, 2] > 0.25
    assert not [e for e in life.events if e[2] == "collision"]
