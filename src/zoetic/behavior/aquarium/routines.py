"""Behaviour routines: an intention and its focused target in, a motor demand out.

avoid (static obstacles and other fishes: ``collision_ahead``, ``fish_threats``), eat, mate,
leave, wander, escape, school and the predator's hunt. Each is a small pure function of the
fish's own kinematics (``Me``) and what it perceives (``Around``); the tank turns the demand
into muscle activations (``locomotion``: the calibrated swim / turn / pitch motor
controllers). Directions are steered in the horizontal plane; ``keep_depth`` pitches the fins
to hold a fish at its target's depth (or its layer), since a turning lattice fish drifts up
or down.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from zoetic.behavior.aquarium import steering
from zoetic.behavior.aquarium.locomotion import Demand
from zoetic.behavior.aquarium.perception import obstacle_distance
from zoetic.behavior.aquarium.steering import (
    avoid_many,
    bearings,
    flats,
    go_to_many,
    keep_depths,
    units,
)

# the routines' constants, defined with their arithmetic over arrays (``steering``)
NEAR, BRAKE_BEARING = steering.NEAR, steering.BRAKE_BEARING
URGENT, URGENT_FISH = steering.URGENT, steering.URGENT_FISH
DEPTH_GAIN, MAX_CLIMB, PITCH_GAIN = steering.DEPTH_GAIN, steering.MAX_CLIMB, steering.PITCH_GAIN
LOOKAHEAD = 10.0  # s of travel (at least 3 m) probed ahead for an imminent collision
PROBES = 8  # points probed along the heading
_STEPS = np.arange(PROBES, dtype=float)
CLEARANCE = 0.5  # m: a probe nearer than this to an obstacle means a collision is imminent
TURN_RADIUS = 1.9  # m: default radius of a fish's sharpest turn (the brain gives its own)
CENTRE_LINE = 5  # points along another fish's centre line, nose to tail, tested for a threat
THREAT_TIMES = 4  # instants from now to the anticipation horizon at which they are tested
ROOM_STEP = 0.4  # m between the probes of the room to either side (walls are 0.5 m thick)
_SIN60 = math.sqrt(3) / 2
# m between two fishes' centre lines under which they touch (bodies are 0.24 m wide and bend)
CONTACT = 0.35
CONTACT_TIMES = 9  # instants from now to the anticipation horizon tested for a contact
CONTACT_HORIZON = 2.0  # s: the longest a contact is anticipated (at most the anticipation)
# the front of a fish whose contact with another it anticipates: a fish brakes early for its
# own head running into another, not for another's head running into its flank (that one
# brakes; this one swims on out of its way)
HEAD = 0.3


@dataclass(frozen=True)
class Me:
    """A fish's own state: centre, nose, unit heading (3,), velocity (3,) and its speeds."""

    com: np.ndarray
    nose: np.ndarray
    forward: np.ndarray
    velocity: np.ndarray
    cruise: float
    top: float
    radius: float = TURN_RADIUS  # m: the sharpest turn's radius
    layer: float = 0.0  # m: the height the fish keeps when it has no target


@dataclass(frozen=True)
class Around:
    """What a fish perceives for its routines: perceived fishes (centres, headings, same
    species?), predators' and prey's centres, the focused target and the way away from a
    threatening obstacle."""

    fish: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    fish_forward: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    same: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    predators: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    target: np.ndarray | None = None
    target_velocity: np.ndarray | None = None
    away: np.ndarray | None = None  # unit horizontal direction away from the threat
    # m from the nose to the nearest perceived obstacle surface or threatening fish
    obstacle: float = math.inf
    fish_only: bool = False  # the threat is another fish alone (no obstacle ahead)


def steer(me: Me, direction: np.ndarray, speed: float) -> Demand:
    """Return the demand to swim along ``direction`` at ``speed`` (the turn motor controller
    beats harder by itself when the turn needs it)."""
    d = flats(direction)
    if math.sqrt(d @ d) < 1e-9:
        return Demand(speed, 0.0)
    return Demand(speed, float(bearings(me.forward, d)))


def keep_depth(me: Me, demand: Demand, height: float | None = None) -> Demand:
    """Return the demand with the fins pitched to bring the fish to ``height`` m (default its
    layer): ``keep_depths`` for one fish."""
    y = me.layer if height is None else float(height)
    pitch = keep_depths(np.array([me.com[1]]), np.array([me.forward[1]]), np.array([y]))
    return Demand(demand.speed, demand.turn, float(pitch[0]))


def probe_reach(me: Me, target: float | None = None) -> float:
    """Return how far ahead (m) a fish probes for obstacles: LOOKAHEAD s of travel (at least
    3 m), or only as far as a food particle it is about to eat (``target`` m away: obstacles
    beyond it are left for after the meal, since food lies near rocks)."""
    speed = max(math.sqrt(me.velocity @ me.velocity), me.cruise)
    reach = max(3.0, LOOKAHEAD * speed)
    if target is not None and math.isfinite(target):
        reach = min(reach, max(target, 0.5 * CLEARANCE))
    return reach


def probes_ahead(me: Me, reach: float) -> np.ndarray:
    """Return the PROBES points (PROBES, 3) along the heading from the nose up to ``reach`` m."""
    f = units(flats(me.forward))
    along = _STEPS * (reach / (PROBES - 1))  # np.linspace(0, reach, PROBES)'s own formula
    along[-1] = reach
    return me.nose + along[:, None] * f


def probes_ahead_many(
    nose: np.ndarray,
    forward: np.ndarray,
    velocity: np.ndarray,
    cruise: np.ndarray,
    targets: list[float | None],
) -> np.ndarray:
    """Return every fish's probes (n, PROBES, 3): ``probes_ahead`` up to ``probe_reach`` for
    n fishes at once (nose, forward, velocity (n, 3), cruise speeds (n,), each one's food
    target distance or None), elementwise as the one fish's formulas: the same numbers."""
    speed = np.maximum(np.sqrt((velocity * velocity).sum(axis=1)), cruise)
    reach = np.maximum(3.0, LOOKAHEAD * speed)
    meal = np.array([np.inf if t is None else t for t in targets], float)
    near = np.isfinite(meal)
    reach[near] = np.minimum(reach[near], np.maximum(meal[near], 0.5 * CLEARANCE))
    f = units(flats(forward))
    along = _STEPS[None, :] * (reach / (PROBES - 1))[:, None]
    along[:, -1] = reach
    return nose[:, None, :] + along[:, :, None] * f[:, None, :]


def side_room(me: Me, kind, center, size, reach: float) -> tuple[float, float]:
    """Return the room (m, the nearest obstacle surface) along rays 60 degrees to the left and
    to the right of the heading, probed every ``ROOM_STEP`` m or closer out to ``reach``
    (close enough that a 0.5 m thick wall is never stepped over): ``side_rooms`` of one fish."""
    left, right = side_rooms(
        me.nose[None], me.forward[None], np.array([reach]), kind, center, size
    )[0]
    return float(left), float(right)


def side_rooms(
    nose: np.ndarray, forward: np.ndarray, reach: np.ndarray, kind, center, size
) -> np.ndarray:
    """Return (n, 2) the room (m) to the left and to the right of each of n fishes (nose,
    forward (n, 3)) out to its ``reach`` (n,) m: ``side_room`` for all at once, each ray's
    points as ``np.linspace`` spaces them (a shorter ray's last point repeated)."""
    f = units(flats(forward))
    fx, fz = f[:, 0:1], f[:, 2:3]
    reach = np.asarray(reach, float)
    k = np.maximum(2, np.ceil((reach - 0.3) / ROOM_STEP).astype(int) + 1)
    stop = np.maximum(reach, 0.3)[:, None]
    steps = np.arange(int(k.max()), dtype=float)[None, :]
    along = steps * ((stop - 0.3) / (k - 1)[:, None]) + 0.3  # np.linspace's own formula
    along = np.where(steps >= (k - 1)[:, None], stop, along)
    pts = np.empty((len(f), 2, along.shape[1], 3))
    pts[..., 1] = nose[:, 1, None, None]
    for j, sgn in enumerate((1.0, -1.0)):  # the ray (cos 60, sin 60) to the left, then right
        pts[:, j, :, 0] = nose[:, 0:1] + along * (0.5 * fx - sgn * _SIN60 * fz)
        pts[:, j, :, 2] = nose[:, 2:3] + along * (0.5 * fz + sgn * _SIN60 * fx)
    return obstacle_distance(pts, kind, center, size).min(axis=(2, 3))


def fish_threats(
    nose: np.ndarray,
    com: np.ndarray,
    forward: np.ndarray,
    velocity: np.ndarray,
    seen: np.ndarray,
    reach: np.ndarray,
    half_width: np.ndarray,
    anticipation: np.ndarray,
    prefer: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return for each of n fishes the fish that threatens a collision (index, -1: none), the
    side to turn to (+1 left, -1 right, 0: none) and how near (m) the threat is (inf: none):
    the distance from its nose to the threat's centre line now or, when less, how far it
    swims until that line comes within ``CONTACT`` of its head (``time_to_contact``, its
    front ``HEAD``, over at most ``CONTACT_HORIZON`` s), which its brake weighs (``avoid``).

    Tu's collision sensitivity region: a box ahead of each fish in the horizontal plane, from
    its nose to ``reach`` m ahead and ``half_width`` m to either side (n,).
    Another fish it perceives (``seen`` (n, n)) threatens when a point of that fish's centre
    line (nose to tail, ``CENTRE_LINE`` points) lies in the box now or will, moving as both
    fishes move now, within ``anticipation`` s (n,); the most dangerous is the one with the
    most points in the box over those instants (the nearest on a tie). The way out is away
    from where the threat's centre will be when nearest (``closest_lateral``; Tu's
    avoid-fish routine turns away from the obstacle's relative position); a threat nearly
    dead ahead (within a quarter of the half width) is turned away from on the side
    ``prefer`` (n,) gives (+1, -1; 0: none), the side
    an avoidance already turns to, so that the fish does not dither, else to the right (two
    fishes meeting head on both turn right and pass). nose, com, forward, velocity: (n, 3)."""
    n = len(nose)
    f = np.array(forward, float)
    f[:, 1] = 0.0
    f /= np.maximum(np.linalg.norm(f, axis=1, keepdims=True), 1e-9)
    left = np.stack([-f[:, 2], np.zeros(n), f[:, 0]], axis=1)
    u = np.linspace(0.0, 1.0, CENTRE_LINE)[:, None, None]  # nose (0) to tail (1)
    line = nose[None] + u * 2.0 * (com - nose)[None]  # (P, n, 3): the tail mirrors the nose
    ii, jj = np.nonzero(seen)  # only the pairs perceived: (n, n) pairs are many in a crowd
    ii, jj = _within_box_reach(ii, jj, nose, com, velocity, reach, half_width, anticipation)
    t = np.linspace(0.0, 1.0, THREAT_TIMES)[:, None, None] * anticipation[ii][None, :, None]
    rel_v = velocity[jj] - velocity[ii]  # (m, 3): j's velocity seen by i
    # (K, P, m, 3): j's centre line points relative to i's nose at each instant
    rel = line[None][:, :, jj] - nose[ii][None, None]
    rel = rel + t[:, None] * rel_v[None, None]
    ahead = np.einsum("kpmc,mc->kpm", rel, f[ii])
    aside = np.einsum("kpmc,mc->kpm", rel, left[ii])
    inside = (ahead > 0.0) & (ahead < reach[ii])
    inside &= np.abs(aside) < half_width[ii]
    count = inside.sum(axis=(0, 1))  # (m,)
    dist = np.linalg.norm(rel[0], axis=-1).min(axis=0)  # (m,) now, nose to centre line
    # each fish's threat: the most points in the box, the nearest on a tie (then the first)
    hit = np.flatnonzero(count > 0)
    order = hit[np.lexsort((jj[hit], dist[hit], -count[hit], ii[hit]))]
    best = order[np.r_[True, ii[order][1:] != ii[order][:-1]]] if len(order) else order
    j = np.full(n, -1)
    j[ii[best]] = jj[best]
    side = np.zeros(n, int)
    near = np.full(n, np.inf)
    if len(hit):
        # every threatening fish: the nearest contact brakes, and the threats' sides (each
        # weighed by its points in the box) give the way out, so that a fish between two
        # does not turn from one into the other and back (it dithered, swimming on)
        me, other = ii[hit], jj[hit]
        horizon = np.minimum(anticipation[me], CONTACT_HORIZON)
        contact = time_to_contact(
            nose[me], f[me], com[me], line[:, other], rel_v[hit], horizon, HEAD
        )
        speed = np.linalg.norm(velocity[me], axis=1)
        # how far it swims before they touch (a still fish: 0 m, it is in the way already)
        travel = np.where(np.isfinite(contact), speed * np.minimum(contact, 1e9), np.inf)
        np.minimum.at(near, me, np.minimum(dist[hit], travel))
        lateral = closest_lateral(com[other] - nose[me], rel_v[hit], left[me], anticipation[me])
        # +1 a threat nearest on the left, -1 on the right, 0 nearly dead ahead
        sign = np.where(np.abs(lateral) >= 0.25 * half_width[me], np.sign(lateral), 0.0)
        side = side_vote(j, me, count[hit], sign, prefer)
    return j, side, near


def _within_box_reach(
    ii: np.ndarray,
    jj: np.ndarray,
    nose: np.ndarray,
    com: np.ndarray,
    velocity: np.ndarray,
    reach: np.ndarray,
    half_width: np.ndarray,
    anticipation: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Return the pairs (fish ``ii[k]``, other fish ``jj[k]``) whose other's centre line can
    come into the fish's collision sensitivity box within its anticipation, in their order:
    a point of the box lies at most ``hypot(reach, half_width)`` m from the nose
    horizontally, a point of the centre line at most ``|nose - com|`` m from the other's
    centre, and the line moves at most ``anticipation`` times the relative speed (m). The
    pairs dropped have no point in the box at any instant (``fish_threats`` counts none for
    them), so the threats are those of all the pairs; in a crowd most pairs seen are metres
    apart (a fish sees 6 m, its box reaches 0.7 m)."""
    if not len(ii):
        return ii, jj
    gap = com[jj] - nose[ii]
    rel_v = velocity[jj] - velocity[ii]
    half = np.sqrt(((nose[jj] - com[jj]) ** 2).sum(axis=1))
    near = np.sqrt(gap[:, 0] ** 2 + gap[:, 2] ** 2) - half
    near -= anticipation[ii] * np.sqrt(rel_v[:, 0] ** 2 + rel_v[:, 2] ** 2)
    box = np.sqrt(reach[ii] ** 2 + half_width[ii] ** 2)
    keep = near <= box + 1e-6 * (1.0 + box)  # a margin over the roundings of these bounds
    return ii[keep], jj[keep]


def side_vote(
    j: np.ndarray,
    me: np.ndarray,
    weight: np.ndarray,
    sign: np.ndarray,
    prefer: np.ndarray | None,
) -> np.ndarray:
    """Return the side (n,) each of n fishes turns to from its threats (+1 left, -1 right, 0
    for a fish without one, ``j`` (n,) -1): a vote of its threatening fishes, threat k of
    fish ``me[k]`` on the side ``sign[k]`` (+1 left, -1 right, 0 nearly dead ahead) weighed
    by its points in the box ``weight[k]``. A fish turns away from the side that outweighs
    the other; holding a side already (``prefer`` (n,), 0: none), only from one that
    outweighs half the votes; else it keeps its side, or turns right."""
    n = len(j)
    pull = np.zeros(n)
    np.add.at(pull, me, weight * sign)
    total = np.zeros(n)
    np.add.at(total, me, weight)
    side = np.zeros(n, int)
    for i in np.flatnonzero(j >= 0).tolist():
        # away from the side where the threats will be nearest (``closest_lateral``), not
        # where they are now: turning away from a fish crossing ahead leads into its path
        kept = int(prefer[i]) if prefer is not None and prefer[i] else 0
        if abs(pull[i]) > (0.5 * total[i] if kept else 0.0):
            side[i] = -1 if pull[i] > 0.0 else 1
        else:  # nearly dead ahead, or threats on both sides: the side already taken, else
            # to the right (as ships do: two fishes meeting head on both turn right and pass)
            side[i] = kept or -1
    return side


def closest_lateral(
    rel: np.ndarray, rel_v: np.ndarray, left: np.ndarray, horizon: np.ndarray
) -> np.ndarray:
    """Return (m,) how far (m) to the left of each of m fishes another fish's centre will lie
    when it is nearest (in the horizontal plane, both swimming on as they swim now, within
    ``horizon`` (m,) s, now at the soonest): the side a fish turns away from. Turning away
    from that point widens the miss (the fish's change of velocity moves the other's
    nearest approach the opposite way); a fish crossing ahead from the right will be
    nearest on the left, so the fish turns right and passes behind it.

    rel (m, 3): the other's centre relative to the nose now; rel_v (m, 3): its velocity
    relative to the fish's; left (m, 3): the fishes' unit horizontal left."""
    r, v = flats(rel), flats(rel_v)
    vv = np.einsum("mc,mc->m", v, v)
    t = np.clip(-np.einsum("mc,mc->m", r, v) / np.maximum(vv, 1e-12), 0.0, horizon)
    return np.einsum("mc,mc->m", r + t[:, None] * v, left)


def time_to_contact(
    nose: np.ndarray,
    forward: np.ndarray,
    com: np.ndarray,
    line: np.ndarray,
    rel_v: np.ndarray,
    horizon: np.ndarray,
    part: float = 1.0,
) -> np.ndarray:
    """Return (m,) the time (s) until another fish's centre line comes within ``CONTACT`` m of
    each of m fishes' own centre line (its front ``part`` of it, from the nose: 1 the whole
    body), both swimming on as they swim now; inf when it does not within ``horizon`` (m,) s
    (tested at ``CONTACT_TIMES`` instants).

    nose, com (m, 3); forward (m, 3) unit horizontal headings; line (P, m, 3): the other
    fishes' centre line points now; rel_v (m, 3): their velocities relative to the fishes'."""
    t = np.linspace(0.0, 1.0, CONTACT_TIMES)[:, None] * horizon[None, :]  # (T, m)
    rel = line[None] - nose[None, None] + t[:, None, :, None] * rel_v[None, None]  # (T,P,m,3)
    ahead = np.einsum("tpmc,mc->tpm", rel, forward)
    length = np.einsum("mc,mc->m", nose - com, forward) * 2.0 * part  # m: from the nose
    behind = ahead - np.clip(ahead, -length[None, None], 0.0)  # along, off the own segment
    off2 = np.einsum("tpmc,tpmc->tpm", rel, rel) - ahead**2  # squared, across the heading
    close = (np.maximum(off2, 0.0) + behind**2).min(axis=1) < CONTACT**2  # (T, m)
    first = close.argmax(axis=0)
    return np.where(close.any(axis=0), t[first, np.arange(t.shape[1])], np.inf)


def collision_ahead(
    me: Me,
    kind,
    center,
    size,
    fish_side: int = 0,
    prefer: int = 0,
    target: float | None = None,
    ahead: np.ndarray | None = None,
    room: tuple[float, float] | None = None,
) -> tuple[bool, np.ndarray | None]:
    """Return (imminent?, the unit way out): probes along the heading (``probes_ahead`` up to
    ``probe_reach``) against the obstacles (clearance CLEARANCE m), then another fish that
    threatens (``fish_side``: the side ``fish_threats`` turns to, +1 left, -1 right, 0 none).
    prefer: +1 (left) or -1 (right) keeps the side an avoidance already turns to,
    unless obstacles close that side and the other side is open; a way out of another fish's
    path is also checked against the obstacles (it must not lead into a rock or a wall);
    target: the distance (m) to a food particle the fish is about to eat; ahead: the probes'
    obstacle distances (PROBES, S) and room: the ``side_room`` (left, right) when already
    computed (the tank does all fishes at once)."""
    reach = probe_reach(me, target)
    f = units(flats(me.forward))
    side = np.array([-f[2], 0.0, f[0]])  # the fish's left

    def way_out(sgn: int) -> np.ndarray:
        """The side sgn (+1 left), unless obstacles close it and the other side is open (with
        both closed the side is kept: flipping between them would ram the fish into a corner)."""
        if not len(kind):
            return side * sgn
        left, right = side_room(me, kind, center, size, reach) if room is None else room
        mine, other = (left, right) if sgn > 0 else (right, left)
        return side * (-sgn if mine < CLEARANCE <= other else sgn)

    if len(kind):
        d = (
            obstacle_distance(probes_ahead(me, reach), kind, center, size)
            if ahead is None
            else ahead
        )
        if d.min() < CLEARANCE:
            if prefer:
                return True, way_out(prefer)
            # turn to the side with more room
            left, right = side_room(me, kind, center, size, reach) if room is None else room
            return True, side if left >= right else -side
    if fish_side:
        return True, way_out(fish_side)
    return False, None


def avoid(me: Me, around: Around) -> Demand:
    """Turn hard to the side of the way out (kept while the avoidance lasts), beating hard
    (``avoid_many`` for one fish)."""
    away = np.full((1, 3), np.nan) if around.away is None else np.asarray(around.away)[None]
    speed, turn = avoid_many(
        np.asarray(me.forward, float)[None], np.asarray(me.velocity, float)[None],
        np.array([me.cruise]), np.array([me.top]), away, np.array([around.obstacle]),
        np.array([around.fish_only]),
    )  # fmt: skip
    return Demand(float(speed[0]), float(turn[0]))


def wander(me: Me, around: Around, rng: np.random.Generator) -> Demand:
    """Cruise with a slowly wandering heading (a random turn, small)."""
    return Demand(me.cruise, float(rng.normal(0.0, 0.3)))


def leave(me: Me, around: Around) -> Demand:
    """Swim away from the centre of the perceived fishes."""
    if len(around.fish) == 0:
        return Demand(me.cruise, 0.0)
    return steer(me, me.com - around.fish.mean(axis=0), me.cruise)


def go_to(
    me: Me, around: Around, rng: np.random.Generator, lead: float = 0.0, beside: float = 0.0
) -> Demand:
    """Swim to the focused target (eat, mate, hunt; ahead of a moving one by ``lead`` s, or
    to a point ``beside`` m to its side, a suitor's place); wander in search of one when
    none is perceived (``go_to_many`` for one fish)."""
    if around.target is None:
        return wander(me, around, rng)
    v = around.target_velocity
    speed, turn = go_to_many(
        *(np.asarray(x, float)[None] for x in (me.nose, me.com, me.forward)),
        np.array([me.cruise]),
        np.array([me.top]),
        np.asarray(around.target, float)[None],
        np.full((1, 3), np.nan) if v is None else np.asarray(v, float)[None],
        np.array([lead]),
        np.array([beside]),
    )
    return Demand(float(speed[0]), float(turn[0]))


def escape(me: Me, around: Around) -> Demand:
    """Flee at full speed, away from the predators (nearer ones weigh more)."""
    if len(around.predators) == 0:
        return Demand(me.top, 0.0)
    rel = flats(me.com - around.predators)
    w = 1.0 / np.maximum(np.linalg.norm(rel, axis=1), 0.1) ** 2
    return steer(me, (w[:, None] * rel).sum(0), me.top)


def school(me: Me, around: Around) -> Demand:
    """Swim with the perceived schoolmates (cohesion, alignment, separation) and away from
    the predators; alone, escape."""
    mates = around.fish[around.same] if len(around.fish) else around.fish
    if len(mates) == 0:
        return escape(me, around)
    heads = around.fish_forward[around.same]
    rel = flats(mates - me.com)
    dist = np.maximum(np.linalg.norm(rel, axis=1), 1e-3)
    cohesion = units(rel.mean(0))
    alignment = units(flats(heads.mean(0)))
    separation = units(-(rel / dist[:, None] ** 2 * (dist < 1.0)[:, None]).sum(0))
    flee = np.zeros(3)
    if len(around.predators):
        flee = units(flats(me.com - around.predators.mean(0)))
    direction = 0.8 * cohesion + 1.0 * alignment + 1.2 * separation + 1.0 * flee
    return steer(me, direction, 0.5 * (me.cruise + me.top))
