"""Animal files (TOML) parsed into plain specs, with errors that name the file and the entry."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from zoetic.errors import BodyError

MEDIA = ("ground", "water", "sea", "vacuum")
SIDES = ("left", "right", "center")
ACTUATOR_KINDS = ("muscle", "fin")


@dataclass(frozen=True)
class NodeSpec:
    name: str
    pos: tuple[float, float, float]
    mass: float
    damping: float


@dataclass(frozen=True)
class SpringSpec:
    a: int
    b: int
    stiffness: float
    damping: float
    length: float | None  # relaxed length; None means the rest-pose distance
    kind: str
    actuator: str | None = None
    max_shortening: float | None = None
    contracted_length: float | None = None


@dataclass(frozen=True)
class ActuatorSpec:
    name: str
    kind: str
    side: str
    mirror: str | None


@dataclass(frozen=True)
class FinSpec:
    name: str
    actuator: str
    nodes: tuple[int, ...]
    forward: tuple[int, int]
    span: tuple[int, int]
    area: float
    angle_range: tuple[float, float]


@dataclass(frozen=True)
class WaveSpec:
    frequency: float
    amplitude: float
    offset: float
    phases: dict[str, float]


@dataclass(frozen=True)
class AnimalSpec:
    name: str
    description: str
    medium: str
    dt: float
    head: int
    forward: tuple[float, float, float]
    nodes: tuple[NodeSpec, ...]
    springs: tuple[SpringSpec, ...]
    actuators: tuple[ActuatorSpec, ...]
    faces: tuple[tuple[int, ...], ...]
    fins: tuple[FinSpec, ...] = ()
    wave: WaveSpec | None = None
    start_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    source: str = "<memory>"
    extra: dict[str, Any] = field(default_factory=dict)


class _Reader:
    """Pulls typed values out of a TOML table and blames the file and entry on failure."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, where: str, problem: str) -> BodyError:
        return BodyError(f"{self.source}: {where}: {problem}")

    def number(self, table: dict, key: str, where: str, default: float | None = None) -> float:
        if key not in table:
            if default is None:
                raise self.fail(where, f"missing '{key}'")
            return float(default)
        value = table[key]
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(where, f"'{key}' must be a number, got {value!r}")
        if not math.isfinite(value):
            raise self.fail(where, f"'{key}' is not a finite number ({value})")
        return float(value)

    def string(self, table: dict, key: str, where: str, default: str | None = None) -> str:
        value = table.get(key, default)
        if value is None:
            raise self.fail(where, f"missing '{key}'")
        if not isinstance(value, str):
            raise self.fail(where, f"'{key}' must be a string, got {value!r}")
        return value

    def vector(self, table: dict, key: str, where: str, n: int) -> tuple[float, ...]:
        value = table.get(key)
        if not isinstance(value, list) or len(value) != n:
            raise self.fail(where, f"'{key}' must be a list of {n} numbers, got {value!r}")
        out = []
        for v in value:
            if isinstance(v, bool) or not isinstance(v, int | float):
                raise self.fail(where, f"'{key}' must hold numbers, got {v!r}")
            if not math.isfinite(v):
                raise self.fail(where, f"'{key}' holds a non-finite number ({v})")
            out.append(float(v))
        return tuple(out)

    def table_list(self, doc: dict, key: str) -> list[dict]:
        value = doc.get(key, [])
        if not isinstance(value, list) or not all(isinstance(t, dict) for t in value):
            raise self.fail(key, f"'{key}' must be an array of tables ([[{key}]])")
        return value


def _node_ref(r: _Reader, ref: Any, index: dict[str, int], n: int, where: str) -> int:
    if isinstance(ref, bool):
        raise r.fail(where, f"unknown node {ref!r}")
    if isinstance(ref, int):
        if 0 <= ref < n:
            return ref
        raise r.fail(where, f"unknown node {ref} (the animal has nodes 0..{n - 1})")
    if isinstance(ref, str) and ref in index:
        return index[ref]
    raise r.fail(where, f"unknown node {ref!r}")


def _node_refs(r: _Reader, table: dict, key: str, index, n: int, where: str, count=None):
    refs = table.get(key)
    if not isinstance(refs, list) or (count is not None and len(refs) not in count):
        want = " or ".join(str(c) for c in count) if count else "some"
        raise r.fail(where, f"'{key}' must list {want} nodes, got {refs!r}")
    return tuple(_node_ref(r, ref, index, n, where) for ref in refs)


def parse_animal(doc: dict[str, Any], source: str = "<memory>") -> AnimalSpec:
    """Return the AnimalSpec described by a parsed TOML document; raise BodyError if malformed."""
    r = _Reader(source)
    name = r.string(doc, "name", "top level")
    medium = r.string(doc, "medium", "top level")
    if medium not in MEDIA:
        raise r.fail("top level", f"unknown medium {medium!r} (choose from {', '.join(MEDIA)})")
    dt = r.number(doc, "dt", "top level", default=0.005)
    if dt <= 0:
        raise r.fail("top level", f"'dt' must be positive, got {dt}")
    defaults = doc.get("defaults", {})
    if not isinstance(defaults, dict):
        raise r.fail("defaults", "must be a table")
    d_node_damping = r.number(defaults, "node_damping", "defaults", default=0.0)
    d_stiffness = r.number(defaults, "stiffness", "defaults", default=0.0)
    d_damping = r.number(defaults, "spring_damping", "defaults", default=0.0)

    nodes: list[NodeSpec] = []
    index: dict[str, int] = {}
    for k, t in enumerate(r.table_list(doc, "nodes")):
        nm = r.string(t, "name", f"nodes[{k}]", default=str(k))
        where = f"node {nm!r} (nodes[{k}])"
        if nm in index:
            raise r.fail(where, f"duplicate node name {nm!r}")
        mass = r.number(t, "mass", where)
        if mass <= 0:
            raise r.fail(where, f"mass must be positive, got {mass}")
        damping = r.number(t, "damping", where, default=d_node_damping)
        if damping < 0:
            raise r.fail(where, f"damping must not be negative, got {damping}")
        index[nm] = k
        nodes.append(NodeSpec(nm, r.vector(t, "pos", where, 3), mass, damping))
    n = len(nodes)
    if n < 2:
        raise r.fail("nodes", "an animal needs at least 2 nodes")

    actuators: list[ActuatorSpec] = []
    act_names: set[str] = set()
    for k, t in enumerate(r.table_list(doc, "actuators")):
        nm = r.string(t, "name", f"actuators[{k}]")
        where = f"actuator {nm!r}"
        if nm in act_names:
            raise r.fail(where, "duplicate actuator name")
        kind = r.string(t, "kind", where, default="muscle")
        if kind not in ACTUATOR_KINDS:
            raise r.fail(where, f"unknown kind {kind!r} (choose from muscle, fin)")
        side = r.string(t, "side", where, default="center")
        if side not in SIDES:
            raise r.fail(where, f"unknown side {side!r} (choose from {', '.join(SIDES)})")
        mirror = t.get("mirror")
        if mirror is not None and not isinstance(mirror, str):
            raise r.fail(where, f"'mirror' must be an actuator name, got {mirror!r}")
        act_names.add(nm)
        actuators.append(ActuatorSpec(nm, kind, side, mirror))
    for a in actuators:
        if a.mirror is not None and a.mirror not in act_names:
            raise r.fail(f"actuator {a.name!r}", f"mirror {a.mirror!r} is not an actuator")

    springs: list[SpringSpec] = []
    seen: dict[tuple[int, int], int] = {}
    for k, t in enumerate(r.table_list(doc, "springs")):
        where = f"springs[{k}]"
        a, b = _node_refs(r, t, "nodes", index, n, where, count=(2,))
        where = f"springs[{k}] ({nodes[a].name}-{nodes[b].name})"
        if a == b:
            raise r.fail(where, "a spring must join two different nodes")
        key = (min(a, b), max(a, b))
        if key in seen:
            raise r.fail(where, f"duplicate spring (same nodes as springs[{seen[key]}])")
        seen[key] = k
        stiffness = r.number(t, "stiffness", where, default=d_stiffness)
        if stiffness <= 0:
            raise r.fail(where, f"stiffness must be positive, got {stiffness}")
        damping = r.number(t, "damping", where, default=d_damping)
        if damping < 0:
            raise r.fail(where, f"damping must not be negative, got {damping}")
        rest = math.dist(nodes[a].pos, nodes[b].pos)
        length = r.number(t, "length", where) if "length" in t else None
        relaxed = rest if length is None else length
        if relaxed <= 1e-9:
            raise r.fail(where, f"zero-length spring (relaxed length {relaxed:g})")
        actuator = t.get("actuator")
        max_short = contracted = None
        kind = r.string(t, "kind", where, default="muscle" if actuator else "structural")
        if actuator is not None:
            if actuator not in act_names:
                raise r.fail(where, f"unknown actuator {actuator!r}")
            if "contracted_length" in t:
                contracted = r.number(t, "contracted_length", where)
            elif "max_shortening" in t:
                max_short = r.number(t, "max_shortening", where)
                contracted = (1.0 - max_short) * relaxed
            else:
                raise r.fail(where, "a muscle needs 'max_shortening' or 'contracted_length'")
            if not contracted < relaxed:
                raise r.fail(
                    where,
                    f"contracted length {contracted:g} is not shorter than relaxed {relaxed:g}",
                )
            if contracted <= 0:
                raise r.fail(where, f"contracted length {contracted:g} must be positive")
        springs.append(
            SpringSpec(a, b, stiffness, damping, length, kind, actuator, max_short, contracted)
        )

    faces = []
    for k, t in enumerate(r.table_list(doc, "faces")):
        refs = _node_refs(r, t, "nodes", index, n, f"faces[{k}]", count=(3, 4))
        if len(set(refs)) != len(refs):
            raise r.fail(f"faces[{k}]", "a face repeats a node")
        faces.append(refs)

    fins = []
    for k, t in enumerate(r.table_list(doc, "fins")):
        nm = r.string(t, "name", f"fins[{k}]")
        where = f"fin {nm!r}"
        act = r.string(t, "actuator", where)
        if act not in act_names:
            raise r.fail(where, f"unknown actuator {act!r}")
        area = r.number(t, "area", where)
        if area <= 0:
            raise r.fail(where, f"area must be positive, got {area}")
        lo, hi = r.vector(t, "angle_range", where, 2)
        if not lo < hi:
            raise r.fail(where, f"angle_range must be increasing, got [{lo}, {hi}]")
        fins.append(
            FinSpec(
                nm,
                act,
                _node_refs(r, t, "nodes", index, n, where, count=(1, 2, 3, 4)),
                _node_refs(r, t, "forward", index, n, where, count=(2,)),
                _node_refs(r, t, "span", index, n, where, count=(2,)),
                area,
                (lo, hi),
            )
        )

    driven = {s.actuator for s in springs if s.actuator} | {f.actuator for f in fins}
    for a in actuators:
        if a.name not in driven:
            what = "muscle" if a.kind == "muscle" else "fin"
            raise r.fail(f"actuator {a.name!r}", f"actuator with no {what}")
        if a.kind == "fin" and any(s.actuator == a.name for s in springs):
            raise r.fail(f"actuator {a.name!r}", "a fin actuator cannot drive muscles")
        if a.kind == "muscle" and any(f.actuator == a.name for f in fins):
            raise r.fail(f"actuator {a.name!r}", "a muscle actuator cannot drive a fin")

    wave = None
    if "wave" in doc:
        w = doc["wave"]
        if not isinstance(w, dict):
            raise r.fail("wave", "must be a table")
        phases = w.get("phases", {})
        if not isinstance(phases, dict):
            raise r.fail("wave", "'phases' must be a table of actuator = phase")
        for key in phases:
            if key not in act_names:
                raise r.fail("wave", f"phase for unknown actuator {key!r}")
            r.number(phases, key, "wave.phases")
        wave = WaveSpec(
            r.number(w, "frequency", "wave"),
            r.number(w, "amplitude", "wave", default=1.0),
            r.number(w, "offset", "wave", default=0.0),
            {k: float(v) for k, v in phases.items()},
        )

    head = _node_ref(r, doc.get("head", 0), index, n, "top level 'head'")
    forward = r.vector(doc, "forward", "top level", 3) if "forward" in doc else (1.0, 0.0, 0.0)
    if math.hypot(*forward) < 1e-9:
        raise r.fail("top level", "'forward' must be a non-zero vector")
    start = r.vector(doc, "start_offset", "top level", 3) if "start_offset" in doc else None
    return AnimalSpec(
        start_offset=start or (0.0, 0.0, 0.0),
        name=name,
        description=str(doc.get("description", "")),
        medium=medium,
        dt=dt,
        head=head,
        forward=forward,
        nodes=tuple(nodes),
        springs=tuple(springs),
        actuators=tuple(actuators),
        faces=tuple(faces),
        fins=tuple(fins),
        wave=wave,
        source=source,
    )


def read_animal_file(path: str | Path) -> AnimalSpec:
    """Return the AnimalSpec in the TOML file at ``path``."""
    from zoetic.io import read_toml

    path = Path(path)
    try:
        doc = read_toml(path, what="animal file")
    except BodyError:
        raise
    except Exception as exc:  # ZoeticError from io: re-raise as BodyError for one family
        raise BodyError(str(exc)) from None
    return parse_animal(doc, source=str(path))
