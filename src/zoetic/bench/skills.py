"""Each basic skill learned with default settings, beside the animal's hand-made entry.

``zoetic bench skills`` runs this: for every animal and every entry of its basic training
(go straight, sharp and wide left turns), learn the entry's task with the defaults of
``zoetic learn`` and score the learned controller and the hand-made one (the animal's wave,
bent for turns: ``handmade.handmade_repertoire``) on the same task, from each of the task's
starts (``learned``/``hand_made`` from the first, rest; ``learned_<name>``/``hand_made_<name>``
from each other start, e.g. ``learned_cruising``), with the same figures: the task's E, speed
in body lengths per second, the heading change, the time to turn 90 degrees and the turning
radius, and for going straight the speed sustained when played for 10 s from that start;
``learned_beats_hand_made`` holds when the learned E is at most the hand-made one from every
start; ``starts`` gives each start's speed (m/s); for an animal with fins, the go-straight
gait's depth change with the fins up and down, and in the sea its burst toward the surface
from 2 m depth (both from rest).
"""

from __future__ import annotations

import numpy as np

from zoetic.behavior.handmade import handmade_repertoire
from zoetic.behavior.tracking import body_length
from zoetic.behavior.training import plan_for
from zoetic.bodies import Body, list_animals, load_animal
from zoetic.control import Controller
from zoetic.learning.objective import heading_angles, motion_terms
from zoetic.physics import State, rest_state, simulate
from zoetic.tasks import Task, start_state

SUSTAINED_SECONDS = 10.0


def skill_figures(body: Body, ctrl: Controller, task: Task, start: int = 0) -> dict:
    """Return the figures of one controller on one task, played from one of its starts (the
    first by default)."""
    steps = int(round(task.horizon / body.dt))
    every = max(1, int(round(0.05 / body.dt)))
    state = start_state(task, body, index=start)
    tr = simulate(body, ctrl.table(steps, body.dt), state=state, record_every=every)
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
    if any(t.kind == "heading_change" for t in task.terms):
        end = int(past[0]) if past.size else len(turned) - 1
        out["turn_radius_bl"] = turn_radius(com[: end + 1], turned[end], body_length(body))
    else:
        out["sustained_bl_s"] = sustained_speed(body, ctrl, state=state)
    return out


def turn_radius(com: np.ndarray, turned: float, length: float) -> float | None:
    """Return the radius (body lengths) of the circular arc that turns the heading by
    ``turned`` radians between the first and last centre-of-mass positions ``com`` (R, 3), as
    the turn promises judge it (``promises.arc_radius``); None under a degree of turn."""
    from zoetic.behavior.promises import arc_radius

    r = arc_radius(com, turned)
    return None if not np.isfinite(r) else round(r / length, 3)


def sustained_speed(
    body: Body, ctrl: Controller, seconds: float = SUSTAINED_SECONDS, state: State | None = None
) -> float:
    """Return the speed (body lengths/s) over the second half of ``seconds`` played from
    ``state`` (default: rest)."""
    steps = int(round(seconds / body.dt))
    tr = simulate(body, ctrl.table(steps, body.dt), state=state, record_every=max(1, steps // 20))
    com = tr.com(body)[0]
    half = com.shape[0] // 2
    dist = np.linalg.norm((com[-1] - com[half])[[0, 2]])
    return round(float(dist / (tr.times[-1] - tr.times[half]) / body_length(body)), 3)


def fin_columns(body: Body) -> np.ndarray:
    """Return the indices of the body's fin actuators."""
    return np.array([k for k, kind in enumerate(body.actuator_kind) if kind == "fin"], dtype=int)


def depth_change(body: Body, ctrl: Controller, seconds: float = 3.0) -> dict | None:
    """Return how far the gait ``ctrl`` rises and sinks with both fins fully up or down.

    Played from rest for ``seconds``; figures in body lengths (BL) and the time to change
    depth by one body length. None for a body without fins.
    """
    fins = fin_columns(body)
    if fins.size == 0:
        return None
    steps = int(round(seconds / body.dt))
    base = ctrl.table(steps, body.dt)
    tables = np.stack([base, base])
    tables[0][:, fins] = 1.0  # nose up
    tables[1][:, fins] = 0.0  # nose down
    every = max(1, int(round(0.05 / body.dt)))
    tr = simulate(body, tables, record_every=every)
    dy = (tr.com(body)[:, :, 1] - tr.com(body)[:, :1, 1]) / body_length(body)
    out = {}
    for k, (name, sign) in enumerate((("up", 1.0), ("down", -1.0))):
        past = np.flatnonzero(sign * dy[k] >= 1.0)
        out[f"{name}_bl"] = round(float(dy[k, -1]), 3)
        out[f"t_1bl_{name}_s"] = None if past.size == 0 else round(float(tr.times[past[0]]), 2)
    return out


def burst(body: Body, ctrl: Controller, depth: float = 2.0, seconds: float = 4.0) -> dict | None:
    """Return the top speed (m/s) of ``ctrl`` with the fins up, from rest ``depth`` m deep.

    For an animal of the sea (a free surface): also the centre of mass's speed when its head
    first reaches the surface. None for other media or a body without fins.
    """
    fins = fin_columns(body)
    if body.medium != "sea" or fins.size == 0:
        return None
    steps = int(round(seconds / body.dt))
    table = ctrl.table(steps, body.dt)
    table[:, fins] = 1.0
    start = rest_state(body, 1, offset=(0.0, -depth, 0.0))
    tr = simulate(body, table, state=start, record_every=1)
    com = tr.com(body)[0]
    v = np.linalg.norm(np.diff(com, axis=0), axis=1) / body.dt
    head_y = tr.positions[0, 1:, body.head, 1]
    up = np.flatnonzero(head_y >= 0.0)
    return {
        "top_speed_m_s": round(float(v.max()), 2),
        "speed_at_surface_m_s": None if up.size == 0 else round(float(v[up[0]]), 2),
        "t_surface_s": None if up.size == 0 else round(float(tr.times[up[0] + 1]), 2),
    }


def start_speeds(body: Body, task: Task) -> dict:
    """Return each start's name and speed (m/s), as the rollouts start."""
    out = {}
    for k, name in enumerate(task.start_names()):
        v = start_state(task, body, index=k).velocities[0]
        out[name] = round(float(np.linalg.norm(v.mean(axis=0))), 3)
    return out


def learn_skill(animal: str, task: Task, seed: int = 0, budget: int | None = None):
    """Return (controller, wall seconds) learned with the defaults of ``zoetic learn``."""
    from zoetic.bench.learn import learn_until
    from zoetic.learning.run import LearnConfig

    config = LearnConfig(animal=animal, task=task.name, seed=seed)
    if budget:
        config.budget = budget
    setup, figures = learn_until(config, task=task)
    return setup.objective.controller(setup.optimizer.best_x), figures["seconds"]


# the hand-made entry an entry of another training plan is compared with; any other entry
# without a hand-made namesake (the dolphin's turn-down, turn-up) is compared with the
# animal's own wave (go-straight) on the same task
HAND_MADE_FOR = {"move-forward": "go-straight", "turn-left": "sharp-turn-left"}


def bench_skills(animals=None, budget: int | None = None, seed: int = 0) -> dict:
    """Return, per animal and skill, the learned and hand-made figures and the wall time."""
    out: dict = {}
    for name in animals or list_animals():
        body = load_animal(name)
        hand = handmade_repertoire(body)
        skills = {}
        for entry in plan_for(body):
            ctrl, wall = learn_skill(name, entry.task, seed, budget)
            hand_name = (
                entry.name
                if entry.name in hand.controllers
                else HAND_MADE_FOR.get(entry.name, "go-straight")
            )
            made = hand.controllers[hand_name]
            names = entry.task.start_names()
            skill: dict = {"task": entry.task.name, "starts": start_speeds(body, entry.task)}
            beats = []
            for k, start in enumerate(names):
                tag = "" if k == 0 else f"_{start}"
                skill[f"learned{tag}"] = skill_figures(body, ctrl, entry.task, k)
                skill[f"hand_made{tag}"] = skill_figures(body, made, entry.task, k)
                beats.append(skill[f"learned{tag}"]["E"] <= skill[f"hand_made{tag}"]["E"])
            # on the task's E from every start
            skills[entry.name] = skill | {
                "hand_made_entry": hand_name,
                "learned_beats_hand_made": all(beats),
                "learn_wall_s": round(wall, 2),
            }
            if hand_name == "go-straight" and entry.name in ("go-straight", "move-forward"):
                # the gait with the fins: depth change, burst
                for key, fn in (("depth_change", depth_change), ("burst", burst)):
                    got = fn(body, ctrl)
                    if got is not None:
                        skills[entry.name][key] = {
                            "learned": got,
                            "hand_made": fn(body, hand.controllers[hand_name]),
                        }
        out[name] = skills
    return out
