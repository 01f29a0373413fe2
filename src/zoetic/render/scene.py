"""The triangles of a world: animals' deformed surfaces in their own colours, rocks (boxes),
seaweed (upright cylinders) and a checkered seabed, flat-shaded by one light from above; and
the shapes of a record's objects and plant strands (``solid``, ``strand_tube``)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from zoetic.bodies import Body
from zoetic.physics.objects import Ball, Box, Cylinder, Food

LIGHT = np.array([0.3, 1.0, 0.2]) / np.linalg.norm([0.3, 1.0, 0.2])
ROCK = (0.45, 0.42, 0.38)
WEED = (0.15, 0.55, 0.2)
BALL = (0.9, 0.9, 0.85)
SEABED = ((0.62, 0.56, 0.42), (0.48, 0.44, 0.34))
_BOX_FACES = np.array(
    [
        (0, 1, 3),
        (0, 3, 2),
        (4, 6, 7),
        (4, 7, 5),
        (0, 4, 5),
        (0, 5, 1),
        (2, 3, 7),
        (2, 7, 6),
        (0, 2, 6),
        (0, 6, 4),
        (1, 5, 7),
        (1, 7, 3),
    ]
)


@dataclass(frozen=True)
class Mesh:
    """Triangles ready to draw: vertices (V, 3) m, triangles (T, 3) int, shaded colours (T, 3)
    in [0, 1], and the owner of each triangle (T,) int: animal index, or -1 for scenery."""

    vertices: np.ndarray
    triangles: np.ndarray
    colors: np.ndarray
    owner: np.ndarray


def shade(vertices: np.ndarray, triangles: np.ndarray, base: np.ndarray) -> np.ndarray:
    """Return the colours (T, 3) of triangles lit by ``LIGHT`` (both sides lit alike)."""
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=-1, keepdims=True) + 1e-12
    lam = np.abs(n @ LIGHT)
    return np.clip(base * (0.45 + 0.55 * lam)[:, None], 0.0, 1.0)


def _box(center, half) -> tuple[np.ndarray, np.ndarray]:
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    return np.asarray(center) + corners * np.asarray(half), _BOX_FACES


def _cylinder(center, radius, length, axis: str, sides: int = 8):
    ang = 2 * np.pi * np.arange(sides) / sides
    ring = np.stack([radius * np.cos(ang), radius * np.sin(ang)], 1)
    h = 0.5 * length
    ax = "xyz".index(axis)
    others = [k for k in range(3) if k != ax]
    v = np.zeros((2 * sides, 3))
    v[:sides, others], v[sides:, others] = ring, ring
    v[:sides, ax], v[sides:, ax] = -h, h
    k = np.arange(sides)
    k1 = (k + 1) % sides
    tris = np.concatenate(
        [np.stack([k, k1, k + sides], 1), np.stack([k1, k1 + sides, k + sides], 1)]
    )
    return v + np.asarray(center), tris


def _sphere(center, radius, n: int = 6):
    lat = np.linspace(0, np.pi, n + 1)
    lon = np.linspace(0, 2 * np.pi, 2 * n, endpoint=False)
    v = np.array(
        [[np.sin(a) * np.cos(b), np.cos(a), np.sin(a) * np.sin(b)] for a in lat for b in lon]
    )
    m = 2 * n
    tris = []
    for i in range(n):
        for j in range(m):
            p, q = i * m + j, i * m + (j + 1) % m
            tris += [(p, q, p + m), (q, q + m, p + m)]
    return center + radius * v, np.array(tris)


_OCTAHEDRON = np.array(
    [[0, 2, 4], [4, 2, 1], [1, 2, 5], [5, 2, 0], [4, 3, 0], [1, 3, 4], [5, 3, 1], [0, 3, 5]]
)


def solid(shape: str, size, axis: str = "y", marker: float = 0.1):
    """Return the vertices (V, 3) about the origin and triangles of a record object's shape
    (``record.Thing``): box (half sizes), cylinder (radius, length along ``axis``, 12 sides),
    sphere (radius); anything else a point, drawn as an octahedron reaching ``marker`` m."""
    if shape == "box":
        return _box(np.zeros(3), size)
    if shape == "cylinder":
        return _cylinder(np.zeros(3), size[0], size[1], axis, sides=12)
    if shape == "sphere":
        return _sphere(np.zeros(3), size[0])
    v = np.float32([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]])
    return v * np.float32(marker), _OCTAHEDRON


def strand_tube(centres: np.ndarray, radius: float, sides: int = 6):
    """Return a tube of ``radius`` m along the M points ``centres`` (M, 3) (a plant's strand):
    its vertices (M * sides, 3) float32, a horizontal ring of ``sides`` about each point; its
    triangles (T, 3); and the point (M,) each vertex rings, to skin it to the strand's nodes."""
    m = centres.shape[0]
    ang = 2 * np.pi * np.arange(sides) / sides
    ring = radius * np.stack([np.cos(ang), np.zeros(sides), np.sin(ang)], 1)
    verts = (centres[:, None] + ring[None]).reshape(-1, 3).astype(np.float32)
    j, k = np.meshgrid(np.arange(m - 1), np.arange(sides), indexing="ij")
    a, c = j * sides + k, j * sides + (k + 1) % sides
    faces = np.stack([a, a + sides, c, c, a + sides, c + sides], -1).reshape(-1, 3)
    return verts, faces, np.repeat(np.arange(m), sides)


def seabed(center_xz=(0.0, 0.0), level: float = -2.0, extent: float = 40.0, tile: float = 1.0):
    """Return (vertices, triangles, colours) of a checkered square seabed at height ``level``."""
    n = max(1, int(round(extent / tile)))
    xs = center_xz[0] - 0.5 * extent + tile * np.arange(n + 1)
    zs = center_xz[1] - 0.5 * extent + tile * np.arange(n + 1)
    gx, gz = np.meshgrid(xs, zs, indexing="ij")
    v = np.stack([gx.ravel(), np.full(gx.size, level), gz.ravel()], 1)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    a = (i * (n + 1) + j).ravel()
    tris = np.concatenate(
        [np.stack([a, a + n + 1, a + 1], 1), np.stack([a + 1, a + n + 1, a + n + 2], 1)]
    )
    parity = np.tile(((i + j) % 2).ravel(), 2)
    cols = np.where(parity[:, None] == 0, SEABED[0], SEABED[1])
    return v, tris, cols


def world_mesh(
    bodies: Sequence[Body],
    positions: Sequence[np.ndarray],
    colors: Sequence[Sequence[float]],
    objects: Sequence[Ball | Box | Cylinder | Food] = (),
    ball_positions=None,
    floor: tuple[float, float, float, float] | None = None,
) -> Mesh:
    """Return the shaded triangles of animals (each (N, 3) positions, an RGB colour in [0, 1])
    and objects (boxes grey, cylinders green as seaweed, balls white; food is not drawn).

    floor: (x, z, level, extent) of a checkered seabed square, or None for none.
    """
    verts, tris, cols, owner = [], [], [], []
    base = 0

    def add(v, t, c, who):
        nonlocal base
        v = np.asarray(v, float)
        t = np.asarray(t, np.int64) + base
        verts.append(v)
        tris.append(t)
        cols.append(np.broadcast_to(np.asarray(c, float), (len(t), 3)))
        owner.append(np.full(len(t), who, np.int64))
        base += len(v)

    for k, (body, pos, col) in enumerate(zip(bodies, positions, colors, strict=True)):
        add(pos, body.faces, col, k)
    balls = iter(np.asarray(ball_positions).reshape(-1, 3)) if ball_positions is not None else None
    for o in objects:
        if isinstance(o, Box):
            add(*_box(o.center, o.half_size), ROCK, -1)
        elif isinstance(o, Cylinder):
            add(*_cylinder(o.center, o.radius, o.length, o.axis), WEED, -1)
        elif isinstance(o, Ball):
            c = next(balls) if balls is not None else np.asarray(o.position)
            add(*_sphere(c, o.radius), BALL, -1)
    if floor is not None:
        v, t, c = seabed(floor[:2], floor[2], floor[3])
        add(v, t, c, -1)
    v = np.concatenate(verts) if verts else np.zeros((0, 3))
    t = np.concatenate(tris) if tris else np.zeros((0, 3), np.int64)
    c = np.concatenate(cols) if cols else np.zeros((0, 3))
    return Mesh(
        v,
        t,
        shade(v, t, c) if len(t) else c,
        np.concatenate(owner) if owner else np.zeros(0, np.int64),
    )


def merge(*meshes: Mesh) -> Mesh:
    """Return one mesh holding the triangles of several (owners kept)."""
    base = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
    return Mesh(
        np.concatenate([m.vertices for m in meshes]),
        np.concatenate([m.triangles + b for m, b in zip(meshes, base, strict=True)]),
        np.concatenate([m.colors for m in meshes]),
        np.concatenate([m.owner for m in meshes]),
    )
