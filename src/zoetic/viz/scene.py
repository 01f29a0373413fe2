"""A run's record as a scene to look at: animals' surfaces, creatures' links and objects at
evenly spaced frame times, in the run's medium.

The glTF exporter (``viz.gltf``) and the web viewer (``viz.viewer``, ``zoetic.web``) both
start from a Scene, and a Scene comes only from the run record (``zoetic.record``), so every
kind of run (simulate, learn, track, macro, sequence, stunt, aquarium, pursuit, SAN) opens
alike.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from zoetic.errors import RunDirError
from zoetic.physics import Medium, get_medium
from zoetic.record import Creature, Event, Link, Record, Thing, read_record
from zoetic.render.skin import Skin, record_skin
from zoetic.viz.render3d import name_color

__all__ = ["Animal", "Creature", "Event", "Link", "Scene", "Thing", "load_scene", "scene_of"]


@dataclass(frozen=True)
class Animal:
    """One animal of a scene: its surface and its recorded motion at the scene's frame times."""

    name: str
    color: tuple[int, int, int]
    faces: np.ndarray  # (F, 3) int triangles, counter-clockwise seen from outside
    positions: np.ndarray  # (R, N, 3) float32 m
    com: np.ndarray  # (R, 3) float32 m, centre of mass
    actuators: tuple[str, ...] = ()
    activations: np.ndarray | None = None  # (R, A) in [0, 1], the controller at each frame
    skin: Skin | None = None  # the display surface over the nodes (render.skin)


@dataclass(frozen=True)
class Scene:
    """What a viewer shows: animals, creatures and objects at frame times ``times`` (R,)."""

    title: str
    kind: str  # the command that made the run: simulate, learn, track, aquarium, ...
    times: np.ndarray  # (R,) s, evenly spaced at ``fps``
    fps: float
    medium: Medium
    animals: tuple[Animal, ...]
    objects: tuple[Thing, ...] = ()  # positions (R, 3) where they move, else (1, 3)
    numbers: dict = field(default_factory=dict)  # run figures shown beside the view
    creatures: tuple[Creature, ...] = ()
    events: tuple[Event, ...] = ()  # what happened and when (s from the record's start)
    states: dict = field(default_factory=dict)  # who -> quantity -> (R,) label names per frame

    @property
    def movers(self) -> tuple:
        """Return the animals and the creatures: each has a name, com, actuators, activations."""
        return tuple(self.animals) + tuple(self.creatures)

    @property
    def duration(self) -> float:
        """Return the scene's length in seconds."""
        return float(self.times[-1] - self.times[0]) if len(self.times) else 0.0


def _frames(times: np.ndarray, fps: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return frame times at ``fps`` over ``times``, the record row before each, and the
    fraction of the way to the next row (linear interpolation weights)."""
    n = int(np.floor((times[-1] - times[0]) * fps + 1e-6)) + 1
    t_new = times[0] + np.arange(n) / fps
    if len(times) == 1:
        return t_new, np.zeros(n, int), np.zeros(n)
    i = np.clip(np.searchsorted(times, t_new, side="right") - 1, 0, len(times) - 2)
    frac = np.clip((t_new - times[i]) / np.maximum(times[i + 1] - times[i], 1e-12), 0, 1)
    return t_new, i, frac


def _lerp(a: np.ndarray | None, i: np.ndarray, frac: np.ndarray) -> np.ndarray | None:
    """Return rows of ``a`` (T, ...) interpolated at frames (row ``i``, fraction ``frac``)."""
    if a is None:
        return None
    a = np.asarray(a)
    if len(a) == 1:
        return np.repeat(a, len(i), axis=0)
    f = frac.reshape((-1,) + (1,) * (a.ndim - 1))
    j = np.minimum(i + 1, len(a) - 1)
    return (a[i] * (1 - f) + a[j] * f).astype(np.float32)


def _travelled(com: np.ndarray) -> float:
    good = com[np.isfinite(com).all(axis=1)]
    return float(np.linalg.norm(good[-1, [0, 2]] - good[0, [0, 2]])) if len(good) else 0.0


def _link(ln: Link, i: np.ndarray, frac: np.ndarray) -> Link:
    angles = np.unwrap(np.asarray(ln.angles, float))
    return Link(
        ln.name,
        ln.color,
        ln.vertices,
        ln.faces,
        _lerp(ln.translations, i, frac),
        _lerp(angles, i, frac),
        ln.axis,
    )


def period_index(rec: Record, frame_times: np.ndarray) -> np.ndarray:
    """Return, for each time (s, the record's clock), the control period running then: the
    last that began by it (0 before the first)."""
    k = np.searchsorted(rec.period_times, np.asarray(frame_times) + 1e-9, side="right") - 1
    return np.clip(k, 0, max(len(rec.period_times) - 1, 0))


def _states(rec: Record, frame_times: np.ndarray) -> dict:
    """Return each animal's named states (an intention: the labels of integer-coded per-period
    scalars) at the frames, as held since the last control period began."""
    if not len(rec.period_times):
        return {}
    k = period_index(rec, frame_times)
    out: dict = {}
    for who, quantities in rec.scalars.items():
        for what, values in quantities.items():
            names = rec.labels.get(what)
            if names and np.ndim(values) == 1:
                codes = np.clip(np.nan_to_num(values[k]).astype(int), 0, len(names) - 1)
                out.setdefault(who, {})[what] = [str(names[c]) for c in codes]
    return out


def scene_of(rec: Record, fps: float = 30.0) -> Scene:
    """Return the Scene of a record, its motion resampled at ``fps`` frames per second."""
    times = np.asarray(rec.times, float)
    t_new, i, frac = _frames(times, fps)
    near = np.clip(np.searchsorted(times, t_new + 1e-9, side="right") - 1, 0, len(times) - 1)
    animals = []
    for a in rec.animals:
        pos = _lerp(a.positions, i, frac)
        com = np.einsum("rnk,n->rk", pos, np.asarray(a.mass, float) / float(np.sum(a.mass)))
        act = None if a.activations is None else np.clip(_lerp(a.activations, i, frac), 0, 1)
        animals.append(
            Animal(
                a.name,
                a.color or name_color(a.species),
                np.asarray(a.faces, np.int64),
                pos,
                com.astype(np.float32),
                a.actuators,
                act,
                record_skin(a.name, a.species, a.faces, a.positions[0]),
            )
        )
    creatures = tuple(
        Creature(
            c.name,
            tuple(_link(ln, i, frac) for ln in c.links),
            _lerp(c.com, i, frac),
            c.actuators,
            None if c.activations is None else c.activations[near],
        )
        for c in rec.creatures
    )
    objects = tuple(
        Thing(
            o.kind,
            o.name,
            o.shape,
            o.size,
            _lerp(o.positions, i, frac),
            o.axis,
            None if o.visible is None else o.visible[near],
        )
        for o in rec.objects
    )
    movers = tuple(animals) + creatures
    numbers = dict(rec.numbers)
    if movers and "distance_m" not in numbers:
        numbers["distance_m"] = round(_travelled(movers[0].com), 3)
    t0 = float(t_new[0])
    events = tuple(Event(e.t - t0, e.who, e.what, e.detail) for e in rec.events)
    return Scene(
        rec.title,
        rec.kind,
        t_new - t0,
        float(fps),
        get_medium(rec.medium),
        tuple(animals),
        objects,
        numbers,
        creatures,
        events,
        _states(rec, t_new),
    )


def load_scene(run_dir: str | Path, fps: float = 30.0) -> Scene:
    """Return the Scene of a run directory's record, resampled at ``fps`` frames per second."""
    fps = float(fps)
    if not fps > 0:
        raise RunDirError(f"the frame rate must be positive, got {fps}")
    return scene_of(read_record(run_dir), fps)
