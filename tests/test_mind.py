"""The artificial fish's mind: mental-state formulas, the intention priorities, the focuser."""

from __future__ import annotations

import math

import pytest

from zoetic.behavior.aquarium.species import Habits, MindConstants
from zoetic.behavior.mind import (
    REFLEX_HOLD,
    MindState,
    Situation,
    ate,
    drives,
    fear,
    focus,
    hunger,
    initial_mind,
    intend,
    libido,
    persist,
    ramp,
    think,
)

C = MindConstants()
SCHOOLING = Habits(schooling=True, dislikes=("crowd",))
LONER = Habits(schooling=False)


def test_hunger_libido_fear_against_hand_computed_values():
    # H = 1 - n_e (1 - p0 dt) / alpha: one particle 20 s ago at p0 = 0.01 -> 1 - 0.8 = 0.2
    assert hunger(1.0, 20.0, 0.01) == pytest.approx(0.2)
    assert hunger(2.0, 20.0, 0.01, alpha=2.0) == pytest.approx(0.2)
    assert hunger(0.0, 5.0, 0.01) == 1.0  # nothing eaten: starving
    assert hunger(3.0, 0.0, 0.01) == 0.0  # clipped at 0
    # L = p1 dt (1 - H): 0.05 * 10 * (1 - 0.2) = 0.4, capped at 1
    assert libido(10.0, 0.05, 0.2) == pytest.approx(0.4)
    assert libido(100.0, 0.05, 0.0) == 1.0
    # F = min(sum min(D0/d, 1), 1): D0 = 2 at 8 m and 10 m -> 0.25 + 0.2
    assert fear([8.0, 10.0], 2.0) == pytest.approx(0.45)
    assert fear([1.0], 2.0) == 1.0
    assert fear([], 2.0) == 0.0


def test_ramp_is_zero_below_q1_one_above_q2_and_the_formula_between():
    assert ramp(0.01, 0.05, 0.2) == 0.0
    assert ramp(0.3, 0.05, 0.2) == 1.0
    s = 0.1
    assert ramp(s, 0.05, 0.2) == pytest.approx((s - 0.05) / (0.4 - 0.05 - s))
    assert ramp(0.2 - 1e-9, 0.05, 0.2) == pytest.approx(1.0)


def test_initial_mind_has_the_asked_hunger_and_a_meal_resets_it():
    m = initial_mind(0.3, C.hunger_rate)
    d = drives(m, 0.0, C)
    assert d.hunger == pytest.approx(0.3)
    assert drives(m, 10.0, C).hunger == pytest.approx(0.3 + 10 * C.hunger_rate)
    fed = ate(m, 10.0)
    assert drives(fed, 10.0, C).hunger == pytest.approx(0.0)


def test_collision_beats_everything():
    d = drives(MindState(eaten=0.0), 0.0, C, predator_distances=[0.5])
    assert d.fear == 1.0 and d.hunger == 1.0
    sit = Situation(collision=True, predator_distances=(0.5,), food_distance=0.1)
    assert intend(d, sit, C, SCHOOLING) == "avoid"


def test_fear_beats_hunger_and_schooling_depends_on_habit_and_panic():
    starving = MindState(eaten=0.0)
    mild = Situation(predator_distances=(3.0,), food_distance=0.5)  # F = 2/3
    d = drives(starving, 0.0, C, mild.predator_distances)
    assert C.fear_threshold < d.fear < C.panic_threshold
    assert intend(d, mild, C, SCHOOLING) == "school"
    assert intend(d, mild, C, LONER) == "escape"
    panic = Situation(predator_distances=(1.0,))
    assert intend(drives(starving, 0.0, C, (1.0,)), panic, C, SCHOOLING) == "escape"
    # a predator fears nothing: it hunts
    assert intend(d, mild, C, LONER, predator=True) == "hunt"


def test_hunger_or_libido_then_wander_or_leave():
    hungry = drives(MindState(eaten=1.0, meal_time=-40.0, mating_time=0.0), 0.0, C)
    assert hungry.hunger > C.desire_threshold
    assert intend(hungry, Situation(), C, LONER) == "eat"
    # libido above hunger: mate; a tie keeps the previous of the two
    sated = MindState(eaten=1.0, meal_time=0.0, mating_time=-100.0)
    assert intend(drives(sated, 0.0, C), Situation(), C, LONER) == "mate"
    from zoetic.behavior.mind import Drives

    tie = Drives(0.5, 0.5, 0.0)
    assert intend(tie, Situation(), C, LONER, previous="mate") == "mate"
    assert intend(tie, Situation(), C, LONER, previous="eat") == "eat"
    assert intend(tie, Situation(), C, LONER, previous="wander") == "eat"
    calm = Drives(0.1, 0.1, 0.0)
    assert intend(calm, Situation(), C, SCHOOLING) == "wander"
    assert intend(calm, Situation(crowded=True), C, SCHOOLING) == "leave"
    # a near food particle raises a mild hunger over the threshold through the ramp
    peckish = Drives(0.2, 0.0, 0.0)
    assert intend(peckish, Situation(), C, LONER) == "wander"
    assert intend(peckish, Situation(food_distance=0.04), C, LONER) == "eat"


def test_intentions_persist_unless_a_more_urgent_one_fires():
    assert persist("eat", 10.0, "wander", 10.5, 1.0) == "eat"
    assert persist("eat", 10.0, "wander", 11.0, 1.0) == "wander"
    assert persist("wander", 10.0, "escape", 10.1, 1.0) == "escape"
    assert persist("escape", 10.0, "avoid", 10.1, 1.0) == "avoid"
    # think: a fish that just chose to eat keeps eating for persistence s after a meal
    m = MindState(eaten=0.0, intention="eat", since=0.0)
    m = ate(m, 0.2)
    m2, _ = think(m, 0.5, C, LONER, Situation())
    assert m2.intention == "eat"
    m3, _ = think(m2, 1.5, C, LONER, Situation())
    assert m3.intention == "wander" and m3.since == 1.5


def test_avoiding_another_fish_ends_when_it_has_passed_a_rock_holds_on():
    hungry = MindState(eaten=0.0, intention="eat", since=0.0)
    by_fish = Situation(collision=True, fish_only=True, food_distance=2.0)
    by_rock = Situation(collision=True, food_distance=2.0)
    clear = Situation(food_distance=2.0)
    m, _ = think(hungry, 5.0, C, LONER, by_fish)
    assert m.intention == "avoid" and m.reflex
    m, _ = think(m, 5.1, C, LONER, clear)  # the fish has passed: held REFLEX_HOLD s
    assert m.intention == "avoid"
    m, _ = think(m, 5.0 + REFLEX_HOLD, C, LONER, clear)  # then back to eating
    assert m.intention == "eat" and m.since == 5.0 + REFLEX_HOLD
    m, _ = think(hungry, 5.0, C, LONER, by_rock)
    assert m.intention == "avoid" and not m.reflex
    m, _ = think(m, 5.1, C, LONER, clear)  # a rock: the avoidance holds persistence s
    assert m.intention == "avoid"
    m, _ = think(m, 6.0, C, LONER, clear)
    assert m.intention == "eat"
    # a fish, then a rock ahead in the same avoidance: no longer a reflex, it holds
    m, _ = think(hungry, 5.0, C, LONER, by_fish)
    m, _ = think(m, 5.1, C, LONER, by_rock)
    m, _ = think(m, 5.2, C, LONER, clear)
    assert m.intention == "avoid"


def test_focuser_picks_the_nearest_and_keeps_a_near_previous_target():
    inf = math.inf
    assert focus([3.0, 1.0, inf]) == 1
    assert focus([inf, inf]) is None
    assert focus([]) is None
    assert focus([1.1, 1.0], previous=0) == 0  # within 25 %: keep
    assert focus([2.0, 1.0], previous=0) == 1  # much farther: switch
    assert focus([inf, 1.0], previous=0) == 1  # no longer perceived: switch
