"""Animal files (TOML) parsed into plain specs, with errors that name the file and the entry."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from zoetic.errors import BodyError
from zoetic.io import LIMITS, Table, abbrev, check_keys, load_toml, suggest

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
class EyesSpec:
    """Two eyes riding on a node: the left eye's offset from it (m) along the rest pose's
    forward, up and left axes (the right eye mirrored across left), the widest level's field
    of view (degrees), the number of levels (field of view halving per level), and the pixels
    along each side of a component image."""

    node: int
    offset: tuple[float, float, float]
    fov: float
    levels: int
    pixels: int


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
    # each face's drag coefficient, a factor on the medium's water coefficient (default 1)
    face_drag: tuple[float, ...] | None = None
    wave: WaveSpec | None = None
    start_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    eyes: EyesSpec | None = None
    source: str = "<memory>"
    extra: dict[str, Any] = field(default_factory=dict)


def _node_ref(r: Table, ref: Any, index: dict[str, int], n: int, what: str) -> int:
    if isinstance(ref, bool):
        raise r.fail(f"{what}: unknown node {ref!r}")
    if isinstance(ref, int):
        if 0 <= ref < n:
            return ref
        raise r.fail(f"{what}: unknown node {ref} (the animal has nodes 0..{n - 1})")
    if isinstance(ref, str) and ref in index:
        return index[ref]
    raise r.fail(f"{what}: unknown node {abbrev(ref, 40)}{suggest(str(ref), index)}")


def _node_refs(r: Table, key: str, index, n: int, count=None) -> tuple[int, ...]:
    refs = r.raw(key)
    if not isinstance(refs, list) or (count is not None and len(refs) not in count):
        want = " or ".join(str(c) for c in count) if count else "some"
        raise r.fail(f"{key!r} must list {want} nodes, got {abbrev(refs)}")
    return tuple(_node_ref(r, ref, index, n, repr(key)) for ref in refs)


MAX_COORD = 1e4  # m: no animal is larger; bigger numbers would overflow in the physics


def _vector(r: Table, key: str, n: int) -> tuple[float, ...]:
    out = tuple(r.numbers(key, size=n))
    if any(abs(v) > MAX_COORD for v in out):
        raise r.fail(f"{key} = {abbrev(list(out))} is out of range (at most {MAX_COORD:g} m)")
    return out


MAX_EYE_LEVELS = 8  # the fovea's field of view is the widest level's / 2**(levels - 1)
MAX_EYE_PIXELS = 1024


def _eyes(top: Table, source: str, index: dict[str, int], n: int) -> EyesSpec:
    e = top.table("eyes")
    e.where = f"{source}: [eyes]"
    node = _node_ref(e, e.raw("node"), index, n, "'node'")
    offset = _vector(e, "offset", 3)
    fov = e.number("fov", positive=True)
    if fov >= 180.0:
        raise e.fail(f"'fov' = {fov:g} degrees must be below 180")
    levels = e.integer("levels", lo=1, hi=MAX_EYE_LEVELS)
    pixels = e.integer("pixels", lo=2, hi=MAX_EYE_PIXELS)
    e.finish()
    return EyesSpec(node, offset, fov, levels, pixels)


TOP_KEYS = ("name", "description", "medium", "dt", "defaults", "nodes", "springs",
            "actuators", "faces", "fins", "wave", "head", "forward", "start_offset", "eyes")


@dataclass(frozen=True)
class _Defaults:
    node_damping: float
    stiffness: float
    spring_damping: float


def parse_animal(doc: dict[str, Any], source: str = "<memory>") -> AnimalSpec:
    """Return the AnimalSpec described by a parsed TOML document; raise BodyError if malformed.

    Strict: unknown keys are refused (with a suggestion), numbers must be finite, and the
    counts of nodes, springs and actuators are bounded (``zoetic.reader.LIMITS``).
    """
    top = Table(doc, source, BodyError)
    check_keys(doc, TOP_KEYS, f"{source}: top level", BodyError)
    top.where = f"{source}: top level"
    name = top.string("name")
    medium = top.string("medium", choices=MEDIA)
    dt = top.number("dt", 0.005, positive=True)
    if dt < LIMITS.min_dt:
        raise top.fail(f"'dt' = {dt:g} s is below the smallest allowed ({LIMITS.min_dt:g} s)")
    defaults = _defaults(top, source)
    nodes, index = _nodes(top, source, defaults)
    n = len(nodes)
    actuators = _actuators(top, source)
    act_names = {a.name for a in actuators}
    springs = tuple(_springs(top, source, nodes, index, act_names, defaults))
    faces, face_drag = _faces(top, source, index, n)
    fins = _fins(top, source, index, n, act_names)
    _check_driven(source, actuators, springs, fins)
    wave = _wave(top, source, act_names) if "wave" in doc else None
    head = _node_ref(top, top.raw("head", 0), index, n, "'head'")
    eyes = _eyes(top, source, index, n) if "eyes" in doc else None
    forward = _vector(top, "forward", 3) if "forward" in doc else (1.0, 0.0, 0.0)
    if math.hypot(*forward) < 1e-9:
        raise top.fail("'forward' must be a non-zero vector")
    start = _vector(top, "start_offset", 3) if "start_offset" in doc else None
    description = top.raw("description", "")
    if not isinstance(description, str):
        raise top.fail(f"'description' must be a string, got {abbrev(description)}")
    return AnimalSpec(
        start_offset=start or (0.0, 0.0, 0.0),
        name=name,
        description=description,
        medium=medium,
        dt=dt,
        head=head,
        forward=forward,
        nodes=nodes,
        springs=springs,
        actuators=actuators,
        faces=faces,
        face_drag=face_drag,
        fins=fins,
        wave=wave,
        eyes=eyes,
        source=source,
    )


def _defaults(top: Table, source: str) -> _Defaults:
    """Return the file's [defaults] for nodes and springs."""
    defaults = top.table("defaults")
    defaults.where = f"{source}: [defaults]"
    out = _Defaults(
        node_damping=defaults.number("node_damping", 0.0),
        stiffness=defaults.number("stiffness", 0.0),
        spring_damping=defaults.number("spring_damping", 0.0),
    )
    defaults.finish()
    return out


def _nodes(top: Table, source: str, defaults: _Defaults):
    """Return the [[nodes]] as NodeSpecs and each node's index by name."""
    nodes: list[NodeSpec] = []
    index: dict[str, int] = {}
    for k, raw in enumerate(top.tables("nodes", LIMITS.nodes)):
        t = Table(raw, f"{source}: nodes[{k}]", BodyError)
        nm = t.string("name", str(k))
        t.where = f"{source}: node {nm!r} (nodes[{k}])"
        if nm in index:
            raise t.fail(f"duplicate node name {nm!r}; rename one")
        mass = t.number("mass", positive=True)
        damping = t.number("damping", defaults.node_damping, lo=0.0)
        pos = _vector(t, "pos", 3)
        t.finish()
        index[nm] = k
        nodes.append(NodeSpec(nm, pos, mass, damping))
    if len(nodes) < 2:
        raise BodyError(f"{source}: [[nodes]]: an animal needs at least 2 nodes, got {len(nodes)}")
    return tuple(nodes), index


def _actuators(top: Table, source: str) -> tuple[ActuatorSpec, ...]:
    """Return the [[actuators]], each mirror naming an actuator."""
    actuators: list[ActuatorSpec] = []
    act_names: set[str] = set()
    for k, raw in enumerate(top.tables("actuators", LIMITS.actuators)):
        t = Table(raw, f"{source}: actuators[{k}]", BodyError)
        nm = t.string("name")
        t.where = f"{source}: actuator {nm!r}"
        if nm in act_names:
            raise t.fail("duplicate actuator name; rename one")
        kind = t.string("kind", "muscle", choices=ACTUATOR_KINDS)
        side = t.string("side", "center", choices=SIDES)
        mirror = t.raw("mirror", None)
        if mirror is not None and not isinstance(mirror, str):
            raise t.fail(f"'mirror' must be an actuator name, got {abbrev(mirror)}")
        t.finish()
        act_names.add(nm)
        actuators.append(ActuatorSpec(nm, kind, side, mirror))
    for a in actuators:
        if a.mirror is not None and a.mirror not in act_names:
            raise BodyError(
                f"{source}: actuator {a.name!r}: mirror {a.mirror!r} is not an actuator"
                f"{suggest(a.mirror, act_names)}"
            )
    return tuple(actuators)


def _springs(top, source, nodes, index, act_names, defaults: _Defaults):
    """Yield the [[springs]] as SpringSpecs (no two on the same pair of nodes)."""
    n = len(nodes)
    seen: dict[tuple[int, int], int] = {}
    for k, raw in enumerate(top.tables("springs", LIMITS.springs)):
        t = Table(raw, f"{source}: springs[{k}]", BodyError)
        a, b = _node_refs(t, "nodes", index, n, count=(2,))
        t.where = f"{source}: springs[{k}] ({nodes[a].name}-{nodes[b].name})"
        if a == b:
            raise t.fail("a spring must join two different nodes")
        key = (min(a, b), max(a, b))
        if key in seen:
            raise t.fail(f"duplicate spring (same nodes as springs[{seen[key]}]); remove one")
        seen[key] = k
        stiffness = t.number("stiffness", defaults.stiffness)
        if stiffness <= 0:
            raise t.fail(f"stiffness must be positive, got {stiffness:g}")
        damping = t.number("damping", defaults.spring_damping, lo=0.0)
        length = t.number("length") if "length" in t else None
        relaxed = math.dist(nodes[a].pos, nodes[b].pos) if length is None else length
        if relaxed <= 1e-9:
            raise t.fail(f"zero-length spring (relaxed length {relaxed:g})")
        actuator = t.raw("actuator", None)
        kind = t.string("kind", "muscle" if actuator else "structural")
        max_short, contracted = _muscle(t, actuator, act_names, relaxed)
        t.finish()
        yield SpringSpec(a, b, stiffness, damping, length, kind, actuator, max_short, contracted)


def _muscle(t: Table, actuator, act_names, relaxed: float):
    """Return a spring's (max_shortening, contracted length), both None for a passive one."""
    if actuator is None:
        t.used.update(("contracted_length", "max_shortening"))
        if "contracted_length" in t or "max_shortening" in t:
            raise t.fail("'max_shortening'/'contracted_length' need an 'actuator'")
        return None, None
    if not isinstance(actuator, str) or actuator not in act_names:
        raise t.fail(f"unknown actuator {abbrev(actuator, 40)}{suggest(str(actuator), act_names)}")
    max_short = None
    if "contracted_length" in t:
        contracted = t.number("contracted_length")
    elif "max_shortening" in t:
        max_short = t.number("max_shortening")
        contracted = (1.0 - max_short) * relaxed
    else:
        raise t.fail("a muscle needs 'max_shortening' or 'contracted_length'")
    if not contracted < relaxed:
        raise t.fail(f"contracted length {contracted:g} is not shorter than relaxed {relaxed:g}")
    if contracted <= 0:
        raise t.fail(f"contracted length {contracted:g} must be positive")
    return max_short, contracted


def _faces(top: Table, source: str, index, n: int):
    """Return the [[faces]] (3 or 4 nodes each) and each face's drag coefficient."""
    faces, face_drag = [], []
    for k, raw in enumerate(top.tables("faces", LIMITS.springs)):
        t = Table(raw, f"{source}: faces[{k}]", BodyError)
        refs = _node_refs(t, "nodes", index, n, count=(3, 4))
        if len(set(refs)) != len(refs):
            raise t.fail("a face repeats a node")
        face_drag.append(t.number("drag", 1.0, lo=0.0, hi=10.0))
        t.finish()
        faces.append(refs)
    return tuple(faces), tuple(face_drag)


def _fins(top: Table, source: str, index, n: int, act_names) -> tuple[FinSpec, ...]:
    """Return the [[fins]]."""
    fins = []
    for k, raw in enumerate(top.tables("fins", LIMITS.actuators)):
        t = Table(raw, f"{source}: fins[{k}]", BodyError)
        nm = t.string("name")
        t.where = f"{source}: fin {nm!r}"
        act = t.string("actuator")
        if act not in act_names:
            raise t.fail(f"unknown actuator {act!r}{suggest(act, act_names)}")
        area = t.number("area", positive=True)
        lo, hi = _vector(t, "angle_range", 2)
        if not lo < hi:
            raise t.fail(f"angle_range must be increasing, got [{lo}, {hi}]")
        fin_nodes = _node_refs(t, "nodes", index, n, count=(1, 2, 3, 4))
        fwd = _node_refs(t, "forward", index, n, count=(2,))
        span = _node_refs(t, "span", index, n, count=(2,))
        t.finish()
        fins.append(FinSpec(nm, act, fin_nodes, fwd, span, area, (lo, hi)))
    return tuple(fins)


def _check_driven(source: str, actuators, springs, fins) -> None:
    """Refuse an actuator that drives nothing, or muscles and fins both."""
    driven = {s.actuator for s in springs if s.actuator} | {f.actuator for f in fins}
    for a in actuators:
        where = f"{source}: actuator {a.name!r}"
        if a.name not in driven:
            what = "muscle" if a.kind == "muscle" else "fin"
            raise BodyError(f"{where}: actuator with no {what}; drive it or remove it")
        if a.kind == "fin" and any(s.actuator == a.name for s in springs):
            raise BodyError(f"{where}: a fin actuator cannot drive muscles")
        if a.kind == "muscle" and any(f.actuator == a.name for f in fins):
            raise BodyError(f"{where}: a muscle actuator cannot drive a fin")


def _wave(top: Table, source: str, act_names) -> WaveSpec:
    """Return the file's [wave]: frequency, amplitude, offset and each actuator's phase."""
    w = top.table("wave")
    w.where = f"{source}: [wave]"
    phases_t = w.table("phases")
    phases_t.where = f"{source}: [wave.phases]"
    phases = {}
    for key in phases_t.data:
        if key not in act_names:
            raise phases_t.fail(
                f"phase for unknown actuator {abbrev(key, 40)}{suggest(key, act_names)}"
            )
        phases[key] = phases_t.number(key)
    wave = WaveSpec(
        w.number("frequency", lo=0.0, hi=1e4),
        w.number("amplitude", 1.0),
        w.number("offset", 0.0),
        phases,
    )
    w.finish()
    return wave


def read_animal_file(path: str | Path) -> AnimalSpec:
    """Return the AnimalSpec in the TOML file at ``path`` (read by the strict reader)."""
    path = Path(path)
    doc = load_toml(path, what="animal file", error=BodyError)
    return parse_animal(doc, source=str(path))
