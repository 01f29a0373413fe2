"""An artificial fish's mind: mental state, the intention generator and the focuser.

Formulas of Tu & Terzopoulos's artificial fish (X. Tu's thesis; ``MODEL-FACTS.md``):

- hunger H = min(1 - n_e R(dt_H) / alpha, 1), R(x) = 1 - p0 x, clipped at 0 from below
  (n_e: food eaten at the last meal, dt_H: time since it);
- libido L = min(s(dt_L) (1 - H), 1), s(x) = p1 x (dt_L: time since the last mating);
- fear F = min(sum_i min(D0 / d_i, 1), 1) over the perceived predators at distances d_i;
- a stimulus s = 1/d of the nearest food or mate enters through ``ramp`` (0 below q1, 1
  above q2): the motive is the drive times (1 + ramp), capped at 1 (our reading).

The intention generator follows the thesis's priorities: (1) an imminent collision -> avoid;
(2) F > f0 -> school (a schooling fish, F < f1) or escape; (3) max(H, L) > r -> eat or mate
(a predator hunts instead of eating), the previous one of the two kept on a tie; (4) wander if
the habits are content with the surroundings, else leave. Intentions persist: a new intention
of the same or a lower priority level replaces the current one only after ``persistence``
seconds, a more urgent one at once, so that the choice does not flicker between periods;
an avoidance of another fish alone (no obstacle ahead) is a reflex that ends ``REFLEX_HOLD``
s after that fish has passed (our reading: the 1 s hold that clears a rock kept a fish from its
meal while nothing threatened it any more).
Pure functions over plain numbers and small arrays; constants in SI (see ``aquarium.species``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

INTENTIONS = ("avoid", "escape", "school", "eat", "mate", "hunt", "wander", "leave")
LEVEL = {
    "avoid": 0,
    "escape": 1,
    "school": 1,
    "eat": 2,
    "mate": 2,
    "hunt": 2,
    "wander": 3,
    "leave": 3,
}
# s: an avoidance of another fish ends this long after no fish threatens any more (not held
# the whole persistence; shorter, the fish flickers between avoiding and its errand each period)
REFLEX_HOLD = 0.3


def ramp(s, q1: float | np.ndarray, q2: float | np.ndarray):
    """Return the stimulus ramp of s: 0 below q1, 1 above q2, (s - q1)/(2 q2 - q1 - s) between."""
    if isinstance(s, float | int):  # one stimulus: plain floats, the same formula
        s = float(s)
        if s <= q1:
            return 0.0
        if s >= q2:
            return 1.0
        return (s - q1) / max(2 * q2 - q1 - s, 1e-12)
    s = np.asarray(s, dtype=float)
    mid = (s - q1) / np.maximum(2 * q2 - q1 - s, 1e-12)
    out = np.where(s <= q1, 0.0, np.where(s >= q2, 1.0, mid))
    return out if out.ndim else float(out)


def hunger(eaten: float, since_meal: float, p0: float, alpha: float = 1.0) -> float:
    """Return the hunger H in [0, 1] after ``since_meal`` s since a meal of ``eaten`` particles."""
    r = 1.0 - p0 * since_meal
    return min(max(float(1.0 - eaten * r / alpha), 0.0), 1.0)


def libido(since_mating: float, p1: float, h: float) -> float:
    """Return the libido L in [0, 1] after ``since_mating`` s at hunger ``h``."""
    return min(max(float(p1 * since_mating * (1.0 - h)), 0.0), 1.0)


def fear(distances, d0: float) -> float:
    """Return the fear F in [0, 1] of predators perceived at ``distances`` (m)."""
    if isinstance(distances, tuple | list) and len(distances) < 8:
        # a few predators: plain floats, summed in order as numpy sums fewer than 8
        return float(min(sum(min(d0 / max(x, 1e-9), 1.0) for x in distances), 1.0))
    d = np.asarray(distances, dtype=float).reshape(-1)
    if d.size == 0:
        return 0.0
    return float(min(np.minimum(d0 / np.maximum(d, 1e-9), 1.0).sum(), 1.0))


@dataclass(frozen=True)
class Drives:
    """The three mental variables at one moment."""

    hunger: float
    libido: float
    fear: float


@dataclass(frozen=True)
class Situation:
    """What the intention generator needs of perception: flags and the nearest distances (m)."""

    collision: bool = False
    predator_distances: tuple[float, ...] = ()
    food_distance: float = np.inf  # nearest perceived (seen or smelled) food
    mate_distance: float = np.inf  # nearest perceived fish of the same species
    prey_distance: float = np.inf  # nearest perceived prey (predators)
    crowded: bool = False  # more fishes within personal space than the habits tolerate
    alone: bool = False  # no fish perceived at all
    near_obstacle: bool = False  # an obstacle within personal space
    fish_only: bool = False  # the imminent collision is with another fish, no obstacle ahead


@dataclass(frozen=True)
class MindState:
    """A fish's mental state: its last meal and mating, and its current intention and target."""

    eaten: float = 1.0  # particles eaten at the last meal
    meal_time: float = 0.0  # s
    mating_time: float = 0.0  # s
    intention: str = "wander"
    since: float = -np.inf  # when the current intention was chosen (s)
    target: int | None = None
    reflex: bool = False  # the avoidance under way is of another fish only (``think``)
    threatened: float = -np.inf  # when another fish last threatened a collision (s)


def initial_mind(initial_hunger: float, p0: float, t: float = 0.0) -> MindState:
    """Return a mind whose hunger is ``initial_hunger`` at time t (a meal placed in the past)."""
    back = initial_hunger / p0 if p0 > 0 else 0.0
    return MindState(eaten=1.0, meal_time=t - back, mating_time=t)


def drives(state: MindState, t: float, c, predator_distances=()) -> Drives:
    """Return hunger, libido and fear at time t for a mind with constants ``c``
    (a ``MindConstants``): rates p0, p1 in 1/s, the fear distance D0 in m."""
    h = hunger(state.eaten, t - state.meal_time, c.hunger_rate, c.alpha)
    return Drives(
        h,
        libido(t - state.mating_time, c.libido_rate, h),
        fear(predator_distances, c.fear_distance),
    )


def drives_many(
    eaten, meal_time, mating_time, t: float, p0, alpha, p1, d0, predators
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return hunger, libido and fear (n,) of n minds at time t in one step over arrays: the
    minds' last meals (``eaten``, ``meal_time``) and matings (n,), their constants p0, alpha,
    p1, D0 (n,) or scalars, and ``predators`` (n, m): the distances (m) of the predators each
    perceives, inf for any other column. Equals ``drives`` of each mind with its perceived
    predators in column order (the fear summed in that order)."""
    eaten, meal_time = np.asarray(eaten, float), np.asarray(meal_time, float)
    r = 1.0 - p0 * (t - meal_time)
    h = np.minimum(np.maximum(1.0 - eaten * r / alpha, 0.0), 1.0)
    lib = np.minimum(np.maximum(p1 * (t - np.asarray(mating_time, float)) * (1.0 - h), 0.0), 1.0)
    d = np.asarray(predators, float).reshape(len(h), -1)
    # only the columns of a predator someone perceives (a crowd has a few): the terms of the
    # other columns are 0, and a running sum adds nothing for them
    d = d[:, np.isfinite(d).any(axis=0)]
    if d.shape[1] == 0:
        return h, lib, np.zeros(len(h))
    each = np.where(
        np.isfinite(d),
        np.minimum(np.asarray(d0, float).reshape(-1, 1) / np.maximum(d, 1e-9), 1.0),
        0.0,
    )
    # a running sum adds the terms one by one in column order, as ``fear`` adds a few
    return h, lib, np.minimum(np.cumsum(each, axis=1)[:, -1], 1.0)


def desires(drive: np.ndarray, distance: np.ndarray, q1: np.ndarray, q2: np.ndarray):
    """Return n motives (n,): each drive times (1 + the ``ramp`` of the stimulus 1/d of its
    nearest target, d (n,) m, inf or 0 for none), capped at 1 (a target in reach at most
    doubles an appetite); each with its own ramp (q1, q2 (n,))."""
    d = np.asarray(distance, float)
    ok = np.isfinite(d) & (d > 0)
    s = np.where(ok, 1.0 / np.where(ok, d, 1.0), 0.0)
    return np.minimum(1.0, drive * (1.0 + ramp(s, q1, q2)))


@dataclass(frozen=True)
class Tempers:
    """n minds' constants and habits as arrays (n,) each, for ``think_many``: the fear,
    panic and desire thresholds, the hunger and libido ramps (q1, q2), the persistence (s),
    and the habits the intention generator reads; and which are predators."""

    fear_threshold: np.ndarray
    panic_threshold: np.ndarray
    hunger_q: tuple[np.ndarray, np.ndarray]
    libido_q: tuple[np.ndarray, np.ndarray]
    desire_threshold: np.ndarray
    persistence: np.ndarray
    schooling: np.ndarray
    no_crowd: np.ndarray  # dislikes crowds
    no_obstacles: np.ndarray  # dislikes obstacles near
    company: np.ndarray  # likes company
    predator: np.ndarray

    @classmethod
    def of(cls, constants: list, habits: list, predator: list[bool]) -> Tempers:
        """Return the tempers of minds with these constants (``MindConstants``), habits and
        predator flags, one each."""

        def col(get) -> np.ndarray:
            return np.array([get(c, h) for c, h in zip(constants, habits, strict=True)])

        return cls(
            col(lambda c, h: c.fear_threshold),
            col(lambda c, h: c.panic_threshold),
            (col(lambda c, h: c.hunger_ramp[0]), col(lambda c, h: c.hunger_ramp[1])),
            (col(lambda c, h: c.libido_ramp[0]), col(lambda c, h: c.libido_ramp[1])),
            col(lambda c, h: c.desire_threshold),
            col(lambda c, h: c.persistence),
            col(lambda c, h: bool(h.schooling)),
            col(lambda c, h: "crowd" in h.dislikes),
            col(lambda c, h: "obstacles" in h.dislikes),
            col(lambda c, h: "company" in h.likes),
            np.array(predator, bool),
        )


@dataclass(frozen=True)
class Situations:
    """n minds' situations as arrays (n,) each: the fields of ``Situation`` the intention
    generator reads (the predators' distances go to the drives)."""

    collision: np.ndarray
    food_distance: np.ndarray
    mate_distance: np.ndarray
    prey_distance: np.ndarray
    crowded: np.ndarray
    alone: np.ndarray
    near_obstacle: np.ndarray
    fish_only: np.ndarray

    @classmethod
    def of(cls, sits: list[Situation]) -> Situations:
        """Return the situations as arrays."""
        names = cls.__dataclass_fields__
        return cls(**{k: np.array([getattr(x, k) for x in sits]) for k in names})


CODE = {name: k for k, name in enumerate(INTENTIONS)}
LEVELS = np.array([LEVEL[name] for name in INTENTIONS])


def intend_many(
    hunger: np.ndarray, libido: np.ndarray, fear: np.ndarray, sit: Situations, c: Tempers,
    previous: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """Return the intentions (n,) (indices into ``INTENTIONS``) the priorities give n minds
    (before persistence), for their drives (n,) in their situations; previous: their
    intentions now (indices)."""
    target = np.where(c.predator, sit.prey_distance, sit.food_distance)
    h = desires(hunger, target, *c.hunger_q)
    lib = desires(libido, sit.mate_distance, *c.libido_q)
    feed = np.where(c.predator, CODE["hunt"], CODE["eat"])
    kept = (previous == feed) | (previous == CODE["mate"])  # a tie: the one followed
    want = np.where(h > lib, feed, np.where(lib > h, CODE["mate"], np.where(kept, previous, feed)))
    content = ~(
        (c.no_crowd & sit.crowded)
        | (c.no_obstacles & sit.near_obstacle)
        | (c.company & sit.alone & ~c.schooling)
    )
    out = np.where(content, CODE["wander"], CODE["leave"])
    out = np.where((h > c.desire_threshold) | (lib > c.desire_threshold), want, out)
    afraid = ~c.predator & (fear > c.fear_threshold)
    school = c.schooling & (fear < c.panic_threshold)
    out = np.where(afraid, np.where(school, CODE["school"], CODE["escape"]), out)
    return np.where(sit.collision, CODE["avoid"], out)


def intend(
    d: Drives,
    sit: Situation,
    c,
    habits,
    predator: bool = False,
    previous: str = "wander",
) -> str:
    """Return the intention the priorities give (before persistence), for drives ``d``
    (``intend_many`` for one mind)."""
    code = intend_many(
        np.array([d.hunger]), np.array([d.libido]), np.array([d.fear]), Situations.of([sit]),
        Tempers.of([c], [habits], [predator]), np.array([CODE[previous]]),
    )  # fmt: skip
    return INTENTIONS[int(code[0])]


def persist(previous: str, since: float, candidate: str, t: float, persistence: float) -> str:
    """Return the intention to follow: the candidate if more urgent than the previous one or
    once the previous has lasted ``persistence`` s, else the previous one."""
    return (
        candidate if persists(CODE[previous], since, CODE[candidate], t, persistence) else previous
    )


def persists(previous, since, candidate, t: float, persistence) -> np.ndarray:
    """Return whether each candidate (indices into ``INTENTIONS``) replaces the previous
    intention (``persist``'s rule over arrays): the same one, a more urgent one, or after
    the previous has lasted ``persistence`` s."""
    previous, candidate = np.asarray(previous), np.asarray(candidate)
    urgent = (candidate == previous) | (LEVELS[candidate] < LEVELS[previous])
    return urgent | (t - np.asarray(since, float) >= persistence)


def focus(distances, previous: int | None = None, keep_within: float = 1.25) -> int | None:
    """Return the index of the target to attend to among candidates at ``distances`` (inf:
    not perceived): the nearest, but the previous target is kept while it is perceived and
    no more than ``keep_within`` times farther than the nearest (no dithering); None when
    none is perceived (``focus_many`` for one mind)."""
    d = np.asarray(distances, dtype=float).reshape(1, -1)
    k = int(focus_many(d, np.array([-1 if previous is None else previous]), keep_within)[0])
    return None if k < 0 else k


def focus_many(distances, previous, keep_within: float = 1.25) -> np.ndarray:
    """Return (n,) the targets the focusers of n minds attend to (-1: none), each row of
    ``distances`` (n, M) one mind's candidates (inf: not perceived) and ``previous`` (n,) its
    previous target (-1: none): ``focus_pairs`` of the perceived ones."""
    d = np.asarray(distances, dtype=float)
    ii, jj = np.nonzero(np.isfinite(d))
    return focus_pairs(len(d), ii, jj, d[ii, jj], previous, keep_within)


def focus_pairs(n: int, rows, cols, distances, previous, keep_within: float = 1.25):
    """Return (n,) the targets the focusers of n minds attend to (-1: none) among the
    candidates each perceives: mind ``rows[k]`` perceives candidate ``cols[k]`` at
    ``distances[k]`` (the pairs in row order, each row's columns ascending); ``previous``
    (n,) each mind's previous target (-1: none). The nearest (the first on a tie), but the
    previous target is kept while it is perceived and no more than ``keep_within`` times
    farther than the nearest (no dithering)."""
    d = np.asarray(distances, float)
    ok = np.isfinite(d)  # an infinite candidate is not perceived
    rows, cols, d = np.asarray(rows, int)[ok], np.asarray(cols, int)[ok], d[ok]
    out = np.full(n, -1)
    if not len(rows):
        return out
    order = np.lexsort((cols, d, rows))  # by mind, then distance, then column
    by = rows[order]
    first = order[np.concatenate(([True], by[1:] != by[:-1]))]
    who = rows[first]
    out[who] = cols[first]
    near = np.full(n, np.inf)
    near[who] = d[first]
    # the previous target's distance, where it is among the mind's candidates
    prev = np.asarray(previous, int)
    width = int(max(cols.max(), prev.max(initial=0))) + 1
    key = rows * width + cols  # ascending: the pairs are in row order, columns ascending
    want = np.arange(n) * width + np.maximum(prev, 0)
    at = np.minimum(np.searchsorted(key, want), len(key) - 1)
    keep = (prev >= 0) & (key[at] == want) & (d[at] <= keep_within * near)
    return np.where(keep, prev, out)


def think(
    state: MindState,
    t: float,
    c,
    habits,
    sit: Situation,
    predator: bool = False,
    d: Drives | None = None,
) -> tuple[MindState, Drives]:
    """Return the mind after one brain period at time t, and its drives (``d`` when given,
    e.g. from ``drives_many``): ``think_many`` for one mind."""
    if d is None:
        d = drives(state, t, c, sit.predator_distances)
    (mind,) = think_many(
        [state], t, Tempers.of([c], [habits], [predator]), Situations.of([sit]),
        np.array([d.hunger]), np.array([d.libido]), np.array([d.fear]),
    )  # fmt: skip
    return mind, d


def think_many(
    minds: list[MindState],
    t: float,
    c: Tempers,
    sit: Situations,
    hunger: np.ndarray,
    libido: np.ndarray,
    fear: np.ndarray,
) -> list[MindState]:
    """Return n minds after one brain period at time t, for their drives (n,) in their
    situations: the intention the priorities and persistence choose (the target is left to
    the focuser); an avoidance of another fish alone ends ``REFLEX_HOLD`` s after no
    collision threatens, not held the whole persistence."""
    now = np.array([CODE[m.intention] for m in minds], int)
    since = np.array([m.since for m in minds], float)
    reflex = np.array([m.reflex for m in minds], bool)
    was = np.array([m.threatened for m in minds], float)
    cand = intend_many(hunger, libido, fear, sit, c, now)
    threatened = np.where(sit.collision & sit.fish_only, t, was)
    passed = ~sit.collision & (t - threatened >= REFLEX_HOLD - 1e-9)
    back = (now == CODE["avoid"]) & reflex & passed  # the fish it avoided has passed
    chosen = np.where(back | persists(now, since, cand, t, c.persistence), cand, now)
    changed = chosen != now
    flip = (chosen == CODE["avoid"]) & sit.collision & (reflex != sit.fish_only)
    reflex = np.where(flip, sit.fish_only, reflex)
    out = list(minds)
    for k in np.flatnonzero(changed | flip | (threatened != was)).tolist():
        m = replace(minds[k], threatened=float(threatened[k]), reflex=bool(reflex[k]))
        if changed[k]:
            m = replace(m, intention=INTENTIONS[chosen[k]], since=t, target=None)
        out[k] = m
    return out


def ate(state: MindState, t: float, particles: float = 1.0) -> MindState:
    """Return the mind after a meal of ``particles`` at time t (hunger drops)."""
    return replace(state, eaten=float(particles), meal_time=t)


def mated(state: MindState, t: float) -> MindState:
    """Return the mind after mating at time t (libido drops to 0)."""
    return replace(state, mating_time=t)
