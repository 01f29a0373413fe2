"""Steering many fishes at once: the arithmetic of the behaviour routines over arrays.

``routines`` defines each routine for one fish on top of these (``go_to``, ``avoid``,
``keep_depth``); a tank's ``Shoal`` asks them for all the fishes that follow the routine in
one step. Each row's numbers are the one fish's: the same operations, elementwise.
"""

from __future__ import annotations

import math

import numpy as np

DEPTH_GAIN = 1.0  # rad of climb per m of depth error (capped at MAX_CLIMB)
MAX_CLIMB = 0.4  # rad: the steepest climb or dive asked for
PITCH_GAIN = 2.0  # rad of fin pitch per rad of climb-angle error
# s of travel: an avoiding fish whose nose is nearer than this to an obstacle turns as hard as
# its motor can (a half turn asked at once), not at its steady steering rate
URGENT = 1.5
# s of travel: an avoiding fish whose nose is nearer than this to another fish that threatens
# it (no obstacle ahead) brakes: the half turn with no forward speed asked (``avoid``); the
# half turn's bursts are what stop a fish, so braking early leaves neighbours room
# (docs/aquarium.md, "Braking from 2 s of travel")
URGENT_FISH = 2.0
# a still target nearer than NEAR m and farther off the heading than BRAKE_BEARING rad is
# turned to about on the spot (``go_to``): the steer's circle is wider than its distance
NEAR = 2.0
BRAKE_BEARING = math.pi / 3


def keep_depths(height: np.ndarray, climb_now: np.ndarray, wanted: np.ndarray) -> np.ndarray:
    """Return (n,) the fin pitches (rad) that bring n fishes at ``height`` (n,) m, their
    headings' vertical components ``climb_now`` (n,), to the heights ``wanted`` (n,) m: a
    climb angle proportional to the depth error (at most ``MAX_CLIMB``), the fins pitched by
    the difference between it and the body's climb angle."""
    climb = np.minimum(np.maximum(DEPTH_GAIN * (wanted - height), -MAX_CLIMB), MAX_CLIMB)
    now = np.arcsin(np.minimum(np.maximum(climb_now, -1.0), 1.0))
    return PITCH_GAIN * (climb - now)


def avoid_many(forward, velocity, cruise, top, away, obstacle, fish_only):
    """Return the speeds (m/s) and turns (rad) (n,) of n avoiding fishes: a turn to the side
    of the way out ``away`` (n, 3; a nan row: none, swim on at cruise) beating hard, a
    quarter turn asked in ``TURN_SECONDS``, or a half turn (as hard as the motor can turn)
    once the obstacle (``obstacle`` (n,) m away) is nearer than ``URGENT`` s of travel.
    Another fish alone (``fish_only``: no obstacle ahead) nearer than ``URGENT_FISH`` s of
    travel: the half turn with no forward speed asked, a brake (the learned sharp turn's
    bursts turn the fish about 10 degrees each and all but stop it; the swim asked between
    them at top speed carried it on into the other fish). forward, velocity (n, 3)."""
    f = units(flats(forward))
    left = away[:, 0] * -f[:, 2] + away[:, 1] * 0.0 + away[:, 2] * f[:, 0] >= 0.0
    speed = np.maximum(np.sqrt((velocity * velocity).sum(axis=1)), cruise)
    urgent = np.where(fish_only, URGENT_FISH, URGENT)
    calm = obstacle >= urgent * speed
    sign = np.where(left, 1.0, -1.0)
    turn = np.where(calm, sign * (np.pi / 2), sign * np.pi)
    # a fish close ahead: the sharp turn's bursts stop the fish, and between them it glides
    # instead of swimming on at top speed into the fish it avoids
    speed = np.where(calm | ~np.asarray(fish_only, bool), top, 0.0)
    none = np.isnan(away[:, 0])
    return np.where(none, cruise, speed), np.where(none, 0.0, turn)


def go_to_many(
    nose: np.ndarray,
    com: np.ndarray,
    forward: np.ndarray,
    cruise: np.ndarray,
    top: np.ndarray,
    target: np.ndarray,
    velocity: np.ndarray,
    lead: np.ndarray,
    beside: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Return the speeds (m/s) and turns (rad) (n,) of n fishes swimming to their targets
    (n, 3): ahead of a moving one (``velocity`` (n, 3), nan rows: a still target, food) by
    ``lead`` (n,) s, or to a point ``beside`` (n,) m to its side (0: none). nose, com,
    forward (n, 3); cruise, top (n,) m/s."""
    still = np.isnan(velocity[:, 0])
    aim = target + np.where(still[:, None], 0.0, lead[:, None] * velocity)
    off = flats(com - aim)
    aim = np.where((beside != 0)[:, None], aim + beside[:, None] * units(off), aim)
    to = flats(aim - nose)
    dist = np.sqrt((to * to).sum(axis=1))
    turn = bearings(forward, to)
    # a still target near and well off the heading: the half turn with no forward speed
    # asked (the brake of ``avoid``), which turns the fish about where it is; the steer
    # (a wide turn at the approach speed) circled such a particle 1.3-2 m away for good
    brake = still & (beside == 0) & (dist < NEAR) & (np.abs(turn) > BRAKE_BEARING)
    speed = np.where(dist > 2.0, top, np.maximum(cruise * 0.6, top * dist / 2.0))
    # always turn towards the target, even one inside the turning circle: swimming on to gain
    # room first costs a fish that turns 90 degrees in 7 s a 15 s detour (and its target
    # to the focuser, or to another fish), while the turn at the slower approach speed is
    # tighter and the target drifts (docs/aquarium.md, "Why the fishes foraged badly")
    turn = np.where(dist < 1e-9, 0.0, turn)  # ``steer``: no way to turn to
    return (
        np.where(brake, 0.0, speed),
        np.where(brake, np.where(turn > 0.0, np.pi, -np.pi), turn),
    )


def flats(v: np.ndarray) -> np.ndarray:
    """Vectors (..., 3) flattened to the horizontal plane (a copy, y = 0)."""
    v = np.array(v, float)
    v[..., 1] = 0.0
    return v


def units(v: np.ndarray) -> np.ndarray:
    """Vectors (..., 3) as unit vectors (zero where shorter than 1e-9 m)."""
    n = np.sqrt((v * v).sum(axis=-1))[..., None]
    return np.where(n > 1e-9, v / np.where(n > 1e-9, n, 1.0), 0.0)


def bearings(forward: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Return the horizontal angles (...,) (rad, left positive, in (-pi, pi]) from headings
    to directions (..., 3)."""
    a = np.arctan2(direction[..., 2], direction[..., 0])
    a = a - np.arctan2(forward[..., 2], forward[..., 0])
    return (a + np.pi) % (2 * np.pi) - np.pi
