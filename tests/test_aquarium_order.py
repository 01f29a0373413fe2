"""A tank's run depends on its config alone, not on what else ran before it in the process.

The process keeps what tanks share: compiled bodies, models and kernels, motor calibrations
and the learned gaits' signals of the latest control period. Any of them holding something
of one tank's run would change the next tank's fishes.
"""

from __future__ import annotations

import numpy as np

from zoetic.behavior.aquarium.tank import Life, TankConfig, build_tank, live

ARRAYS = ("times", "food", "eaten", "brain_times", "drives", "intentions", "alive", "targets")


def _same(a: Life, b: Life) -> None:
    for name in ARRAYS:
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    for i, (p, q) in enumerate(zip(a.positions, b.positions, strict=True)):
        assert np.array_equal(p, q), f"fish {i}'s positions"
    assert a.events == b.events
    assert (a.deepest, a.deepest_fish) == (b.deepest, b.deepest_fish)


def test_a_tank_lives_the_same_after_another_tank_with_other_settings():
    first = TankConfig(fishes=6, predators=1, seconds=4.0, seed=12)
    before = live(build_tank(first))
    # another crowd, another seed, the wave motor for every fish, the eyes for its predator,
    # a longer control period and no righting reflex: every cache the two share is exercised
    other = TankConfig(
        fishes=9,
        predators=2,
        seconds=2.0,
        seed=5,
        skills="built-in",
        perception="vision",
        control_period=0.2,
        righting=False,
    )
    live(build_tank(other))
    live(build_tank(TankConfig(fishes=4, predators=1, seconds=1.5, seed=7)))  # learned again
    after = live(build_tank(first))
    assert len(before.events) > 0  # the fishes did something worth comparing
    _same(before, after)
