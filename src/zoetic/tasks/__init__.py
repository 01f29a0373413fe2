"""Named tasks: weighted objective terms, a horizon, a start state and the capabilities they need.

A task file (TOML) holds ``name``, ``description``, ``requires`` (capabilities an animal and its
medium must have, e.g. ``["water"]``; ``"a|b"`` accepts either), ``horizon`` (s), ``nodes``
(controller parameters per actuator), ``mu1``/``mu2``/``nu1``/``nu2`` (the objective's weights),
``record_hz`` (how often terms see the motion), an optional ``[start]`` table (``position``
[x, y, z] m of the centre of mass, ``depth`` m below the water surface, ``heading`` and
``pitch`` rad, ``speed`` m/s along the heading or ``"cruise"``, and an optional ``name``) or,
instead, ``[[starts]]``: several such tables, each rollout of a candidate played from every one
of them (its objective is the mean of its E over the starts), and ``[[terms]]`` entries
(``kind`` from ``zoetic.tasks.terms.TERMS``, ``weight``, ``target``, ``goal``). Keys are
checked strictly.

``speed = "cruise"`` is a swimming (or crawling) start at the speed the animal's own wave
sustains: the centre of mass's top-view displacement over the second half of
``CRUISE_SECONDS`` of the wave played from rest at that start's place, over that time
(``cruise_speed``), so one task file gives each animal a start at a speed it actually swims.
"""

from __future__ import annotations

import dataclasses
import math
import weakref
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from zoetic import io as rd
from zoetic.errors import TaskError, ZoeticError
from zoetic.tasks.terms import TERMS

if TYPE_CHECKING:
    from zoetic.bodies import Body
    from zoetic.physics import Medium, State

TASK_DIR = Path(__file__).parent
TERM_KINDS = {name: d.doc for name, d in TERMS.items()}
CAPABILITIES = {
    "water": "its medium has water to swim in",
    "deep-water": "water everywhere, no surface to leave",
    "surface": "water with air above it (leaps)",
    "ground": "a floor to crawl on",
    "fins": "it has fins",
    "head": "it has a head node",
    "mirror": "it is left-right symmetric (mirrored turns)",
}
TOP_KEYS = (
    "name",
    "description",
    "requires",
    "horizon",
    "nodes",
    "mu1",
    "mu2",
    "nu1",
    "nu2",
    "record_hz",
    "start",
    "starts",
    "terms",
    "promise",
)
START_KEYS = ("name", "position", "depth", "heading", "pitch", "speed")
CRUISE = "cruise"  # a start speed: the animal's own wave's sustained speed (cruise_speed)
CRUISE_SECONDS = 6.0  # s of the wave played to measure it (the speed of the second half)
MAX_STARTS = 16
TERM_KEYS = ("kind", "weight", "target", "goal")
# what a learned entry must do, judged from each of its task's starts over the horizon
# (``behavior.promises.judge_entry``): a task's [promise] table gives [low, high] per quantity
PROMISES = {
    "turn_deg": "heading change, end minus start (deg, left positive)",
    "climb_m": "rise of the centre of mass, end minus start (m, up positive)",
    "speed_bl_s": "mean speed of the centre of mass (body lengths/s)",
    "steady_speed_bl_s": "top-view speed of the centre of mass, second half (body lengths/s)",
    "radius_bl": "radius of the arc the centre of mass turns on (body lengths)",
    "roll_deg": "greatest roll over the motion (deg, either way)",
    "pitch_change_deg": "pitch change, end minus start (deg, nose up positive)",
}


@dataclass(frozen=True)
class Term:
    """A task's term: kind (a ``TERMS`` name), weight (E_v adds weight * value), target, goal."""

    kind: str
    weight: float
    target: float = 0.0
    goal: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Promise:
    """What a learned entry must do: ``quantity`` (a ``PROMISES`` name) within [low, high]."""

    quantity: str
    low: float
    high: float

    def text(self) -> str:
        """Return the promise in words, e.g. "turn_deg >= 90" or "roll_deg <= 30"."""
        if math.isinf(self.high):
            return f"{self.quantity} >= {self.low:g}"
        if math.isinf(self.low) or (self.low == 0 and self.quantity == "roll_deg"):
            return f"{self.quantity} <= {self.high:g}"
        return f"{self.quantity} in [{self.low:g}, {self.high:g}]"


@dataclass(frozen=True)
class Start:
    """Where and how a task's rollouts start; None keeps the body's own start."""

    position: tuple[float, float, float] | None = None  # m, centre of mass
    depth: float | None = None  # m below the water surface (sets the height)
    heading: float = 0.0  # rad, left turns (toward +z) positive
    pitch: float = 0.0  # rad, nose up positive
    speed: float | str = 0.0  # m/s along the start heading, or CRUISE
    name: str = ""  # how reports name it ("rest", "swimming"); "" for an unnamed start

    def to_dict(self) -> dict:
        """Return the non-default entries as a TOML-able dict."""
        d = {"heading": self.heading, "pitch": self.pitch, "speed": self.speed}
        if self.name:
            d["name"] = self.name
        if self.position is not None:
            d["position"] = list(self.position)
        if self.depth is not None:
            d["depth"] = self.depth
        return d


@dataclass(frozen=True)
class Task:
    """What to learn: E = mu1 * E_u + mu2 * E_v over a horizon, E_v = sum of weighted terms."""

    name: str
    description: str
    requires: tuple[str, ...]
    horizon: float
    nodes: int
    mu1: float
    mu2: float
    nu1: float
    nu2: float
    terms: tuple[Term, ...]
    source: str = "<memory>"
    starts: tuple[Start, ...] = (Start(),)
    record_hz: float = 20.0
    promises: tuple[Promise, ...] = ()

    @property
    def start(self) -> Start:
        """The first start (the only one of a single-start task)."""
        return self.starts[0]

    def start_names(self) -> list[str]:
        """Return a name per start: its own, else "rest" / "swimming" by its speed, made
        unique with its index where two would read the same."""
        names = [s.name or ("rest" if s.speed == 0 else "swimming") for s in self.starts]
        return [n if names.count(n) == 1 else f"{n}{k}" for k, n in enumerate(names)]

    def to_dict(self) -> dict:
        """Return the task as a TOML-able dict (for a run's config.toml)."""
        return {
            "name": self.name,
            "description": self.description,
            "requires": list(self.requires),
            "horizon": self.horizon,
            "nodes": self.nodes,
            "mu1": self.mu1,
            "mu2": self.mu2,
            "nu1": self.nu1,
            "nu2": self.nu2,
            "record_hz": self.record_hz,
            **(
                {"start": self.start.to_dict()}
                if len(self.starts) == 1
                else {"starts": [st.to_dict() for st in self.starts]}
            ),
            "terms": [
                {"kind": t.kind, "weight": t.weight, "target": t.target, "goal": list(t.goal)}
                for t in self.terms
            ],
            **(
                {"promise": {p.quantity: [p.low, p.high] for p in self.promises}}
                if self.promises
                else {}
            ),
        }


def _did_you_mean(word: str, choices) -> str:
    return rd.suggest(str(word), choices) or f" (choose from {', '.join(choices)})"


def _check_keys(d: dict, allowed, where: str) -> None:
    rd.check_keys(d, allowed, where, TaskError)


def _num(d: dict, key: str, where: str, default=None, **bounds) -> float:
    v = d.get(key, default)
    if v is None:
        raise TaskError(f"{where}: missing '{key}'")
    return rd.number(v, f"{where}: '{key}'", TaskError, **bounds)


def _vec3(d: dict, key: str, where: str, default=None):
    v = d.get(key, default)
    if v is None:
        return None
    if not (isinstance(v, list | tuple) and len(v) == 3):
        raise TaskError(f"{where}: '{key}' must be [x, y, z], got {v!r}")
    return tuple(_num({"v": g}, "v", f"{where}: '{key}'") for g in v)


def _parse_start(raw, w: str) -> Start:
    """Return the Start a [start] table (or one [[starts]] entry, ``w`` naming it) holds."""
    if not isinstance(raw, dict):
        raise TaskError(f"{w} must be a table")
    _check_keys(raw, START_KEYS, w)
    depth = None if raw.get("depth") is None else _num(raw, "depth", w)
    speed = raw.get("speed", 0.0)
    if not (isinstance(speed, str) and speed == CRUISE):
        if isinstance(speed, str):
            raise TaskError(
                f"{w}: 'speed' must be m/s or {CRUISE!r} (the animal's own wave's "
                f"sustained speed), got {speed!r}"
            )
        speed = _num(raw, "speed", w, 0.0)
    name = raw.get("name", "")
    if not isinstance(name, str):
        raise TaskError(f"{w}: 'name' must be text, got {name!r}")
    return Start(
        _vec3(raw, "position", w),
        depth,
        _num(raw, "heading", w, 0.0),
        _num(raw, "pitch", w, 0.0),
        speed,
        name,
    )


def _parse_starts(doc: dict, where: str) -> tuple[Start, ...]:
    """Return the task's starts: its [start] table, or its [[starts]] entries, or rest."""
    if "start" in doc and "starts" in doc:
        raise TaskError(f"{where}: give one [start] table or [[starts]] entries, not both")
    if "starts" not in doc:
        return (_parse_start(doc.get("start", {}), f"{where}: start"),)
    raw = doc["starts"]
    if not isinstance(raw, list) or not raw:
        raise TaskError(f"{where}: 'starts' must be one or more [[starts]] tables, got {raw!r}")
    if len(raw) > MAX_STARTS:
        raise TaskError(f"{where}: {len(raw)} [[starts]] entries; at most {MAX_STARTS}")
    starts = tuple(_parse_start(r, f"{where}: starts[{k}]") for k, r in enumerate(raw))
    names = [s.name for s in starts]
    for k, s in enumerate(starts):
        if s.name and s.name in names[:k]:
            raise TaskError(
                f"{where}: starts[{k}]: the name {s.name!r} is given to "
                f"{names.count(s.name)} starts; each needs its own"
            )
    return starts


def _parse_promises(raw, where: str) -> tuple[Promise, ...]:
    """Return the promises of a [promise] table: quantity = [low, high] (inf allowed)."""
    if raw is None:
        return ()
    w = f"{where}: promise"
    if not isinstance(raw, dict):
        raise TaskError(f"{w} must be a table of quantity = [low, high]")
    _check_keys(raw, tuple(PROMISES), w)
    out = []
    for q, v in raw.items():
        ok = isinstance(v, list) and len(v) == 2
        if not ok or any(isinstance(x, bool) or not isinstance(x, int | float) for x in v):
            raise TaskError(f"{w}: '{q}' must be [low, high] (numbers, inf allowed), got {v!r}")
        lo, hi = float(v[0]), float(v[1])
        if math.isnan(lo) or math.isnan(hi) or not lo <= hi:
            raise TaskError(f"{w}: '{q}' must be [low, high] with low <= high, got {v!r}")
        out.append(Promise(q, lo, hi))
    return tuple(out)


def _parse_requires(raw, where: str) -> tuple[str, ...]:
    if not isinstance(raw, list) or not all(isinstance(r, str) for r in raw):
        raise TaskError(f"{where}: 'requires' must be a list of capabilities, got {raw!r}")
    for r in raw:
        for alt in r.split("|"):
            if alt not in CAPABILITIES:
                raise TaskError(
                    f"{where}: requires: unknown capability {alt!r}"
                    f"{_did_you_mean(alt, CAPABILITIES)}"
                )
    return tuple(raw)


def parse_task(doc: dict, source: str = "<memory>") -> Task:
    """Return the Task a parsed TOML document describes; TaskError names what is wrong."""
    where = source
    _check_keys(doc, TOP_KEYS, where)
    name = doc.get("name")
    if not isinstance(name, str):
        raise TaskError(f"{where}: missing 'name'")
    horizon = _num(doc, "horizon", where, positive=True, hi=rd.LIMITS.seconds)
    nodes = rd.integer(
        doc.get("nodes", 15), f"{where}: 'nodes'", TaskError, 2, rd.LIMITS.controller_nodes
    )
    record_hz = _num(doc, "record_hz", where, 20.0, positive=True, hi=10_000.0)
    terms = []
    raw_terms = doc.get("terms", [])
    if not isinstance(raw_terms, list) or not raw_terms:
        raise TaskError(f"{where}: a task needs at least one [[terms]] entry")
    for k, t in enumerate(raw_terms):
        w = f"{where}: terms[{k}]"
        if not isinstance(t, dict):
            raise TaskError(f"{w}: must be a table")
        _check_keys(t, TERM_KEYS, w)
        kind = t.get("kind")
        if kind not in TERMS:
            raise TaskError(f"{w}: unknown kind {kind!r}{_did_you_mean(kind, TERMS)}")
        terms.append(
            Term(
                kind,
                _num(t, "weight", w, 1.0),
                _num(t, "target", w, 0.0),
                _vec3(t, "goal", w, [0.0, 0.0, 0.0]),
            )
        )
    return Task(
        name=name,
        description=str(doc.get("description", "")),
        requires=_parse_requires(doc.get("requires", []), where),
        horizon=horizon,
        nodes=nodes,
        mu1=_num(doc, "mu1", where, 0.0),
        mu2=_num(doc, "mu2", where, 1.0),
        nu1=_num(doc, "nu1", where, 0.0),
        nu2=_num(doc, "nu2", where, 0.0),
        terms=tuple(terms),
        source=source,
        starts=_parse_starts(doc, where),
        record_hz=record_hz,
        promises=_parse_promises(doc.get("promise"), where),
    )


def list_tasks() -> list[str]:
    """Return the names of the built-in tasks."""
    return sorted(p.stem for p in TASK_DIR.glob("*.toml"))


def load_task(name_or_path: str | Path) -> Task:
    """Return a built-in task by name, or the task in a TOML file."""
    from zoetic.io import read_toml, suggest

    path = Path(name_or_path)
    if not (path.suffix == ".toml" or path.exists()):
        path = TASK_DIR / f"{name_or_path}.toml"
        if not path.exists():
            hint = suggest(str(name_or_path), list_tasks())
            raise TaskError(
                f"unknown task {str(name_or_path)!r}{hint}: choose one of "
                f"{', '.join(list_tasks())} or give the path of a task .toml file"
            )
    try:
        doc = read_toml(path, what="task file")
    except ZoeticError as exc:
        raise TaskError(str(exc)) from None
    return parse_task(doc, str(path))


def capabilities(body: Body, medium: Medium | str | None = None) -> set[str]:
    """Return the capabilities an animal has in a medium (default: its own)."""
    from zoetic.physics import get_medium
    from zoetic.physics.media import FAR

    med = get_medium(medium or body.medium)
    caps = {"head"} if 0 <= body.head < body.n_nodes else set()
    if med.water_drag > 0 and med.water_level > -FAR:
        caps.add("water")
        caps.add("deep-water" if med.water_level >= FAR else "surface")
    if med.floor:
        caps.add("ground")
    if len(body.fin_area):
        caps.add("fins")
    if body.is_mirror_symmetric:
        caps.add("mirror")
    return caps


def missing(task: Task, body: Body, medium: Medium | str | None = None) -> list[str]:
    """Return the task's requirements the animal (in that medium) does not meet."""
    caps = capabilities(body, medium)
    return [r for r in task.requires if not set(r.split("|")) & caps]


def fits(task: Task, body: Body, medium: Medium | str | None = None) -> bool:
    """Return True when the task can apply to the animal in that medium."""
    return not missing(task, body, medium)


def check_fits(task: Task, body: Body, medium: Medium | str | None = None) -> None:
    """Raise TaskError saying why the task cannot apply to the animal, if it cannot."""
    lack = missing(task, body, medium)
    if lack:
        med = medium if isinstance(medium, str) else getattr(medium, "name", None) or body.medium
        needs = ", ".join(" or ".join(r.split("|")) for r in lack)
        raise TaskError(
            f"task {task.name!r} ({task.source}) cannot apply to the {body.name} (medium "
            f"{med!r}): it requires {needs}, which the {body.name} does not have there"
        )


def start_state(
    task: Task, body: Body, medium: Medium | str | None = None, index: int = 0
) -> State:
    """Return one of the task's start states for a body (batch 1; default the first): placed,
    turned, pitched, moving."""
    from zoetic.physics import State, get_medium, rest_state
    from zoetic.physics.media import FAR

    st = task.starts[index]
    base = rest_state(body, 1)
    if dataclasses.replace(st, name="") == Start():  # rest where the body starts
        return base
    w = body.mass / body.total_mass
    pos = base.positions[0]
    com = w @ pos
    cp, sp = math.cos(st.pitch), math.sin(st.pitch)
    ch, sh = math.cos(st.heading), math.sin(st.heading)
    pitch = np.array([[cp, -sp, 0.0], [sp, cp, 0.0], [0.0, 0.0, 1.0]])  # x toward +y
    turn = np.array([[ch, 0.0, -sh], [0.0, 1.0, 0.0], [sh, 0.0, ch]])  # x toward +z
    rot = turn @ pitch
    target = np.array(st.position if st.position is not None else com, float)
    if st.depth is not None:
        level = get_medium(medium or body.medium).water_level
        if abs(level) >= FAR:
            raise TaskError(
                f"{task.source}: start depth needs a water surface, and "
                f"{medium or body.medium} has none"
            )
        target[1] = level - st.depth
    new = (pos - com) @ rot.T + target
    fwd = rot @ np.asarray(body.forward, float)
    speed = st.speed
    if speed == CRUISE:
        still = State(new[None].copy(), np.zeros((1, *new.shape)))
        speed = cruise_speed(body, medium, still)
    vel = np.broadcast_to(float(speed) * fwd, new.shape)
    return State(new[None].copy(), np.array(vel)[None].copy())


def start_states(task: Task, body: Body, medium: Medium | str | None = None) -> State:
    """Return all the task's start states for a body, one per batch row (S, N, 3)."""
    from zoetic.physics import State

    each = [start_state(task, body, medium, k) for k in range(len(task.starts))]
    return State(
        np.concatenate([s.positions for s in each]), np.concatenate([s.velocities for s in each])
    )


_CRUISE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # body -> {settings: m/s}


def cruise_speed(
    body: Body,
    medium: Medium | str | None = None,
    start: State | None = None,
    seconds: float = CRUISE_SECONDS,
) -> float:
    """Return the speed (m/s) the animal's own wave sustains: the centre of mass's top-view
    displacement over the second half of ``seconds`` of the wave played from ``start`` (default:
    rest). Measured once per body, medium and start (one simulation), then remembered."""
    from zoetic.control import wave_controller
    from zoetic.physics import get_medium, rest_state, simulate

    med = get_medium(medium or body.medium)
    start = start if start is not None else rest_state(body, 1)
    key = (med.name, start.positions.tobytes(), start.velocities.tobytes(), float(seconds))
    cached = _CRUISE.setdefault(body, {})
    if key in cached:
        return cached[key]
    steps = int(round(seconds / body.dt))
    every = max(1, steps // 40)
    tr = simulate(
        body, wave_controller(body).table(steps, body.dt)[None], med, body.dt, start, every
    )
    com = tr.com(body)[0]
    half = com.shape[0] // 2
    dist = float(np.linalg.norm((com[-1] - com[half])[[0, 2]]))
    v = dist / float(tr.times[-1] - tr.times[half]) if not tr.failed[0] else 0.0
    cached[key] = v
    return v
