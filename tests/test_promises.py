"""The default basic training keeps the promises of its tasks (marked long, outside CI's two
tiers: each trains a whole repertoire at the default budget, a few minutes an animal on two
cores; run with ``./run.sh test -m long``)."""

from __future__ import annotations

import pytest

from zoetic.behavior.promises import unmet_text
from zoetic.behavior.training import judge_repertoire, train_repertoire
from zoetic.bodies import load_animal

# entries the default training does not yet make keep their promises, with the reason: the
# ray's flat disc pitches at most about 5 degrees/s with any flap of its four wing actuators
# (hand-made sweeps and learning: it rises or sinks 0.06-0.07 m in 3 s where swim-up and
# swim-down promise 0.5 m), and even pointing straight up from the first instant its fastest
# gait takes it 0.48 m in 3 s from rest; see docs/animals.md, "Strength of the ray", and
# experiments/ray_climb.py. Stronger muscles, a streamlined leading edge and fins on the rear of
# the wings (experiments/ray_variants.py) keep the promise from cruising but not from rest.
NOT_YET = {"ray": {"swim-up", "swim-down"}}


@pytest.mark.long
@pytest.mark.parametrize("animal", ["snake", "ray", "dolphin", "shark"])
def test_default_training_keeps_its_tasks_promises(tmp_path, animal):
    train_repertoire(animal, tmp_path)
    verdicts = judge_repertoire(tmp_path, load_animal(animal))
    assert verdicts  # every learned entry's task makes promises
    broken = [
        unmet_text(name, v)
        for name, v in verdicts.items()
        if not v["met"] and name not in NOT_YET.get(animal, set())
    ]
    assert not broken, broken


@pytest.mark.parametrize("name", ["swim-up", "swim-down"])
def test_a_climbs_E_costs_a_broken_roll_or_turn_promise_more_than_the_climb_gains(name):
    """At the edge of its roll or turn promise, a climb pays more in E than it gains by rising
    from the least its promise allows to its target: the E optimum does not climb by turning
    or rolling over (issue 27)."""
    import math

    from zoetic.tasks import load_task

    task = load_task(name)
    terms = {t.kind: t for t in task.terms}
    promise = {p.quantity: p for p in task.promises}
    height = terms["height_change"]
    least = min(abs(promise["climb_m"].low), abs(promise["climb_m"].high))
    gain = height.weight * (abs(height.target) - least) ** 2
    for kind, quantity in (("roll_excess", "roll_deg"), ("turn_excess", "turn_deg")):
        edge = math.radians(promise[quantity].high)
        assert terms[kind].target < edge  # costs begin inside the promise
        assert terms[kind].weight * (edge - terms[kind].target) ** 2 > gain, (kind, gain)
