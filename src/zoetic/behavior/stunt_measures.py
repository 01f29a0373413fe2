"""What one stunt achieved, in plain units: the numbers a judge reads (``measures``), from
the recorded flight (height, air time, turns in the air, style, splash), the ball (how far, by
which part, the tail's strike) and the hurdle's bars (clearance, over, touched)."""

from __future__ import annotations

import numpy as np

from zoetic.behavior.stunt_problem import StuntProblem, StuntRecord
from zoetic.behavior.tracking import body_length
from zoetic.physics.objects import Cylinder
from zoetic.tasks.terms import (
    PARTS,
    Signals,
    TermParams,
    ball_moved_by_nose,
    ball_moved_by_tail,
    final_height,
    flight_pitch_rotation,
    flight_roll_rotation,
    flight_rotation,
    tail_strike_rotation,
)


def measures(problem: StuntProblem, rec: StuntRecord, lane: int = 0) -> dict:
    """Return what one stunt achieved, in plain units (the numbers a judge reads)."""
    s = problem.signals(rec)
    out = _flight_measures(problem, rec, s, lane)
    if rec.balls.shape[2]:
        out |= _ball_measures(rec, s, lane)
    return out | _bar_measures(problem, rec, s, lane)


def _flight_measures(problem: StuntProblem, rec: StuntRecord, s: Signals, lane: int) -> dict:
    """Return the flight's measures of one stunt: height, air time, turns in the air, style
    and the splash."""
    dt = float(rec.traj.times[1] - rec.traj.times[0]) if len(rec.traj.times) > 1 else 0.0
    com_y = s.com[lane, :, 1]
    apex_at = int(s.apex_record[lane])
    rot = float(flight_rotation(np, s, None)[lane])
    length = body_length(problem.body)
    apex = float(com_y[apex_at] - problem.level)
    return {
        "apex_above_surface_m": round(apex, 3),
        "apex_body_lengths": round(apex / length, 3),
        "apex_time_s": round(float(rec.traj.times[apex_at]), 3),
        # the paper's finding: dive deep first, then thrust upward (depth of the centre of
        # mass at its lowest before the apex, m below the surface)
        "deepest_before_apex_m": round(float(problem.level - com_y[: apex_at + 1].min()), 3),
        "air_time_s": round(float(s.airborne[lane].sum() * dt), 3),
        "most_nodes_out_of_water": round(float(np.mean(1 - s.in_water[lane], axis=1).max()), 3),
        "rotation_in_air_deg": round(float(np.degrees(rot)), 1),
        "rotations_in_air": round(rot / (2 * np.pi), 3),
        # the somersault part of it: about the body's own left-right axis (a spin about the
        # vertical, or a body turned sideways to the start's plane, counts above, not here)
        "pitch_rotation_in_air_deg": round(
            float(np.degrees(flight_pitch_rotation(np, s, None)[lane])), 1
        ),
        # the spin: about the body's own long axis (a barrel roll in the air)
        "roll_rotation_in_air_deg": round(
            float(np.degrees(flight_roll_rotation(np, s, None)[lane])), 1
        ),
        "contacts": int(rec.contacts[lane].sum()),
        "body_length_m": round(length, 3),
        # the hurdle's style: the pitch of the body's axis (nose up +) at the apex, and where
        # the head re-enters the water after it (None while it has not by the end)
        "apex_pitch_deg": round(float(np.degrees(s.at(s.body_pitch, s.apex_record)[lane])), 1),
        "entry_pitch_deg": (
            round(float(np.degrees(s.at(s.body_pitch, s.reentry_record)[lane])), 1)
            if s.reentered[lane]
            else None
        ),
        "splash_m3_s": round(float(np.sum(s.entry_flux[lane])), 4),
        "entries_into_water": int(np.sum(np.diff(s.airborne[lane]) < 0)),
        # how far the highest node is still above the surface at the end (0: the body is back in)
        "final_height_m": round(float(final_height(np, s, None)[lane]), 3),
    }


def _ball_measures(rec: StuntRecord, s: Signals, lane: int) -> dict:
    """Return how one stunt moved the ball: how far, by which part, and the tail's strike."""
    b = rec.balls[lane, :, 0]
    parts = ball_parts(s, lane)
    # the tail's strike during a somersault: rotation in flight when it struck (0: never
    # while the whole body was out of the water) and how close the tail came
    turned = tail_strike_rotation(np, s, TermParams())[lane]
    return {
        "ball_rise_m": round(float(b[:, 1].max() - b[0, 1]), 3),
        "ball_moved_m": round(float(np.linalg.norm(b - b[0], axis=1).max()), 3),
        "ball_contact": "yes" if parts else "no",
        "ball_parts": parts,
        "ball_moved_by_nose_m": round(float(ball_moved_by_nose(np, s, None)[lane]), 3),
        "ball_moved_by_tail_m": round(float(ball_moved_by_tail(np, s, None)[lane]), 3),
        "tail_strike_rotation_deg": round(float(np.degrees(turned)), 1),
        "ball_tail_distance_m": round(float(s.part_ball_distance("tail")[lane].min()), 3),
    } | strike_speeds(rec, s.ball_touch[lane], lane)


def _bar_measures(problem: StuntProblem, rec: StuntRecord, s: Signals, lane: int) -> dict:
    """Return how one stunt passed the trick's horizontal bars ({} without one): clearance,
    whether it crossed over them, whether it touched them."""
    bars = [
        (i, o)
        for i, o in enumerate(problem.trick.objects)
        if isinstance(o, Cylinder) and o.axis != "y"
    ]
    if not bars:
        return {}
    pos = rec.traj.positions[lane]
    out: dict = {
        "hurdle_clearance_m": round(
            min(float(np.nanmin(cylinder_distance(o, pos))) for _, o in bars), 3
        )
    }
    # over the bar: the whole body passed from before it to beyond it, and where the
    # centre of mass passed it, the body's lowest node was above the bar's top
    crossed = []
    for _, o in bars:
        ax = 0 if o.axis == "z" else 2
        c = o.center[ax]
        i = int(np.nanargmin(np.abs(s.com[lane, :, ax] - c)))
        span = (np.nanmax(pos[:, :, ax].min(axis=1)) > c) & (pos[0, :, ax].max() < c)
        crossed.append(bool(span and np.nanmin(pos[i, :, 1]) > o.center[1] + o.radius))
    out["bar_crossed"] = all(crossed)
    if rec.touch is not None:
        out["hurdle_touched"] = bool(any(rec.touch[lane, :, :, i].sum() > 0 for i, _ in bars))
    return out


def strike_speeds(rec: StuntRecord, touch: np.ndarray, lane: int = 0) -> dict:
    """Return the fastest node that touched the first ball (at the records where it touched)
    and the ball's top speed from then on, m/s, from the recorded positions; {} if nothing
    touched it. touch: (R, N) the nodes' contact with the ball since the previous record."""
    t = rec.traj.times
    hit = np.flatnonzero(touch.sum(axis=1) > 0)
    if hit.size == 0 or len(t) < 2:
        return {}
    dt = np.diff(t)[:, None]
    nodes = np.linalg.norm(np.diff(rec.traj.positions[lane], axis=0), axis=-1) / dt  # (R-1, N)
    ball = np.linalg.norm(np.diff(rec.balls[lane, :, 0], axis=0), axis=-1) / dt[:, 0]
    rows = hit[hit > 0]
    striker = max((float(nodes[r - 1][touch[r] > 0].max()) for r in rows), default=0.0)
    return {
        "striker_speed_m_s": round(striker, 2),
        "ball_speed_m_s": round(float(ball[max(int(hit[0]) - 1, 0) :].max()), 2),
    }


def ball_parts(s: Signals, lane: int = 0) -> list[str]:
    """Return the body parts that touched the first ball, in the order of their first touch."""
    first = {}
    for part in PARTS:
        hit = np.flatnonzero(s.part_touch(part)[lane] > 0)
        if hit.size:
            first[part] = int(hit[0])
    return sorted(first, key=lambda p: (first[p], PARTS.index(p)))


def cylinder_distance(c: Cylinder, points: np.ndarray) -> np.ndarray:
    """Return the distance (...,) from points (..., 3) to the surface of a fixed cylinder
    (negative inside): how far a body passed from a hurdle's bar."""
    ax = "xyz".index(c.axis)
    d = np.asarray(points, float) - np.asarray(c.center, float)
    along = np.abs(d[..., ax]) - 0.5 * c.length
    radial = np.sqrt(np.sum(np.delete(d, ax, axis=-1) ** 2, axis=-1)) - c.radius
    out = np.hypot(np.maximum(radial, 0.0), np.maximum(along, 0.0))
    return np.where((radial < 0) & (along < 0), np.maximum(radial, along), out)
