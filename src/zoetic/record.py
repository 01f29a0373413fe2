"""The run record: one file (``record.npz``) per run that says what happened, for every kind of
run (simulate, learn, track, macro, sequence, stunt, aquarium, pursuit, SAN).

One writer (:func:`write_record`) and one reader (:func:`read_record`); the viewer, glTF export
and the plots read runs only through them. The file is a compressed NumPy archive: a JSON
header (``meta``) with names, colours, object geometry, events and the run's figures, and
float32 arrays for what moves. docs/record.md lists every field with its shape and units.
Pure NumPy and JSON, so every layer may use it.
"""

from __future__ import annotations

import io
import json
import os
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from zoetic.errors import RunDirError, ZoeticError
from zoetic.io import LIMITS, atomic_write_bytes

FORMAT = "zoetic-record"
VERSION = 1
FILE = "record.npz"
SHAPES = ("sphere", "box", "cylinder", "point", "strand")
AXES = ("x", "y", "z")
# arrays of motion, which a run that blew up leaves NaN from then on (viewers hold the last
# good frame); every other float array must be finite, and per-period scalars may hold inf
MOTION = ("positions", "translations", "angles", "com")


@dataclass(frozen=True)
class Animal:
    """A deformable animal: its surface's triangles over its nodes, and where the nodes were."""

    name: str  # unique within the record
    species: str  # the body's name (a zoo animal) or the animal file that built it
    faces: np.ndarray  # (F, 3) int32 node indices, counter-clockwise seen from outside
    positions: np.ndarray  # (T, N, 3) float32 m, at the record's times
    mass: np.ndarray  # (N,) float32 kg, node masses (the centre of mass weights)
    color: tuple[int, int, int] | None = None  # RGB 0-255; None: the species' own colour
    actuators: tuple[str, ...] = ()
    activations: np.ndarray | None = None  # (T, A) float32 in [0, 1], the muscles' commands


@dataclass(frozen=True)
class Link:
    """One rigid link of a creature: a mesh in its own frame, moved by a planar pose per frame."""

    name: str
    color: tuple[int, int, int]
    vertices: np.ndarray  # (V, 3) float32 m, in the link's frame
    faces: np.ndarray  # (F, 3) int32
    translations: np.ndarray  # (T, 3) float32 m, the frame's origin
    angles: np.ndarray  # (T,) float32 rad about ``axis``, from +x toward the plane's 2nd axis
    axis: str  # "z": a vertical plane (x forward, y up); "y": a top view (x forward, z left)


@dataclass(frozen=True)
class Creature:
    """A rigid-link creature (a sensor-actuator network's): its links and what drives them."""

    name: str
    links: tuple[Link, ...]
    com: np.ndarray  # (T, 3) float32 m, centre of mass
    actuators: tuple[str, ...] = ()
    activations: np.ndarray | None = None  # (T, A) float32, commands mapped to [0, 1]


@dataclass(frozen=True)
class Thing:
    """A passive object: a ball, food, a rock, seaweed, a wall, a hurdle's part, a target."""

    kind: str  # what it is: ball, food, rock, seaweed, wall, hurdle, target, ...
    name: str
    shape: str  # sphere (size: radius), box (half sizes x, y, z), cylinder (radius, length),
    # point (no size: a marker), strand (radius: a chain of nodes, a dynamic plant's blade)
    size: tuple[float, ...]
    # (T, 3) float32 m where it moves, else (1, 3): its centre; a strand's nodes (T, M, 3)
    positions: np.ndarray
    axis: str = "y"  # a cylinder's long axis
    visible: np.ndarray | None = None  # (T,) bool: present (food not yet eaten); None: always


@dataclass(frozen=True)
class Event:
    """Something that happened: at ``t`` s, ``who`` did ``what`` (eat, catch, ...) ``detail``."""

    t: float
    who: str
    what: str
    detail: str = ""


@dataclass(frozen=True)
class Record:
    """What a run recorded: animals, creatures and objects at ``times``, events, and per
    control period the scalars of each animal (E, speed, depth, intentions, gaze, ...)."""

    kind: str  # the command: simulate, learn, track, macro, sequence, stunt, aquarium, ...
    title: str
    medium: str  # ground, water, sea, vacuum
    times: np.ndarray  # (T,) float64 s
    animals: tuple[Animal, ...] = ()
    creatures: tuple[Creature, ...] = ()
    objects: tuple[Thing, ...] = ()
    events: tuple[Event, ...] = ()
    period_times: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (P,) float64 s
    scalars: dict = field(default_factory=dict)  # who -> quantity -> (P, ...) float32
    labels: dict = field(default_factory=dict)  # quantity -> names of its integer codes
    units: dict = field(default_factory=dict)  # quantity -> unit ("m", "m/s", "rad", "")
    numbers: dict = field(default_factory=dict)  # the run's figures (JSON values)
    history: dict = field(default_factory=dict)  # quantity -> (K,) float32 per evaluation


def _rgb(color) -> list[int] | None:
    return None if color is None else [int(c) for c in color]


def _arrays(rec: Record) -> dict[str, np.ndarray]:
    """Return the record's arrays under their archive names (docs/record.md)."""
    out = {
        "times": np.asarray(rec.times, np.float64),
        "period_times": np.asarray(rec.period_times, np.float64),
    }
    for i, a in enumerate(rec.animals):
        out[f"animal/{i}/faces"] = np.asarray(a.faces, np.int32)
        out[f"animal/{i}/positions"] = np.asarray(a.positions, np.float32)
        out[f"animal/{i}/mass"] = np.asarray(a.mass, np.float32)
        if a.activations is not None:
            out[f"animal/{i}/activations"] = np.asarray(a.activations, np.float32)
    for i, c in enumerate(rec.creatures):
        out[f"creature/{i}/com"] = np.asarray(c.com, np.float32)
        if c.activations is not None:
            out[f"creature/{i}/activations"] = np.asarray(c.activations, np.float32)
        for j, ln in enumerate(c.links):
            for key in ("vertices", "translations", "angles"):
                out[f"creature/{i}/link/{j}/{key}"] = np.asarray(getattr(ln, key), np.float32)
            out[f"creature/{i}/link/{j}/faces"] = np.asarray(ln.faces, np.int32)
    for k, o in enumerate(rec.objects):
        out[f"object/{k}/positions"] = np.asarray(o.positions, np.float32)
        if o.visible is not None:
            out[f"object/{k}/visible"] = np.asarray(o.visible, bool)
    for who, quantities in rec.scalars.items():
        for what, values in quantities.items():
            out[f"scalar/{who}/{what}"] = np.asarray(values, np.float32)
    for what, values in rec.history.items():
        out[f"history/{what}"] = np.asarray(values, np.float32)
    return out


def _meta(rec: Record) -> dict:
    """Return the record's JSON header: everything but the arrays."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "kind": rec.kind,
        "title": rec.title,
        "medium": rec.medium,
        "animals": [
            {
                "name": a.name,
                "species": a.species,
                "color": _rgb(a.color),
                "actuators": list(a.actuators),
            }
            for a in rec.animals
        ],
        "creatures": [
            {
                "name": c.name,
                "actuators": list(c.actuators),
                "links": [
                    {"name": ln.name, "color": _rgb(ln.color), "axis": ln.axis} for ln in c.links
                ],
            }
            for c in rec.creatures
        ],
        "objects": [
            {
                "kind": o.kind,
                "name": o.name,
                "shape": o.shape,
                "size": [float(s) for s in o.size],
                "axis": o.axis,
            }
            for o in rec.objects
        ],
        "events": [[float(e.t), str(e.who), str(e.what), str(e.detail)] for e in rec.events],
        "scalars": {who: sorted(q) for who, q in rec.scalars.items()},
        "labels": {k: list(v) for k, v in rec.labels.items()},
        "units": dict(rec.units),
        "numbers": rec.numbers,
        "history": sorted(rec.history),
    }


def write_record(path: str | os.PathLike, rec: Record) -> Path:
    """Write the record to ``path`` (a run directory, or a file), atomically; returns the file.

    The record is checked as the reader checks it, so a written record always reads back.
    """
    path = Path(path)
    if path.is_dir() or not path.suffix:
        path = path / FILE
    arrays = _arrays(rec)
    meta = _meta(rec)
    text = json.dumps(meta, separators=(",", ":"), allow_nan=False)
    _build(meta, arrays, str(path))  # the reader's checks: refuse to write what cannot be read
    buf = io.BytesIO()
    np.savez_compressed(buf, meta=np.frombuffer(text.encode(), np.uint8), **arrays)
    return atomic_write_bytes(path, buf.getvalue())


class _Check:
    """Checks on one record file; every failure is a RunDirError naming the file."""

    def __init__(self, where: str, arrays: dict[str, np.ndarray]) -> None:
        self.where, self.arrays = where, arrays

    def fail(self, what: str) -> RunDirError:
        return RunDirError(f"{self.where}: {what}; not a zoetic run record, or a damaged one")

    def array(self, key: str, shape: tuple, kind: str = "f", optional: bool = False):
        """Return the array ``key`` checked against ``shape`` (None: any size) and its kind."""
        if key not in self.arrays:
            if optional:
                return None
            raise self.fail(f"no array {key!r}")
        a = self.arrays[key]
        if a.dtype.kind not in kind:
            raise self.fail(f"{key} has dtype {a.dtype}, expected {kind!r}")
        if a.ndim != len(shape) or any(
            s is not None and s != n for s, n in zip(shape, a.shape, strict=True)
        ):
            want = "(" + ", ".join("?" if s is None else str(s) for s in shape) + ")"
            raise self.fail(f"{key} has shape {a.shape}, expected {want}")
        checked = a.dtype.kind == "f" and not key.startswith("scalar/")
        if checked and not key.endswith(MOTION) and not np.isfinite(a).all():
            raise self.fail(f"{key} holds non-finite values")
        return a

    def faces(self, key: str, n: int) -> np.ndarray:
        """Return the triangles ``key`` checked to index ``n`` vertices."""
        f = self.array(key, (None, 3), "iu")
        if f.size and (f.min() < 0 or f.max() >= n):
            raise self.fail(f"{key} indexes vertices outside 0..{n - 1}")
        return f.astype(np.int64)

    def entry(self, d, keys: tuple[str, ...], what: str) -> dict:
        if not isinstance(d, dict) or not set(keys) <= set(d):
            raise self.fail(f"{what} needs {', '.join(keys)}")
        return d


def _color(c, check: _Check, what: str):
    if c is None:
        return None
    if not isinstance(c, list) or len(c) != 3 or not all(isinstance(v, int) for v in c):
        raise check.fail(f"{what}: color must be three integers 0..255")
    return tuple(c)


def _animals(meta: dict, ck: _Check, t: int) -> tuple[Animal, ...]:
    out = []
    for i, d in enumerate(meta["animals"]):
        d = ck.entry(d, ("name", "species", "color", "actuators"), f"animals[{i}]")
        pos = ck.array(f"animal/{i}/positions", (t, None, 3))
        n = pos.shape[1]
        acts = ck.array(f"animal/{i}/activations", (t, len(d["actuators"])), optional=True)
        out.append(
            Animal(
                str(d["name"]),
                str(d["species"]),
                ck.faces(f"animal/{i}/faces", n),
                pos,
                ck.array(f"animal/{i}/mass", (n,)),
                _color(d["color"], ck, f"animals[{i}]"),
                tuple(map(str, d["actuators"])),
                acts,
            )
        )
    return tuple(out)


def _creatures(meta: dict, ck: _Check, t: int) -> tuple[Creature, ...]:
    out = []
    for i, d in enumerate(meta["creatures"]):
        d = ck.entry(d, ("name", "actuators", "links"), f"creatures[{i}]")
        links = []
        for j, ln in enumerate(d["links"]):
            ln = ck.entry(ln, ("name", "color", "axis"), f"creatures[{i}].links[{j}]")
            if ln["axis"] not in ("y", "z"):
                raise ck.fail(f"creatures[{i}].links[{j}]: axis must be 'y' or 'z'")
            key = f"creature/{i}/link/{j}"
            verts = ck.array(f"{key}/vertices", (None, 3))
            links.append(
                Link(
                    str(ln["name"]),
                    _color(ln["color"], ck, key),
                    verts,
                    ck.faces(f"{key}/faces", len(verts)),
                    ck.array(f"{key}/translations", (t, 3)),
                    ck.array(f"{key}/angles", (t,)),
                    ln["axis"],
                )
            )
        acts = ck.array(f"creature/{i}/activations", (t, len(d["actuators"])), optional=True)
        out.append(
            Creature(
                str(d["name"]),
                tuple(links),
                ck.array(f"creature/{i}/com", (t, 3)),
                tuple(map(str, d["actuators"])),
                acts,
            )
        )
    return tuple(out)


def _objects(meta: dict, ck: _Check, t: int) -> tuple[Thing, ...]:
    out = []
    sizes = {"sphere": 1, "box": 3, "cylinder": 2, "point": 0, "strand": 1}
    for k, d in enumerate(meta["objects"]):
        d = ck.entry(d, ("kind", "name", "shape", "size", "axis"), f"objects[{k}]")
        if d["shape"] not in SHAPES or d["axis"] not in AXES:
            raise ck.fail(f"objects[{k}]: shape must be one of {SHAPES}, axis one of {AXES}")
        size = d["size"]
        if (
            not isinstance(size, list)
            or len(size) != sizes[d["shape"]]
            or not all(isinstance(s, int | float) and np.isfinite(s) and s > 0 for s in size)
        ):
            raise ck.fail(f"objects[{k}]: a {d['shape']} needs {sizes[d['shape']]} positive sizes")
        chain = d["shape"] == "strand"
        pos = ck.array(f"object/{k}/positions", (None, None, 3) if chain else (None, 3))
        if len(pos) not in (1, t):
            raise ck.fail(f"object/{k}/positions has {len(pos)} rows, expected 1 or {t}")
        vis = ck.array(f"object/{k}/visible", (t,), "b", optional=True)
        out.append(
            Thing(
                str(d["kind"]),
                str(d["name"]),
                d["shape"],
                tuple(float(s) for s in size),
                pos,
                d["axis"],
                vis,
            )
        )
    return tuple(out)


def _scalars(meta: dict, ck: _Check, p: int) -> dict:
    if not isinstance(meta["scalars"], dict):
        raise ck.fail("scalars must be a table")
    out: dict = {}
    for who, names in meta["scalars"].items():
        if not isinstance(names, list):
            raise ck.fail(f"scalars[{who!r}] must list quantities")
        out[who] = {}
        for what in names:
            a = ck.arrays.get(f"scalar/{who}/{what}")
            if a is None or a.ndim < 1 or len(a) != p or a.dtype.kind != "f":
                raise ck.fail(f"scalar/{who}/{what} must be float with {p} rows")
            out[who][what] = a
    return out


def _history(meta: dict, ck: _Check) -> dict:
    """Return a search's progress per evaluation (optional: records before it have none)."""
    names = meta.get("history", [])
    if not isinstance(names, list):
        raise ck.fail("history must list quantities")
    out = {}
    for what in names:
        a = ck.arrays.get(f"history/{what}")
        if a is None or a.ndim != 1 or a.dtype.kind != "f":
            raise ck.fail(f"history/{what} must be a float array (K,)")
        out[str(what)] = a
    return out


def _events(meta: dict, ck: _Check) -> tuple[Event, ...]:
    out = []
    for e in meta["events"]:
        if not (
            isinstance(e, list)
            and len(e) == 4
            and isinstance(e[0], int | float)
            and all(isinstance(v, str) for v in e[1:])
        ):
            raise ck.fail(f"an event must be [t, who, what, detail], got {str(e)[:60]}")
        out.append(Event(float(e[0]), *e[1:]))
    return tuple(out)


def _build(meta, arrays: dict[str, np.ndarray], where: str) -> Record:
    """Return the Record that a header and arrays describe, every field checked."""
    ck = _Check(where, arrays)
    keys = (
        "format",
        "version",
        "kind",
        "title",
        "medium",
        "animals",
        "creatures",
        "objects",
        "events",
        "scalars",
        "labels",
        "units",
        "numbers",
    )
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise ck.fail("its header does not say format = 'zoetic-record'")
    if meta.get("version") != VERSION:
        raise RunDirError(
            f"{where}: record version {meta.get('version')!r}; this zoetic reads "
            f"version {VERSION} (run the command again to write it)"
        )
    ck.entry(meta, keys, "the header")
    for key in ("animals", "creatures", "objects", "events"):
        if not isinstance(meta[key], list):
            raise ck.fail(f"{key} must be a list")
    times = ck.array("times", (None,))
    if len(times) < 1 or not np.isfinite(times).all() or np.any(np.diff(times) < 0):
        raise ck.fail("times must be finite, non-decreasing and not empty")
    period = ck.array("period_times", (None,))
    return Record(
        str(meta["kind"]),
        str(meta["title"]),
        str(meta["medium"]),
        times,
        _animals(meta, ck, len(times)),
        _creatures(meta, ck, len(times)),
        _objects(meta, ck, len(times)),
        _events(meta, ck),
        period,
        _scalars(meta, ck, len(period)),
        dict(meta["labels"]),
        dict(meta["units"]),
        dict(meta["numbers"]),
        _history(meta, ck),
    )


def _load(path: Path) -> tuple[dict, dict[str, np.ndarray]]:
    """Return the header and arrays of a record file, refusing what is not one."""
    try:
        with zipfile.ZipFile(path) as zf:
            total = sum(i.file_size for i in zf.infolist())
        if total > LIMITS.memory_bytes:  # checked before anything is decompressed
            raise RunDirError(
                f"{path}: {total / 2**20:.0f} MiB of arrays, more than a run "
                f"record may hold ({LIMITS.memory_bytes / 2**20:.0f} MiB)"
            )
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except RunDirError:
        raise
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError) as exc:
        raise RunDirError(f"{path}: not a readable run record ({exc})") from None
    raw = arrays.pop("meta", None)
    if raw is None or raw.dtype != np.uint8 or raw.ndim != 1 or raw.size > LIMITS.file_bytes:
        raise RunDirError(f"{path}: no record header; not a zoetic run record")
    try:
        meta = json.loads(raw.tobytes().decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise RunDirError(f"{path}: a damaged record header ({exc})") from None
    return meta, arrays


def read_record(path: str | os.PathLike) -> Record:
    """Return the Record in ``path`` (a run directory or its record.npz), every field checked.

    A missing, foreign or damaged file is a RunDirError that names it.
    """
    path = Path(path)
    if path.is_dir():
        path = path / FILE
    if not path.is_file():
        raise RunDirError(
            f"{path}: no run record; views and exports come from runs of "
            "simulate, learn, track, macro, sequence, stunt, aquarium, pursue "
            "and san (run the command again to write one)"
        )
    meta, arrays = _load(path)
    try:
        return _build(meta, arrays, str(path))
    except ZoeticError:
        raise
    except (TypeError, ValueError, KeyError, AttributeError) as exc:
        raise RunDirError(f"{path}: a malformed run record ({exc})") from None
