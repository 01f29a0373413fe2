"""What a run record shows of each animal's motion, measured once for every kind of run:
forward speed, depth (or height), heading, pitch and roll at the recorded instants.

The quantities are the sensors' own (``control.sensors``: the forward and up axes carried by
the best linear fit of the rest pose), read from recorded node positions instead of a live
world; velocities come from central differences of the recorded positions. Animals that share
a Body (a school of one species) are measured in one batch.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from zoetic.bodies import Body
from zoetic.errors import ZoeticError
from zoetic.physics import Medium, get_medium
from zoetic.record import Record

from .sensors import SENSORS, Senses

FAR = 1e8  # m; a water level at least this far away is no surface
# the measured quantities and their units; "depth" where the medium has a water surface,
# "height" (of the centre of mass above y = 0) where it has none
UNITS = {
    "speed": "m/s",
    "depth": "m",
    "height": "m",
    "heading": "deg",
    "pitch": "deg",
    "roll": "deg",
}


def has_surface(medium: Medium) -> bool:
    """Return whether the medium has a water surface that depths are measured from."""
    return abs(medium.water_level) < FAR


def _velocities(positions: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Return node velocities (K, T, N, 3) m/s by central differences over ``times`` (T,) s;
    NaN where two instants coincide, zeros for a single instant."""
    if positions.shape[1] < 2:
        return np.zeros_like(positions)
    dt = np.gradient(np.asarray(times, float))
    with np.errstate(divide="ignore", invalid="ignore"):
        step = np.where(dt > 0, 1.0 / np.where(dt > 0, dt, 1.0), np.nan)
        return np.gradient(positions, axis=1) * step[None, :, None, None]


def motion_scalars(
    body: Body, positions: np.ndarray, times: np.ndarray, medium: Medium
) -> dict[str, np.ndarray]:
    """Return the motion of animals sharing ``body``, positions (K, T, N, 3) m at ``times``
    (T,) s, as arrays (K, T): speed (m/s along the forward axis), depth below the surface (m;
    ``height`` of the centre of mass where the medium has no surface), heading (deg, left
    turns positive, unwrapped over time), pitch (deg, nose up positive) and roll (deg, the
    back toward the animal's right positive)."""
    pos = np.asarray(positions, float)
    k, t, n = pos.shape[:3]
    flat = pos.reshape(k * t, n, 3)
    vel = _velocities(pos, times).reshape(k * t, n, 3)
    s = Senses(body, flat, vel, medium, 0.0, np.zeros((k * t, 0), bool))
    out = {"speed": SENSORS["forward_speed"](s)}
    if has_surface(medium):
        out["depth"] = SENSORS["depth"](s)
    else:
        out["height"] = s.com[:, 1]
    heading = SENSORS["heading"](s).reshape(k, t)
    for a in range(k):  # each animal's heading unwrapped over its finite (not blown-up) rows
        good = np.isfinite(heading[a])
        heading[a, good] = np.unwrap(heading[a, good])
    out["heading"] = np.degrees(heading).reshape(k * t)
    out["pitch"] = np.degrees(SENSORS["pitch"](s))
    out["roll"] = np.degrees(SENSORS["roll"](s))
    return {q: v.reshape(k, t) for q, v in out.items()}


def _at(values: np.ndarray, times: np.ndarray, when: np.ndarray) -> np.ndarray:
    """Return ``values`` (T,) at the instants ``times`` (T,) interpolated at ``when`` (P,)."""
    if len(values) == len(when) and np.array_equal(times, when):
        return values
    return np.interp(when, times, values)


def measure_record(rec: Record, bodies: Sequence[Body]) -> Record:
    """Return the record with each animal's motion scalars added (``motion_scalars``), the
    Body of ``rec.animals[i]`` being ``bodies[i]``.

    A record without control periods gets the recorded instants as its periods, so the
    quantities are per recorded instant; one with control periods (an aquarium's brains)
    gets them interpolated at its period times.
    """
    if len(bodies) != len(rec.animals):
        raise ZoeticError(f"{len(bodies)} bodies for the {len(rec.animals)} animals of a record")
    times = np.asarray(rec.times, float)
    periods = np.asarray(rec.period_times, float)
    if not len(periods) and not rec.scalars:
        periods = times
    medium = get_medium(rec.medium)
    scalars = {who: dict(q) for who, q in rec.scalars.items()}
    groups: dict[int, list[int]] = {}
    for i, body in enumerate(bodies):
        groups.setdefault(id(body), []).append(i)
    for members in groups.values():
        body = bodies[members[0]]
        pos = np.stack([np.asarray(rec.animals[i].positions, float) for i in members])
        measured = motion_scalars(body, pos, times, medium)
        for row, i in enumerate(members):
            mine = scalars.setdefault(rec.animals[i].name, {})
            for what, values in measured.items():
                mine[what] = _at(values[row], times, periods).astype(np.float32)
    units = {**rec.units, **{q: UNITS[q] for q in UNITS if any(q in s for s in scalars.values())}}
    return dataclasses.replace(rec, period_times=periods, scalars=scalars, units=units)


def muscle_work(body: Body, positions: np.ndarray, activations: np.ndarray) -> np.ndarray:
    """Return the work (J) the muscles spend, per candidate: positions (K, T, N, 3) m and the
    activations (K, T, A) in force at the same T instants.

    A muscle is a spring whose rest length r = relaxed + u (contracted - relaxed) follows its
    activation u; moving r by dr against the spring's tension k (l - r) does work -k (l - r) dr
    on the body. Expenditure counts it whether the muscle shortens against a pull or is
    lengthened by one (|work|, as a muscle spends energy either way), summed over muscles and
    instants (the tension at the midpoint of each interval). The measure of 'energy
    expenditure' in section 4.2 of Grzeszczuk & Terzopoulos 95.
    """
    pos = np.asarray(positions, float)
    u = np.clip(np.asarray(activations, float), 0.0, 1.0)
    act = np.asarray(body.spring_actuator)
    m = np.flatnonzero(act >= 0)
    if not len(m) or pos.shape[1] < 2:
        return np.zeros(pos.shape[0])
    a, b = np.asarray(body.spring_a)[m], np.asarray(body.spring_b)[m]
    length = np.linalg.norm(pos[:, :, a] - pos[:, :, b], axis=-1)  # (K, T, M)
    relaxed, contracted = np.asarray(body.relaxed)[m], np.asarray(body.contracted)[m]
    rest = relaxed + u[:, :, act[m]] * (contracted - relaxed)
    tension = np.asarray(body.stiffness)[m] * (length - rest)
    mid = 0.5 * (tension[:, 1:] + tension[:, :-1])
    return np.nansum(np.abs(mid * np.diff(rest, axis=1)), axis=(1, 2))


def locomotion(body: Body, positions: np.ndarray, times: np.ndarray) -> dict[str, object]:
    """Return what a locomotion run did to the animal's depth, attitude and heading: the
    centre of mass's height change end minus start and its lowest and highest (m, up
    positive, relative to the start), the worst roll and pitch (deg, either way) and the net
    turn (deg, left positive: the heading over the last half second less that over the first,
    so a stroke's head swing cancels) over ``positions`` (R, N, 3) recorded at ``times`` (R,) s."""
    pos = np.asarray(positions, float)
    times = np.asarray(times, float)
    m = motion_scalars(body, pos[None], times, get_medium(body.medium))
    y = np.einsum("rnk,n->rk", pos, body.mass / body.total_mass)
    y = y[:, 1] - y[0, 1]
    half = times <= times[0] + 0.5, times >= times[-1] - 0.5
    heading = [float(np.nanmean(m["heading"][0, h])) for h in half]
    return {
        "depth_change_m": round(float(y[-1]), 3),
        "depth_span_m": [round(float(y.min()), 3), round(float(y.max()), 3)],
        "worst_roll_deg": round(float(np.nanmax(np.abs(m["roll"]))), 1),
        "worst_pitch_deg": round(float(np.nanmax(np.abs(m["pitch"]))), 1),
        "turn_deg": round(heading[1] - heading[0], 1),
    }
