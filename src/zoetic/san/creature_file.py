"""Creature files: read and validate a TOML creature, write one back (``docs/creatures.md``).

Public interface::

    load_creature(name_or_path) -> Creature        zoo name ("cart") or a .toml path
    list_creatures() -> list[str]
    creature_from_dict(data, path=None) -> Creature
    creature_to_toml(c) -> str; save_creature(c, path) -> Path

Every error is a :class:`CreatureError` naming the file, the entry and the problem.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import fields
from pathlib import Path
from typing import Any

from zoetic.io import LIMITS, abbrev, check_keys, is_path, load_toml, suggest
from zoetic.san.creature import (
    _DEG,
    ACTUATOR_KINDS,
    JOINT_KINDS,
    MEDIA,
    METRICS,
    PLANES,
    SENSOR_KINDS,
    SHAPES,
    ZOO_DIR,
    Actuator,
    Creature,
    CreatureError,
    Joint,
    Link,
    Sensor,
    _check_actuator_values,
    _check_range,
    _finite,
)


def list_creatures() -> list[str]:
    """Return the names of the built-in creatures (the zoo)."""
    return sorted(p.stem for p in ZOO_DIR.glob("*.toml"))


def load_creature(name_or_path: str | os.PathLike) -> Creature:
    """Return the creature from the zoo (by name, e.g. "cart") or from a .toml file.

    A bare name always means the zoo entry (a folder ``cart/`` in the working directory does
    not hide it); a file is written as a path (``./cart.toml``, ``runs/x/creature.toml``).
    """
    text_name = str(name_or_path)
    if is_path(text_name):
        path = Path(text_name)
        if not path.exists():
            raise CreatureError(f"{text_name}: no such creature file")
    else:
        path = ZOO_DIR / f"{text_name}.toml"
        if not path.exists():
            here = Path(text_name).exists()
            hint = f" (to use the file {text_name!r} here, write ./{text_name})" if here else ""
            raise CreatureError(
                f"unknown creature {text_name!r}{suggest(text_name, list_creatures())}: not "
                f"in the zoo, which has {', '.join(list_creatures())}{hint}"
            )
    data = load_toml(path, what="creature file", error=CreatureError)
    return creature_from_dict(data, path)


# A creature's simulation may take at most this many physics steps (seconds / dt): the
# planar world steps a few hundred thousand times a second, and a search runs many.
MAX_CREATURE_STEPS = 1_000_000
PAPER_KD_PER_KS = 0.1  # s: "choosing kd/ks = 0.10 provides suitable energetic motions"
MIN_CREATURE_DT = 1e-5


class _Table:
    """Typed access to one TOML table with errors that name the file and the entry."""

    def __init__(self, data: Any, where: str):
        if not isinstance(data, dict):
            raise CreatureError(f"{where}: must be a table")
        self.data, self.where, self.used = data, where, set()

    def err(self, msg: str) -> CreatureError:
        return CreatureError(f"{self.where}: {msg}")

    def has(self, key: str) -> bool:
        return key in self.data or key + "_deg" in self.data

    def str(self, key: str, default: Any = ..., choices: tuple[str, ...] | None = None):
        self.used.add(key)
        if key not in self.data:
            if default is ...:
                raise self.missing(key)
            return default
        val = self.data[key]
        if not isinstance(val, str) or not val:
            raise self.err(f"{key} must be a non-empty string, got {abbrev(val)}")
        if choices is not None and val not in choices:
            raise self.err(
                f"unknown {key} {abbrev(val, 40)}{suggest(val, choices)} (expected one of "
                f"{', '.join(choices)})"
            )
        return val

    def missing(self, key: str) -> CreatureError:
        """The error for a missing required key, pointing at a misspelling of it if any."""
        near = suggest(key, [k for k in self.data if k not in self.used])
        found = f"; found {near[15:-2]} (misspelled?)" if near else ""
        return self.err(f"missing required key {key!r}{found}")

    def num(self, key: str, default: Any = ..., angle: bool = False, per_deg: bool = False):
        """A finite float; ``key_deg`` accepted in degrees when ``angle`` (or per degree)."""
        self.used.update((key, key + "_deg") if angle or per_deg else (key,))
        scale = 1.0
        if (angle or per_deg) and key + "_deg" in self.data:
            if key in self.data:
                raise self.err(f"give {key} or {key}_deg, not both")
            key, scale = key + "_deg", (1.0 / _DEG if per_deg else _DEG)
        if key not in self.data:
            if default is ...:
                raise self.missing(key)
            return default
        return _finite(self.data[key], f"{self.where}: {key}") * scale

    def pair(self, key: str, default: Any = ..., angle: bool = False):
        self.used.update((key, key + "_deg") if angle else (key,))
        scale = 1.0
        if angle and key + "_deg" in self.data:
            if key in self.data:
                raise self.err(f"give {key} or {key}_deg, not both")
            key, scale = key + "_deg", _DEG
        if key not in self.data:
            if default is ...:
                raise self.missing(key)
            return default
        val = self.data[key]
        if not isinstance(val, list) or len(val) != 2:
            raise self.err(f"{key} must be a list of two numbers, got {abbrev(val)}")
        return tuple(_finite(v, f"{self.where}: {key}") * scale for v in val)

    def finish(self) -> None:
        check_keys(self.data, self.used, self.where, CreatureError)


def _entries(data: dict, key: str, where: str) -> list:
    val = data.get(key, [])
    if not isinstance(val, list):
        raise CreatureError(f"{where}: [[{key}]] must be an array of tables")
    if len(val) > LIMITS.links:
        raise CreatureError(f"{where}: {len(val)} [[{key}]] entries (at most {LIMITS.links})")
    return val


def _name(t: _Table, seen: set[str], what: str) -> str:
    name = t.str("name")
    if name in seen:
        raise t.err(f"duplicate {what} name {name!r}")
    seen.add(name)
    t.where = t.where.split(" #")[0] + f" {name!r}"
    return name


def _header(data: dict, src: str) -> dict[str, Any]:
    """Return the Creature's keyword values from the [creature] table."""
    h = _Table(data["creature"], f"{src}: [creature]")
    kw: dict[str, Any] = {}
    kw["name"] = h.str("name")
    kw["metric"] = h.str("metric", "distance", METRICS)
    kw["medium"] = h.str("medium", "ground", MEDIA)
    kw["plane"] = h.str("plane", "vertical", PLANES)
    kw["description"] = h.str("description", "")
    for key in ("seconds", "expected_cycle", "dt", "control_dt"):
        val = h.num(key, None if key == "expected_cycle" else getattr(Creature, key))
        if val is not None and val <= 0:
            raise h.err(f"{key} must be positive, got {val:g}")
        kw[key] = val  # no expected_cycle: derived from the creature (see san.scales.own_scales)
    if kw["dt"] < MIN_CREATURE_DT:
        raise h.err(f"dt = {kw['dt']:g} s is below the smallest allowed ({MIN_CREATURE_DT:g} s)")
    steps = kw["seconds"] / kw["dt"]
    if steps > MAX_CREATURE_STEPS:
        raise h.err(
            f"seconds / dt = {kw['seconds']:g} / {kw['dt']:g} is {steps:,.0f} steps (at most "
            f"{MAX_CREATURE_STEPS:,}); use a shorter time or a larger dt"
        )
    if kw["control_dt"] > kw["seconds"]:
        raise h.err(f"control_dt ({kw['control_dt']:g}) is longer than seconds")
    ratio = kw["control_dt"] / kw["dt"]
    if abs(ratio - round(ratio)) > 1e-6 or round(ratio) < 1:
        raise h.err(f"control_dt ({kw['control_dt']:g}) must be a whole multiple of dt")
    kw["paper_speed"] = h.num("paper_speed_cm_s", None)
    kw["useful_speed"] = h.num("useful_speed_cm_s", None)
    if kw["useful_speed"] is not None and kw["useful_speed"] <= 0:
        raise h.err(f"useful_speed_cm_s must be positive, got {kw['useful_speed']:g}")
    if "hidden" in h.data:
        h.used.add("hidden")
        hid = h.data["hidden"]
        if isinstance(hid, bool) or not isinstance(hid, int) or not 0 <= hid <= LIMITS.links:
            raise h.err(f"hidden must be an integer in [0, {LIMITS.links}], got {abbrev(hid)}")
        kw["hidden"] = hid
    kw["root_angle"] = h.num("root_angle", 0.0, angle=True)
    for key in ("friction", "hop_k", "water_k", "follow_speed", "follow_lead", "rough_height"):
        val = h.num(key, getattr(Creature, key))
        if val < 0:
            raise h.err(f"{key} must be non-negative, got {val:g}")
        kw[key] = val
    if "crawl_friction" in h.data:
        h.used.add("crawl_friction")
        cf = h.data["crawl_friction"]
        if not isinstance(cf, list) or len(cf) != 3:
            raise h.err("crawl_friction must be [forward, backward, lateral]")
        kw["crawl_friction"] = tuple(_finite(v, f"{h.where}: crawl_friction") for v in cf)
        if min(kw["crawl_friction"]) < 0:
            raise h.err("crawl_friction coefficients must be non-negative")
    tilt = h.num("fall_tilt", None, angle=True)
    if tilt is not None and tilt <= 0:
        raise h.err(f"fall_tilt must be positive, got {tilt:g}")
    kw["fall_tilt"] = tilt
    h.used.add("fall_links")
    fl = h.data.get("fall_links", [])
    if not isinstance(fl, list) or not all(isinstance(x, str) for x in fl):
        raise h.err("fall_links must be a list of link names")
    kw["fall_links"] = tuple(fl)
    h.finish()
    return kw


def _links(data: dict, src: str) -> list[Link]:
    """Return the [[link]] entries as Links (at least one)."""
    links, seen = [], set()
    for i, entry in enumerate(_entries(data, "link", src)):
        t = _Table(entry, f"{src}: [[link]] #{i + 1}")
        name = _name(t, seen, "link")
        shape = t.str("shape", choices=SHAPES)
        length = t.num("length", 0.0)
        radius = t.num("radius")
        mass = t.num("mass")
        inertia = t.num("inertia", None)
        depth = t.num("depth", 0.0)
        start = t.num("start", 0.0)
        if mass <= 0:
            raise t.err(f"mass must be positive, got {mass:g}")
        if radius <= 0:
            raise t.err(f"radius must be positive, got {radius:g}")
        if length < 0 or (shape != "sphere" and length <= 0):
            raise t.err(f"length must be positive for a {shape}, got {length:g}")
        if inertia is not None and inertia <= 0:
            raise t.err(f"inertia must be positive, got {inertia:g}")
        if depth < 0:
            raise t.err(f"depth must be non-negative, got {depth:g}")
        t.finish()
        links.append(Link(name, shape, length, radius, mass, inertia, depth, start))
    if not links:
        raise CreatureError(f"{src}: a creature needs at least one [[link]]")
    return links


def _joints(data: dict, src: str, links: list[Link]) -> tuple[list[Joint], str]:
    """Return the [[joint]] entries as Joints, and the root link: they must join the links
    into one tree."""
    link_names = {ln.name for ln in links}
    joints, jseen, has_parent = [], set(), {}
    for i, entry in enumerate(_entries(data, "joint", src)):
        t = _Table(entry, f"{src}: [[joint]] #{i + 1}")
        name = _name(t, jseen | link_names, "joint or link")
        jseen.add(name)
        kind = t.str("kind", choices=JOINT_KINDS)
        parent, child = t.str("parent"), t.str("child")
        for role, ln in (("parent", parent), ("child", child)):
            if ln not in link_names:
                raise t.err(f"{role} link {ln!r} does not exist")
        if child in has_parent:
            raise t.err(f"link {child!r} already has a parent joint ({has_parent[child]!r})")
        if child == parent:
            raise t.err(f"joins link {child!r} to itself")
        has_parent[child] = name
        anchor = t.pair("anchor", (0.0, 0.0))
        angle = t.num("angle", 0.0, angle=True)
        offset = t.num("offset", 0.0)
        rng = t.pair("range", None, angle=(kind == "hinge"))
        if rng is not None:
            _check_range(rng[0], rng[1], t.where + ": range")
        stiffness, damping = t.num("stiffness", 0.0), t.num("damping", 0.0)
        if stiffness < 0 or damping < 0:
            raise t.err("stiffness and damping must be non-negative")
        if kind == "fixed" and (rng is not None or stiffness or damping):
            raise t.err("a fixed joint takes no range, stiffness or damping")
        t.finish()
        joints.append(
            Joint(name, kind, parent, child, anchor, angle, offset, rng, stiffness, damping)
        )
    roots = [ln.name for ln in links if ln.name not in has_parent]
    if len(roots) != 1:
        raise CreatureError(
            f"{src}: the joints must join the links into one tree with a single root; "
            f"links without a parent joint: {', '.join(roots) or 'none (a cycle)'}"
        )
    parent_of = {j.child: j.parent for j in joints}
    for ln in link_names:  # cycle check
        cur, steps = ln, 0
        while cur in parent_of:
            cur, steps = parent_of[cur], steps + 1
            if steps > len(links):
                raise CreatureError(f"{src}: the joints form a cycle through link {ln!r}")
    return joints, roots[0]


def _actuators(data: dict, src: str, joint_by: dict[str, Joint], unset: set[str]) -> list[Actuator]:
    """Return the [[actuator]] entries as Actuators (at least one), one per joint; the names
    of those that give no kd are added to ``unset``."""
    acts, aseen = [], set()
    for i, entry in enumerate(_entries(data, "actuator", src)):
        t = _Table(entry, f"{src}: [[actuator]] #{i + 1}")
        name = _name(t, aseen, "actuator")
        kind = t.str("kind", choices=ACTUATOR_KINDS)
        jn = t.str("joint")
        if jn not in joint_by:
            raise t.err(f"joint {jn!r} does not exist")
        need = "hinge" if kind == "angular" else "slide"
        if joint_by[jn].kind != need:
            raise t.err(f"an {kind} actuator needs a {need} joint; {jn!r} is {joint_by[jn].kind}")
        if jn in {a.joint for a in acts}:
            raise t.err(f"joint {jn!r} already has an actuator")
        ang = kind == "angular"
        lo, hi = t.num("lo", angle=ang), t.num("hi", angle=ang)
        ks = t.num("ks", per_deg=ang)
        kd = t.num("kd", None, per_deg=ang)
        t.finish()
        if kd is None:
            unset.add(name)  # the paper's kd/ks = 0.1 s, or derived (see san.scales.own_scales)
            kd = PAPER_KD_PER_KS * ks
        a = Actuator(name, kind, jn, lo, hi, ks, kd)
        _check_actuator_values(a, t.where)
        acts.append(a)
    if not acts:
        raise CreatureError(
            f"{src}: a creature needs at least one [[actuator]] (a network has nothing to drive)"
        )
    return acts


def _sensors(
    data: dict, src: str, link_names: set[str], joint_by: dict[str, Joint], act_by: dict
) -> list[Sensor]:
    """Return the [[sensor]] entries as Sensors, each on a target of its kind."""
    sens, sseen = [], set()
    for i, entry in enumerate(_entries(data, "sensor", src)):
        t = _Table(entry, f"{src}: [[sensor]] #{i + 1}")
        name = _name(t, sseen, "sensor")
        kind = t.str("kind", choices=SENSOR_KINDS)
        target = t.str("target")
        ang = kind in ("angle", "eye")
        if kind in ("touch", "eye"):
            if target not in link_names:
                raise t.err(f"target link {target!r} does not exist")
        elif kind == "angle":
            if target not in joint_by or joint_by[target].kind != "hinge":
                raise t.err(f"target {target!r} is not a hinge joint")
        else:
            ok = (target in joint_by and joint_by[target].kind == "slide") or (
                target in act_by and act_by[target].kind == "linear"
            )
            if not ok:
                raise t.err(f"target {target!r} is not a slide joint or linear actuator")
        if kind == "touch":
            lo, hi = t.num("lo", -1.0), t.num("hi", 0.002)
        else:
            lo, hi = t.num("lo", angle=ang), t.num("hi", angle=ang)
        at = t.num("at", None) if kind in ("touch", "eye") else None
        t.finish()
        _check_range(lo, hi, t.where)
        sens.append(Sensor(name, kind, target, lo, hi, at))
    return sens


def creature_from_dict(data: dict, path: str | os.PathLike | None = None) -> Creature:
    """Return the validated creature described by parsed TOML ``data`` (from ``path``)."""
    src = str(path) if path is not None else "<creature>"
    top = _Table(data, src)
    top.used.update(("creature", "link", "joint", "sensor", "actuator"))
    top.finish()
    if "creature" not in data:
        raise CreatureError(f"{src}: missing the [creature] table")
    kw = _header(data, src)
    links = _links(data, src)
    link_names = {ln.name for ln in links}
    joints, root = _joints(data, src, links)
    joint_by = {j.name: j for j in joints}
    no_kd: set[str] = set()
    acts = _actuators(data, src, joint_by, no_kd)
    sens = _sensors(data, src, link_names, joint_by, {a.name: a for a in acts})
    for ln in kw["fall_links"]:
        if ln not in link_names:
            raise CreatureError(f"{src}: [creature]: fall link {ln!r} does not exist")
    if kw["metric"] == "follow" and not any(s.kind == "eye" for s in sens):
        raise CreatureError(f"{src}: [creature]: metric 'follow' needs at least one eye sensor")
    # the root link first: the world makes it the planar root
    links.sort(key=lambda ln: ln.name != root)
    own = kw["expected_cycle"] is None
    kw["expected_cycle"] = kw["expected_cycle"] or Creature.expected_cycle
    c = Creature(
        links=tuple(links),
        joints=tuple(joints),
        sensors=tuple(sens),
        actuators=tuple(acts),
        path=Path(path) if path is not None else None,
        **kw,
    )
    if not own:
        return c
    from zoetic.san.scales import own_scales

    return own_scales(c, no_kd)


# ----------------------------------------------------------------------------- saving


def _clean(d: dict) -> dict:
    return {k: v for k, v in d.items() if v is not None}


def creature_to_dict(c: Creature) -> dict:
    """Return the creature as TOML-ready data in SI units (the inverse of loading)."""
    head = {
        f.name: getattr(c, f.name)
        for f in fields(c)
        if f.name
        not in ("links", "joints", "sensors", "actuators", "path", "paper_speed", "useful_speed")
    }
    head["paper_speed_cm_s"] = c.paper_speed
    head["useful_speed_cm_s"] = c.useful_speed
    head["fall_links"] = list(c.fall_links)
    head["crawl_friction"] = list(c.crawl_friction)
    out: dict[str, Any] = {"creature": _clean(head)}
    out["link"] = [_clean(vars(ln).copy()) for ln in c.links]
    joints = []
    for j in c.joints:
        d = _clean(vars(j).copy())
        d["anchor"] = list(j.anchor)
        if j.range is not None:
            d["range"] = list(j.range)
        joints.append(d)
    out["joint"] = joints
    out["sensor"] = [_clean(vars(s).copy()) for s in c.sensors]
    out["actuator"] = [_clean(vars(a).copy()) for a in c.actuators]
    return out


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else ("nan" if v != v else ("inf" if v > 0 else "-inf"))
    if isinstance(v, str):
        return json.dumps(v)  # a JSON string is a TOML basic string
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} to TOML")


def creature_to_toml(c: Creature) -> str:
    """Return the creature as TOML text (SI keys), which :func:`load_creature` reads back."""
    data = creature_to_dict(c)
    lines = [f"# creature {c.name!r}, written by zoetic (SI units: m, kg, s, rad)", "[creature]"]
    lines += [f"{k} = {_toml_value(v)}" for k, v in data["creature"].items()]
    for section in ("link", "joint", "sensor", "actuator"):
        for entry in data[section]:
            lines += ["", f"[[{section}]]"]
            lines += [f"{k} = {_toml_value(v)}" for k, v in entry.items()]
    return "\n".join(lines) + "\n"


def save_creature(c: Creature, path: str | os.PathLike) -> Path:
    """Write the creature to a TOML file (atomically); returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".part")
    tmp.write_text(creature_to_toml(c))
    os.replace(tmp, path)
    return path
