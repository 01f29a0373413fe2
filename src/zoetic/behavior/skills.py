"""Each basic skill learned with default settings, beside the animal's hand-made entry.

``zoetic bench skills`` runs this: for every animal and every entry of its basic training
(go straight, sharp and wide left turns), learn the entry's task with the defaults of
``zoetic learn`` and score the learned controller and the hand-made one (the animal's wave,
bent for turns: ``tracking.handmade_repertoire``) on the same task, from rest, with the same
figures: the task's E, speed in body lengths per second, the heading change, the time to
turn 90 degrees, and for going straight the speed sustained when played for 10 s.
"""

from __future__ import annotations

import time

import numpy as np

from zoetic.behavior.tracking import body_length, handmade_repertoire
from zoetic.behavior.training import plan_for
from zoetic.bodies import Body, list_animals, load_animal
from zoetic.control import Controller
from zoetic.learn.objective import heading_angles, motion_terms
from zoetic.physics import simulate
from zoetic.tasks import Task

SUSTAINED_SECONDS = 10.0


def skill_figures(body: Body, ctrl: Controller, task: Task) -> dict:
    """Return the figures of one controller on one task, played from rest."""
    steps = int(round(task.horizon / body.dt))
    every = max(1, int(round(0.05 / body.dt)))
    tr = simulate(body, ctrl.table(steps, body.dt), record_every=every)
    terms = motion_terms(task, body, tr.positions, task.horizon)
    e = float(sum(t.weight * terms[t.kind][0] for t in task.terms))
    heading = heading_angles(body, tr.positions)[0]
    turned = heading - heading[0]
    past = np.flatnonzero(np.abs(turned) >= np.pi / 2)
    com = tr.com(body)[0]
    step = np.linalg.norm(np.diff(com[:, [0, 2]], axis=0), axis=1)
    out = {
        "E": round(e, 4),
        "speed_bl_s": round(float(step.sum() / task.horizon / body_length(body)), 3),
        "heading_deg": round(float(np.degrees(turned[-1])), 1),
        "t90_s": None if past.size == 0 else round(float(tr.times[past[0]]), 2),
    }
    if not any(t.kind == "heading_change" for t in task.terms):
        out["sustained_bl_s"] = sustained_speed(body, ctrl)
    return out


def sustained_speed(body: Body, ctrl: Controller, seconds: float = SUSTAINED_SECONDS) -> float:
    """Return the speed (body lengths/s) over the second half of ``seconds`` played from rest."""
    steps = int(round(seconds / body.dt))
    tr = simulate(body, ctrl.table(steps, body.dt), record_every=max(1, steps // 20))
    com = tr.com(body)[0]
    half = com.shape[0] // 2
    dist = np.linalg.norm((com[-1] - com[half])[[0, 2]])
    return round(float(dist / (tr.times[-1] - tr.times[half]) / body_length(body)), 3)


def learn_skill(animal: str, task: Task, seed: int = 0, budget: int | None = None):
    """Return (controller, wall seconds) learned with the defaults of ``zoetic learn``."""
    from zoetic.learn.run import LearnConfig, build

    config = LearnConfig(animal=animal, task=task.name, seed=seed)
    if budget:
        config.budget = budget
    setup = build(config, task)
    opt, obj = setup.optimizer, setup.objective
    obj.evaluate(opt.x0[None])  # compile and warm the kernel outside the clock
    t0 = time.perf_counter()
    while opt.evaluations < config.budget and not opt.done():
        X = opt.ask()
        if len(X) == 0:
            break
        opt.tell(X, obj(X))
    wall = time.perf_counter() - t0
    close = getattr(opt, "close", None)
    if close:
        close()
    return obj.controller(opt.best_x), wall


def bench_skills(animals=None, budget: int | None = None, seed: int = 0) -> dict:
    """Return, per animal and skill, the learned and hand-made figures and the wall time."""
    out: dict = {}
    for name in animals or list_animals():
        body = load_animal(name)
        hand = handmade_repertoire(body)
        skills = {}
        for entry in plan_for(body):
            ctrl, wall = learn_skill(name, entry.task, seed, budget)
            learned = skill_figures(body, ctrl, entry.task)
            made = skill_figures(body, hand.controllers[entry.name], entry.task)
            skills[entry.name] = {
                "task": entry.task.name,
                "learned": learned,
                "hand_made": made,
                "learned_beats_hand_made": learned["E"] <= made["E"],
                "learn_wall_s": round(wall, 2),
            }
        out[name] = skills
    return out
