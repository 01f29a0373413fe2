"""Parameterised motor skills: a swim at any speed between the learned straight swims, a turn
of any radius (or turning rate) between the learned turns.

The muscle paper's basic training (section 3.1): "Typically, our artificial animals are put
through a "basic training" regimen of primitive motor tasks that it must learn, such as
locomoting at different speeds and executing turns of different radii. They learn effective
low level controllers for each task and retain compact representations of these controllers
through controller abstraction." ``zoetic repertoire train --speeds`` learns straight swims at
steady speeds (``training.SPEED_PLAN``) beside go-straight, the fastest; every basic training
learns a sharp and a wide left turn (and their mirrors), and ``--radii`` a medium one between.

The paper blends abstracted controllers only in time (a sequence cross-fades each into the
next over about 5% of it). Here a value between two learned entries' is asked of a blend of the
two neighbouring entries' parameters along a ``Scale`` (``SPEED``: straight swims ordered by
speed; ``TURN``: go-straight and the left turns ordered by the curvature of their path):
``motor.blend``, (1 - w) a + w b, offsets mixed and each mode's amplitude scaled (an abstracted
entry is a sum of cosines, so the blend is again one, and it plays the weighted sum of the two
signals), the second entry shifted in time by a lag (``AbstractController.ahead``). Two
independently learned gaits blended out of step swim slower than either, or veer: the shark's
slow and medium swims, each within 3 degrees of straight over 6 s, blended half and half in
step by least squares turned 33 degrees; blends of the shark's learned turns out of step roll
it onto its back. So the lag is the one, on the body's time step over a stroke, whose blends at
the ``CALIBRATION_WEIGHTS`` do best (``_best_lag``): none on its back, the scale's quantity
rising from one entry's to the other's at the most weights, the scale's side effects smallest
(a straight swim: least worst turn plus roll; a turn: least worst roll). What those blends do
is kept (``Nodes``, measured once in one batched simulation per gap), and w is read off it,
linear between calibrated weights: neither the speed nor the curvature of a blend is linear in
w. A straight swim's speed is its steady one (the second half of ``GAIT_SECONDS`` from rest);
a turn's radius is that of the arc it swims from rest over ``TURN_SECONDS``, as a turn task's
promise "radius_bl" is judged.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np

from zoetic.behavior.motor import blend
from zoetic.behavior.repertoire import Repertoire
from zoetic.bodies import Body
from zoetic.control.abstract import AbstractController
from zoetic.errors import ZoeticError

GAIT_SECONDS = 6.0  # s a straight swim is played from rest; its speed is that of the second half
TURN_SECONDS = 4.0  # s a turn is played from rest: the wide and medium turn tasks' horizon
UPSIDE_DOWN = 90.0  # deg of roll past which a blend swims on its back
# deg of roll a blend may reach and still be read off: the turn and swim tasks' promise of
# level and upright (roll_deg <= 30)
UPRIGHT = 30.0
# the fraction of the value asked by which a turn blend's own measured radius or turning rate
# may miss it: more, and the calibrated blends around it change too abruptly for a weight
# read linearly between them (the shark's medium and sharp turns, blended 0.15 to 0.18 of
# the sharp one, turn on 0.5 to 1.1 body lengths)
TOLERANCE = 0.1
# the blend weights of two neighbouring entries whose motion is measured (ends: the entries)
CALIBRATION_WEIGHTS = (0.0, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 1.0)
# what ``gait_motion`` measures, with units, for the tables a CLI prints
QUANTITIES = {
    "speed": "m/s",
    "curvature": "1/BL",
    "turn_rate": "deg/s",
    "turn": "deg",
    "roll": "deg",
}


@dataclass(frozen=True)
class Scale:
    """What blends of neighbouring repertoire entries span: the entries it may use (those a
    repertoire has, at least two, ordered by ``quantity``), the ``gait_motion`` quantity they
    are ordered by and a blend's weight is read off, and the side effects (quantities whose
    worst magnitude over the calibrated blends, summed) the lag between two entries keeps
    smallest."""

    name: str
    entries: tuple[str, ...]
    quantity: str
    side_effects: tuple[str, ...]
    seconds: float  # s each entry and blend is played from rest and measured (``gait_motion``)
    train: str  # how a repertoire gets the entries, for the message when it has too few


SPEED = Scale(
    "straight swim",
    ("swim-slow", "swim-medium", "go-straight"),
    "speed",
    ("turn", "roll"),
    GAIT_SECONDS,
    "train it with --speeds",
)
# a turn of very wide radius blends the widest learned turn with go-straight (curvature ~0)
TURN = Scale(
    "turn",
    ("go-straight", "wide-turn-left", "medium-turn-left", "sharp-turn-left"),
    "curvature",
    ("roll",),
    TURN_SECONDS,
    "every basic training learns go-straight and the sharp and wide turns; --radii a medium one",
)
# measured nodes per body object, then per scale and content of its repertoire's entries
_NODES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def gait_motion(body: Body, ctrls: list, seconds: float = GAIT_SECONDS) -> dict[str, np.ndarray]:
    """Return, per controller played from rest for ``seconds`` (one batched simulation), what
    ``control.measure`` reads of the motion: "speed", the steady forward speed (m/s, the mean
    over the second half; NaN if it blew up), "turn" (deg, heading change, left positive),
    "roll" (deg, the greatest either way), "turn_rate" (deg/s, the turn over the time) and
    "curvature" (1/body length, left positive) of the arc from the first to the last centre of
    mass: the arc a turn task's promise "radius_bl" is judged by from rest over its horizon
    (``promises.arc_curvature``), so its radius is 1 / curvature body lengths."""
    from zoetic.behavior.promises import arc_curvature
    from zoetic.behavior.tracking import body_length
    from zoetic.control.measure import motion_scalars
    from zoetic.physics import get_medium, simulate

    steps = int(round(seconds / body.dt))
    every = max(1, int(round(0.05 / body.dt)))
    table = np.stack([c.table(steps, body.dt) for c in ctrls])
    tr = simulate(body, table, record_every=every)
    m = motion_scalars(body, tr.positions, tr.times, get_medium(body.medium))
    late = tr.times >= tr.times[-1] / 2.0
    turned = m["heading"][:, -1] - m["heading"][:, 0]
    bend = [arc_curvature(c, np.radians(a)) for c, a in zip(tr.com(body), turned, strict=True)]
    return {
        "speed": np.where(tr.failed, np.nan, m["speed"][:, late].mean(axis=1)),
        "turn": turned,
        "roll": np.nanmax(np.abs(m["roll"]), axis=1),
        "turn_rate": turned / (tr.times[-1] - tr.times[0]),
        "curvature": np.where(tr.failed, np.nan, np.asarray(bend) * body_length(body)),
    }


def gait_speeds(body: Body, ctrls: list) -> np.ndarray:
    """Return the steady forward speed (m/s) of each controller (``gait_motion``)."""
    return gait_motion(body, ctrls)["speed"]


def _best_lag(
    body: Body, a: AbstractController, b: AbstractController, ends: dict, scale: Scale
) -> tuple[float, dict[str, np.ndarray]]:
    """Return (lag s, motion): the lag (a multiple of the time step within b's stroke) at
    which the blends of ``a`` and ``b`` played ``lag`` ahead at the inner
    ``CALIBRATION_WEIGHTS`` do best, by in turn: none rolled past ``UPSIDE_DOWN``; the fewest
    steps along the weights at which ``scale.quantity`` fails to rise from a's to b's (``ends``:
    each ``gait_motion`` quantity's values of a and b); ``scale``'s side effects smallest (the
    sum of each one's worst magnitude, deg). motion: every quantity at every calibration
    weight, the ends included, at that lag."""
    inner = CALIBRATION_WEIGHTS[1:-1]
    lags = np.arange(max(1, int(round(b.period / body.dt)))) * body.dt
    ctrls = [blend(a, b.ahead(s), w) for s in lags for w in inner]
    m = gait_motion(body, ctrls, scale.seconds)
    chains = {
        q: np.column_stack(
            [
                np.full(len(lags), ends[q][0]),
                v.reshape(len(lags), -1),
                np.full(len(lags), ends[q][1]),
            ]
        )
        for q, v in m.items()
    }
    falls = np.sum(~(np.diff(chains[scale.quantity], axis=1) > 0), axis=1)
    over = np.any(~(chains["roll"][:, 1:-1] <= UPSIDE_DOWN), axis=1)
    score = sum(np.abs(chains[q][:, 1:-1]).max(axis=1) for q in scale.side_effects)
    k = int(np.lexsort((np.nan_to_num(score, nan=np.inf), falls, over))[0])
    return float(lags[k]), {q: c[k] for q, c in chains.items()}


@dataclass(frozen=True)
class Nodes:
    """The entries of one repertoire along a ``Scale``, ordered by its quantity, and what the
    blends of each two neighbours do.

    Gap i joins entries i and i + 1, entry i + 1 played ``lags[i]`` s ahead (``_best_lag``);
    ``curves[q][i]`` holds quantity q (``gait_motion``) of the blends at
    ``CALIBRATION_WEIGHTS`` (entry i's own first, entry i + 1's last), which ``neighbours``
    inverts where ``mids[q][i]``, the blends halfway between two calibrated weights, bear out
    a line between them (``segments``).
    """

    scale: Scale
    names: tuple[str, ...]
    lags: np.ndarray  # (S - 1,) s
    curves: dict[str, np.ndarray]  # quantity -> (S - 1, W)
    mids: dict[str, np.ndarray]  # quantity -> (S - 1, W - 1), the blends halfway between

    @classmethod
    def measure(cls, body: Body, rep: Repertoire, scale: Scale) -> Nodes:
        """Measure the repertoire's entries of ``scale`` (those it has; at least two) and the
        blends of each two neighbours at ``CALIBRATION_WEIGHTS`` over a stroke of lags (a
        batched simulation per gap)."""
        names = [n for n in scale.entries if n in rep.controllers]
        if len(names) < 2:
            raise ZoeticError(
                f"a {scale.name} between learned ones blends two of {', '.join(scale.entries)}"
                f"; the repertoire has {', '.join(names) or 'none'} ({scale.train})"
            )
        own = gait_motion(body, [rep.controllers[n] for n in names], scale.seconds)
        bad = [n for n, v in zip(names, own[scale.quantity], strict=True) if not np.isfinite(v)]
        if bad:
            raise ZoeticError(f"entries {bad} blow up when played from rest")
        order = np.argsort(own[scale.quantity])
        names = [names[i] for i in order]
        own = {q: v[order] for q, v in own.items()}
        if np.any(np.diff(own[scale.quantity]) <= 0):
            raise ZoeticError(
                f"two entries of {', '.join(names)} have the same {scale.quantity}: "
                f"{own[scale.quantity].round(3)}"
            )
        gaps = [
            _best_lag(
                body,
                rep.controllers[a],
                rep.controllers[b],
                {q: v[i : i + 2] for q, v in own.items()},
                scale,
            )
            for i, (a, b) in enumerate(zip(names[:-1], names[1:], strict=True))
        ]
        curves = {q: np.array([g[1][q] for g in gaps]) for q in own}
        lags = np.array([g[0] for g in gaps])
        gaits = [rep.controllers[n] for n in names]
        w = np.asarray(CALIBRATION_WEIGHTS)
        halves = (w[:-1] + w[1:]) / 2.0
        ctrls = [
            blend(gaits[i], gaits[i + 1].ahead(lag), h)
            for i, lag in enumerate(lags)
            for h in halves
        ]
        m = gait_motion(body, ctrls, scale.seconds)
        mids = {q: v.reshape(len(lags), len(halves)) for q, v in m.items()}
        return cls(scale, tuple(names), lags, curves, mids)

    def table(self, quantity: str | None = None) -> dict[str, float]:
        """Return each entry's ``quantity`` (default: the scale's), in the scale's order."""
        row = self.curves[quantity or self.scale.quantity]
        return {n: float(v) for n, v in zip(self.names, [*row[:, 0], row[-1, -1]], strict=True)}

    def segments(self, quantity: str | None = None) -> list[tuple[int, int, float, float]]:
        """Return (i, k, a, b) for each calibrated segment, gap i between weights k and k + 1,
        whose two blends and the one halfway stay within ``UPRIGHT`` degrees of roll and whose
        halfway blend's ``quantity`` (default: the scale's) lies within a quarter of |b - a| of
        the middle of a and b, those of its ends, in the scale's order: the segments a blend can
        be read off, nearly a line between its ends (the shark's medium and sharp turns blended
        0.125 and 0.25 of the sharp one turn on 0.6 body lengths left and 1.1 right, and the
        blend halfway 0.5 left)."""
        q = quantity or self.scale.quantity
        row, mid, roll, mroll = self.curves[q], self.mids[q], self.curves["roll"], self.mids["roll"]
        out = []
        for i in range(len(row)):
            for k in range(row.shape[1] - 1):
                a, b = float(row[i, k]), float(row[i, k + 1])
                between = abs(mid[i, k] - (a + b) / 2.0) <= abs(b - a) / 4.0
                upright = max(roll[i, k], roll[i, k + 1], mroll[i, k]) <= UPRIGHT
                if between and upright:
                    out.append((i, k, a, b))
        return out

    def spans(self, quantity: str | None = None) -> list[tuple[float, float]]:
        """Return the intervals of ``quantity`` (default: the scale's), least first, that the
        upright calibrated blends reach (``segments``, overlapping ones merged)."""
        out: list[list[float]] = []
        for lo, hi in sorted((min(a, b), max(a, b)) for *_, a, b in self.segments(quantity)):
            if out and lo <= out[-1][1]:
                out[-1][1] = max(out[-1][1], hi)
            else:
                out.append([lo, hi])
        return [(lo, hi) for lo, hi in out]

    def neighbours(self, value: float, quantity: str | None = None) -> tuple[int, float] | None:
        """Return (i, w): the blend of entries i and i + 1 at weight w has ``quantity``
        (default: the scale's) ``value`` by the upright calibrated blends (``segments``; the
        first crossing, linear between calibrated weights); w = 0 on entry i, and the last
        entry is i = S - 2, w = 1 (an entry's own value plays the entry). None where no
        upright calibrated blend reaches ``value``."""
        own = list(self.table(quantity).values())
        if value in own:  # an entry itself
            i = own.index(value)
            return (i, 0.0) if i < len(own) - 1 else (i - 1, 1.0)
        w = CALIBRATION_WEIGHTS
        for i, k, a, b in self.segments(quantity):
            if value == a:
                return i, w[k]
            if min(a, b) <= value <= max(a, b):
                return i, float(w[k] + (w[k + 1] - w[k]) * (value - a) / (b - a))
        return None

    def __len__(self) -> int:
        return len(self.names)


def nodes_for(body: Body, rep: Repertoire, scale: Scale) -> Nodes:
    """Return ``Nodes.measure(body, rep, scale)``, measured once per body object, scale and
    content of the repertoire's entries of the scale (a sequence of several swims at chosen
    speeds measures once)."""
    gaits = [rep.controllers[n] for n in scale.entries if n in rep.controllers]
    key = (scale.name,) + tuple(
        np.concatenate([c.offset, c.freq.ravel(), c.amp.ravel(), c.phase.ravel()]).tobytes()
        for c in gaits
    )
    cached = _NODES.setdefault(body, {})
    if key not in cached:
        cached[key] = Nodes.measure(body, rep, scale)
    return cached[key]


def speed_nodes(body: Body, rep: Repertoire) -> Nodes:
    """Return the repertoire's straight swims along ``SPEED`` (``nodes_for``)."""
    return nodes_for(body, rep, SPEED)


def play_at(
    rep: Repertoire, nodes: Nodes, value: float, quantity: str | None = None
) -> tuple[AbstractController, dict]:
    """Return (controller, how) whose ``quantity`` (default: the scale's) is about ``value``:
    the blend of the two neighbouring entries around it (``motor.blend``, the second at its
    best lag, at the weight the calibrated blends give), or the entry itself at a node; ``how``
    names the two entries and the weight. Raise ZoeticError, naming the reachable range and
    each entry's value, where no calibrated blend reaches ``value``."""
    q = quantity or nodes.scale.quantity
    found = nodes.neighbours(value, q) if np.isfinite(value) else None
    if found is None:
        raise ZoeticError(
            f"{q} {value:g} {QUANTITIES[q]}: the learned {nodes.scale.name}s' upright blends "
            f"reach {_spans_text(nodes.spans(q))} "
            f"({', '.join(f'{n} {v:.3f}' for n, v in nodes.table(q).items())})"
        )
    i, w = found
    a, b = nodes.names[i], nodes.names[i + 1]
    how = {q: float(value), "from": a, "to": b, "weight": round(w, 4)}
    if w <= 0.0:
        return rep.controllers[a], how
    if w >= 1.0:
        return rep.controllers[b], how
    return blend(rep.controllers[a], rep.controllers[b].ahead(nodes.lags[i]), w), how


def swim_at(rep: Repertoire, nodes: Nodes, speed: float) -> tuple[AbstractController, dict]:
    """Return (controller, how) swimming about ``speed`` m/s (``play_at`` along ``SPEED``)."""
    ctrl, how = play_at(rep, nodes, speed)
    return ctrl, {"speed_m_s": how.pop("speed")} | how


def _radius_text(curvature: float) -> str:
    """Return the radius (body lengths) of a path of ``curvature`` (1/BL, left positive) as
    text: "straight" for none or a right turn (a left turn's radius beyond any), else the
    radius."""
    return "straight" if curvature <= 0.0 else f"{1.0 / curvature:.2f}"


def _spans_text(spans: list[tuple[float, float]]) -> str:
    """Return intervals as text: "a to b, c to d"."""
    return ", ".join(f"{lo:.3f} to {hi:.3f}" for lo, hi in spans) or "nothing"


def turn_of_radius(
    rep: Repertoire, nodes: Nodes, radius_bl: float
) -> tuple[AbstractController, dict]:
    """Return (controller, how) turning left on a path of about ``radius_bl`` body lengths
    (``play_at`` along ``TURN`` at curvature 1 / radius). Raise ZoeticError naming the radii
    the learned turns reach, and each entry's, where none of their blends turns that wide or
    that tight."""
    found = None
    if np.isfinite(radius_bl) and radius_bl > 0.0:
        found = nodes.neighbours(1.0 / radius_bl)
    if found is None:
        radii = [
            (f"{1.0 / hi:.2f}" if hi > 0.0 else "straight", _radius_text(lo))
            for lo, hi in reversed(nodes.spans())
            if hi > 0.0
        ]
        entries = ", ".join(f"{n} {_radius_text(k)}" for n, k in nodes.table().items())
        reach = ", ".join(a if a == b else f"{a} to {b}" for a, b in radii) or "no left turn"
        raise ZoeticError(
            f"radius {radius_bl:g} body lengths: the learned turns' upright blends reach "
            f"{reach} (body lengths; {entries}; from rest over {TURN_SECONDS:g} s)"
        )
    ctrl, how = play_at(rep, nodes, 1.0 / radius_bl)
    del how["curvature"]
    return ctrl, {"radius_bl": float(radius_bl)} | how


def check_reached(what: str, asked: float, measured: float | None, unit: str, roll: float) -> None:
    """Raise ZoeticError where a blend, played, misses the value ``asked`` by more than
    ``TOLERANCE`` of it (``measured``: its own value; None: it swims straight) or rolls past
    ``UPRIGHT`` degrees (``roll``): the calibrated blends around it change too abruptly there
    for a weight read between them."""
    if measured is not None and abs(measured - asked) <= TOLERANCE * abs(asked):
        if roll <= UPRIGHT:
            return
    got = "swims straight" if measured is None else f"measures {measured:.3g} {unit}"
    raise ZoeticError(
        f"{what} {asked:g} {unit}: the blend read off the calibrated blends {got} and rolls "
        f"up to {roll:.0f} deg when played (more than {TOLERANCE:.0%} off, or past "
        f"{UPRIGHT:g} deg): the learned entries' blends change abruptly there; ask another value"
    )
