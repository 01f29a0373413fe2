"""What a learned repertoire entry does and whether it keeps its task's promises.

A task's ``[promise]`` table (``tasks.PROMISES``) bounds quantities of the motion a learned
entry makes from each of the task's starts over its horizon: the turn, climb, speed, radius and
roll (``entry_motion``). ``judge_entry`` says which it keeps, from the worst start;
``zoetic repertoire train`` and ``show`` print the ones broken (``unmet_text``), and their
``--strict`` exits 1 (``check_promises``); the training learns an entry again when it breaks
one (``behavior.restarts``).
"""

from __future__ import annotations

import numpy as np

from zoetic.bodies import Body
from zoetic.control import Controller
from zoetic.errors import ZoeticError
from zoetic.tasks import Promise, Task, start_states


def arc_curvature(com: np.ndarray, turned: float) -> float:
    """Return the signed curvature (1/m, left turns positive) of the circular arc that turns
    the heading by ``turned`` rad between the first and last centre-of-mass positions ``com``
    (R, 3): a chord c of an arc of angle a has curvature 2 sin(a / 2) / c, the angle capped at
    180 degrees; 0 for no turn, inf for a turn on the spot."""
    a = min(abs(float(turned)), np.pi)
    chord = float(np.linalg.norm((com[-1] - com[0])[[0, 2]]))
    bend = 2.0 * float(np.sin(a / 2.0)) * float(np.sign(turned))
    return bend / chord if chord > 0.0 else float(np.copysign(np.inf, bend)) if bend else 0.0


def arc_radius(com: np.ndarray, turned: float) -> float:
    """Return the radius (m) of the circular arc that turns the heading by ``turned`` rad
    between the first and last centre-of-mass positions ``com`` (R, 3): 1 / |curvature|
    (``arc_curvature``); inf under a degree of turn (a straight line)."""
    if abs(float(turned)) < np.radians(1.0):
        return float("inf")
    return 1.0 / abs(arc_curvature(com, turned))


def entry_motion(body: Body, ctrl: Controller, task: Task) -> list[dict[str, float]]:
    """Return the ``tasks.PROMISES`` quantities of a controller played from each of the task's
    starts over its horizon (one simulation, a row per start), and the straight-line distance
    its centre of mass covers ("distance_m")."""
    from zoetic.behavior.tracking import body_length
    from zoetic.control.measure import motion_scalars
    from zoetic.physics import get_medium, simulate

    starts = start_states(task, body)
    k = len(task.starts)
    steps = int(round(task.horizon / body.dt))
    every = max(1, int(round(0.05 / body.dt)))
    table = np.repeat(ctrl.table(steps, body.dt)[None], k, axis=0)
    tr = simulate(body, table, state=starts, record_every=every)
    m = motion_scalars(body, tr.positions, tr.times, get_medium(body.medium))
    com = tr.com(body)
    length = body_length(body)
    rows = []
    for i in range(k):
        turned = float(m["heading"][i, -1] - m["heading"][i, 0])
        path = np.linalg.norm(np.diff(com[i], axis=0), axis=1).sum()
        half = len(com[i]) // 2
        late = np.linalg.norm((com[i, -1] - com[i, half])[[0, 2]])
        rows.append(
            {
                "turn_deg": turned,
                "climb_m": float(com[i, -1, 1] - com[i, 0, 1]),
                "distance_m": float(np.linalg.norm(com[i, -1] - com[i, 0])),
                "speed_bl_s": float(path / task.horizon / length),
                "steady_speed_bl_s": float(late / (tr.times[-1] - tr.times[half]) / length),
                "radius_bl": arc_radius(com[i], np.radians(turned)) / length,
                "roll_deg": float(np.nanmax(np.abs(m["roll"][i]))),
                "pitch_change_deg": float(m["pitch"][i, -1] - m["pitch"][i, 0]),
                "failed": bool(tr.failed[i]),
            }
        )
    return rows


def judge_entry(body: Body, ctrl: Controller, task: Task) -> dict[str, object]:
    """Return how a learned entry keeps its task's promises, from every start of the task.

    {"task", "met": bool, "promises": [{"promise": text, "worst": value, "start": name,
    "met": bool}]}: for each promise the value furthest outside (or nearest the edge of) its
    range over the starts; an entry that blows up meets nothing.
    """
    rows = entry_motion(body, ctrl, task)
    names = task.start_names()
    out = []
    for p in task.promises:
        values = [r[p.quantity] for r in rows]
        miss = [
            outside(p, v) if not r["failed"] else np.inf for v, r in zip(values, rows, strict=True)
        ]
        worst = int(np.argmax(miss))
        out.append(
            {
                "promise": p.text(),
                "worst": round(float(values[worst]), 3),
                "start": names[worst],
                "met": bool(miss[worst] <= 0.0),
            }
        )
    return {"task": task.name, "met": all(o["met"] for o in out), "promises": out}


def outside(p: Promise, value: float) -> float:
    """Return how far ``value`` lies outside the promise's range (negative: inside)."""
    inside = p.low <= value <= p.high
    if not np.isfinite(value):  # an infinite radius (no turn) or a NaN
        return -1e9 if inside else 1e9
    if inside:
        return -float(min(value - p.low, p.high - value))
    return float(max(p.low - value, value - p.high))


class PromiseError(ZoeticError):
    """Entries of a repertoire do not do what their tasks promise (``--strict``)."""

    exit_code = 1


def check_promises(verdicts: dict[str, dict], where: str) -> None:
    """Raise PromiseError naming the learned entries of ``where`` that break a promise."""
    unmet = [n for n, v in verdicts.items() if not v["met"] and "mirror_of" not in v]
    if unmet:
        raise PromiseError(
            f"{where}: {len(unmet)} entr{'y' if len(unmet) == 1 else 'ies'} "
            f"({', '.join(unmet)}) do not do what their tasks promise (--strict)"
        )


def unmet_text(name: str, verdict: dict) -> str:
    """Return a line naming the promises an entry does not keep, with the worst value."""
    bad = [
        f"{o['promise']} but {o['worst']:g} (from {o['start']})"
        for o in verdict["promises"]
        if not o["met"]
    ]
    return f"entry {name!r} does not do what task {verdict['task']!r} promises: " + "; ".join(bad)
