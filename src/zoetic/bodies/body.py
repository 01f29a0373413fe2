"""The compiled animal: immutable arrays the simulators read (the MjModel of zoetic)."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from zoetic.bodies.spec import AnimalSpec
from zoetic.errors import BodyError


def _frozen(a, dtype) -> np.ndarray:
    arr = np.array(a, dtype=dtype)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Body:
    """A spring-mass animal as arrays: N nodes, S springs, A actuators, F triangles, K fins."""

    name: str
    medium: str
    dt: float
    source: str
    node_names: tuple[str, ...]
    mass: np.ndarray  # (N,) kg
    node_damping: np.ndarray  # (N,) N s/m
    rest_pos: np.ndarray  # (N, 3) m
    spring_a: np.ndarray  # (S,) int
    spring_b: np.ndarray  # (S,) int
    stiffness: np.ndarray  # (S,) N/m
    spring_damping: np.ndarray  # (S,) N s/m
    relaxed: np.ndarray  # (S,) m
    contracted: np.ndarray  # (S,) m, equal to relaxed for passive springs
    spring_actuator: np.ndarray  # (S,) int, -1 for passive springs
    spring_kind: tuple[str, ...]
    actuator_names: tuple[str, ...]
    actuator_kind: tuple[str, ...]
    actuator_side: tuple[str, ...]
    actuator_mirror: np.ndarray  # (A,) int: the actuator on the other side (itself if none)
    faces: np.ndarray  # (F, 3) int triangles, counter-clockwise seen from outside (drawing)
    panels: np.ndarray  # (P, 4) int: the file's faces for the water (a triangle repeats c)
    panel_weights: np.ndarray  # (P, 4): each node's share of its panel (1/3 or 1/4, 0 pad)
    panel_drag: np.ndarray  # (P,): each panel's drag coefficient, a factor on the medium's
    fin_nodes: np.ndarray  # (K, 4) int, padded with -1
    fin_forward: np.ndarray  # (K, 2) int: forward axis = x[0] - x[1]
    fin_span: np.ndarray  # (K, 2) int: span axis = x[0] - x[1]
    fin_area: np.ndarray  # (K,) m^2
    fin_angle: np.ndarray  # (K, 2) rad: angle at activation 0 and 1
    fin_actuator: np.ndarray  # (K,) int
    fin_names: tuple[str, ...]
    axis_front: np.ndarray  # (N,) int: neighbour ahead, defines the local body axis
    axis_back: np.ndarray  # (N,) int: neighbour behind
    node_mirror: np.ndarray  # (N,) int: node mirrored through z = 0, -1 if asymmetric
    head: int
    forward: np.ndarray  # (3,) unit heading of the rest pose
    wave_frequency: float
    wave_amplitude: float
    wave_offset: float
    wave_phase: np.ndarray  # (A,) cycles
    wave_held: np.ndarray  # (A,) NaN where the wave drives the actuator, else its held value
    start_offset: np.ndarray  # (3,) m: where the rest pose is placed at the start of a run
    # the file's [eyes] (all None for an animal without eyes): the node they ride on, the left
    # eye's offset (3,) m along forward, up, left (the right eye mirrored), the widest level's
    # field of view (rad), the number of levels (halving per level), pixels per image side
    eye_node: int | None = None
    eye_offset: np.ndarray | None = None
    eye_fov: float | None = None
    eye_levels: int | None = None
    eye_pixels: int | None = None

    @property
    def n_nodes(self) -> int:
        return int(self.mass.shape[0])

    @property
    def n_springs(self) -> int:
        return int(self.stiffness.shape[0])

    @property
    def n_actuators(self) -> int:
        return len(self.actuator_names)

    @property
    def n_muscles(self) -> int:
        return int(np.count_nonzero(self.spring_actuator >= 0))

    @property
    def total_mass(self) -> float:
        return float(self.mass.sum())

    @property
    def length(self) -> float:
        """The animal's length (m) along its forward axis in the rest pose."""
        return float(np.ptp(self.rest_pos @ np.asarray(self.forward, float)))

    @property
    def is_mirror_symmetric(self) -> bool:
        return bool(np.all(self.node_mirror >= 0))

    def with_(self, **changes) -> Body:
        """Return a copy with some arrays replaced (e.g. zero damping for a physics test)."""
        names = {f.name for f in fields(self)}
        unknown = set(changes) - names
        if unknown:
            raise TypeError(f"Body has no field(s) {sorted(unknown)}")
        frozen = {
            k: _frozen(v, np.asarray(getattr(self, k)).dtype)
            if isinstance(getattr(self, k), np.ndarray)
            else v
            for k, v in changes.items()
        }
        return replace(self, **frozen)

    def mirror_actuators(self, activations: np.ndarray) -> np.ndarray:
        """Return activations (..., A) with left and right actuators swapped."""
        return np.asarray(activations)[..., self.actuator_mirror]


def _triangulate(faces) -> np.ndarray:
    tris = []
    for f in faces:
        if len(f) == 3:
            tris.append(f)
        else:
            a, b, c, d = f
            tris.extend([(a, b, c), (a, c, d)])
    return np.array(tris, dtype=np.int64).reshape(-1, 3)


def _panels(faces) -> tuple[np.ndarray, np.ndarray]:
    """Faces as 4-node panels: the normal (c - a) x (d - b) is twice the area times the unit
    normal for a triangle (d = c) and a quad alike, and does not depend on which diagonal a
    triangulation would pick, so mirrored animals feel mirrored water forces."""
    idx = np.zeros((len(faces), 4), dtype=np.int64)
    w = np.zeros((len(faces), 4))
    for k, f in enumerate(faces):
        if len(f) == 3:
            idx[k] = (f[0], f[1], f[2], f[2])
            w[k, :3] = 1.0 / 3.0
        else:
            idx[k] = f
            w[k] = 0.25
    return idx, w


def _local_axes(rest: np.ndarray, sa, sb, forward: np.ndarray):
    n = rest.shape[0]
    proj = rest @ forward
    front = np.arange(n)
    back = np.arange(n)
    best_f = proj.copy()
    best_b = proj.copy()
    for a, b in zip(sa, sb, strict=True):
        for i, j in ((a, b), (b, a)):
            if proj[j] > best_f[i] + 1e-9:
                best_f[i], front[i] = proj[j], j
            if proj[j] < best_b[i] - 1e-9:
                best_b[i], back[i] = proj[j], j
    return front, back


def _node_mirror(rest: np.ndarray) -> np.ndarray:
    mirrored = rest * np.array([1.0, 1.0, -1.0])
    d = np.linalg.norm(rest[None, :, :] - mirrored[:, None, :], axis=-1)
    j = d.argmin(axis=1)
    scale = max(float(np.ptp(rest, axis=0).max()), 1e-9)
    ok = d[np.arange(len(rest)), j] < 1e-6 * scale
    return np.where(ok, j, -1)


def compile_body(spec: AnimalSpec) -> Body:
    """Return the immutable Body arrays for a validated AnimalSpec."""
    rest = np.array([nd.pos for nd in spec.nodes], dtype=np.float64)
    act_index = {a.name: k for k, a in enumerate(spec.actuators)}
    sa = np.array([s.a for s in spec.springs], dtype=np.int64)
    sb = np.array([s.b for s in spec.springs], dtype=np.int64)
    relaxed, contracted = _spring_lengths(spec, rest)
    spring_act = np.array([act_index[s.actuator] if s.actuator else -1 for s in spec.springs])
    mirror = _actuator_mirror(spec, act_index)
    forward = np.array(spec.forward) / np.linalg.norm(spec.forward)
    front, back = _local_axes(rest, sa, sb, forward)
    panels, panel_weights = _panels(spec.faces)
    return Body(
        name=spec.name,
        medium=spec.medium,
        dt=spec.dt,
        source=spec.source,
        node_names=tuple(nd.name for nd in spec.nodes),
        mass=_frozen([nd.mass for nd in spec.nodes], np.float64),
        node_damping=_frozen([nd.damping for nd in spec.nodes], np.float64),
        rest_pos=_frozen(rest, np.float64),
        spring_a=_frozen(sa, np.int64),
        spring_b=_frozen(sb, np.int64),
        stiffness=_frozen([s.stiffness for s in spec.springs], np.float64),
        spring_damping=_frozen([s.damping for s in spec.springs], np.float64),
        relaxed=_frozen(relaxed, np.float64),
        contracted=_frozen(contracted, np.float64),
        spring_actuator=_frozen(spring_act, np.int64),
        spring_kind=tuple(s.kind for s in spec.springs),
        actuator_names=tuple(a.name for a in spec.actuators),
        actuator_kind=tuple(a.kind for a in spec.actuators),
        actuator_side=tuple(a.side for a in spec.actuators),
        actuator_mirror=_frozen(mirror, np.int64),
        faces=_frozen(_triangulate(spec.faces), np.int64),
        panels=_frozen(panels, np.int64),
        panel_weights=_frozen(panel_weights, np.float64),
        panel_drag=_frozen(spec.face_drag or np.ones(len(spec.faces)), np.float64),
        axis_front=_frozen(front, np.int64),
        axis_back=_frozen(back, np.int64),
        node_mirror=_frozen(_node_mirror(rest), np.int64),
        head=spec.head,
        forward=_frozen(forward, np.float64),
        start_offset=_frozen(spec.start_offset, np.float64),
        **_fin_fields(spec, act_index),
        **_wave_fields(spec, act_index),
        **_eye_fields(spec),
    )


def _spring_lengths(spec: AnimalSpec, rest: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return each spring's relaxed length (the file's, else the rest-pose distance) and
    contracted length (the relaxed one for a passive spring)."""
    relaxed = np.array(
        [
            s.length if s.length is not None else float(np.linalg.norm(rest[s.a] - rest[s.b]))
            for s in spec.springs
        ]
    )
    contracted = np.array(
        [
            s.contracted_length if s.contracted_length is not None else relaxed[k]
            for k, s in enumerate(spec.springs)
        ]
    )
    return relaxed, contracted


def _actuator_mirror(spec: AnimalSpec, act_index: dict[str, int]) -> np.ndarray:
    """Return each actuator's mirror (itself if none); refuse a mirror that is not mutual."""
    mirror = np.array(
        [act_index[a.mirror] if a.mirror else k for k, a in enumerate(spec.actuators)],
        dtype=np.int64,
    )
    for k, m in enumerate(mirror):
        if mirror[m] != k:
            raise BodyError(
                f"{spec.source}: actuator {spec.actuators[k].name!r}: mirror "
                f"{spec.actuators[m].name!r} does not name it back as its mirror"
            )
    return mirror


def _fin_fields(spec: AnimalSpec, act_index: dict[str, int]) -> dict:
    """Return the Body's fin arrays (nodes padded with -1 to four)."""
    kf = len(spec.fins)
    fin_nodes = -np.ones((kf, 4), dtype=np.int64)
    for k, f in enumerate(spec.fins):
        fin_nodes[k, : len(f.nodes)] = f.nodes
    return dict(
        fin_nodes=_frozen(fin_nodes, np.int64),
        fin_forward=_frozen([f.forward for f in spec.fins], np.int64).reshape(kf, 2),
        fin_span=_frozen([f.span for f in spec.fins], np.int64).reshape(kf, 2),
        fin_area=_frozen([f.area for f in spec.fins], np.float64),
        fin_angle=_frozen([f.angle_range for f in spec.fins], np.float64).reshape(kf, 2),
        fin_actuator=_frozen([act_index[f.actuator] for f in spec.fins], np.int64),
        fin_names=tuple(f.name for f in spec.fins),
    )


def _wave_fields(spec: AnimalSpec, act_index: dict[str, int]) -> dict:
    """Return the Body's travelling wave: frequency, amplitude, offset, each actuator's phase,
    and the value held by an actuator the wave does not drive."""
    phase = np.zeros(len(spec.actuators))
    wave = spec.wave
    # an actuator missing from [wave].phases is not driven by the wave: a muscle stays relaxed
    # (0) and a fin is held level (the activation of angle 0, clipped to its range)
    held = np.full(len(spec.actuators), np.nan)
    if wave is not None:
        held[:] = 0.0
        for nm, p in wave.phases.items():
            phase[act_index[nm]] = p
            held[act_index[nm]] = np.nan
        for f in spec.fins:
            k = act_index[f.actuator]
            if not np.isnan(held[k]):
                lo, hi = f.angle_range
                held[k] = float(np.clip(-lo / (hi - lo), 0.0, 1.0)) if hi != lo else 0.0
    return dict(
        wave_frequency=wave.frequency if wave else 1.0,
        wave_amplitude=wave.amplitude if wave else 1.0,
        wave_offset=wave.offset if wave else 0.0,
        wave_phase=_frozen(phase, np.float64),
        wave_held=_frozen(held, np.float64),
    )


def _eye_fields(spec: AnimalSpec) -> dict:
    e = spec.eyes
    if e is None:
        return {}
    return dict(
        eye_node=e.node,
        eye_offset=_frozen(e.offset, np.float64),
        eye_fov=float(np.radians(e.fov)),
        eye_levels=e.levels,
        eye_pixels=e.pixels,
    )
