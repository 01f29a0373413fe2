"""A z-buffered software rasteriser (Numba): triangles with flat colours into RGB images from
pinhole cameras, batched over cameras, with exponential underwater fog. One thread: on a
shared 2-core host a thread pool over 8 small eye images ran 4x slower than a plain loop.

Conventions follow the project's axes (x forward, y up, z left). A camera's rotation holds the
right, up and forward unit axes as rows (as ``viz.render3d.look_at``). A point p lands at the
continuous pixel (col, row) = (W/2 + F x / z, H/2 - F y / z), with (x, y, z) = R (p - eye) and
focal length F = (W/2) / tan(fov/2): pixel (i, j) covers cols [i, i+1) and rows [j, j+1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from zoetic.errors import ZoeticError
from zoetic.jitcache import fresh_numba_cache

fresh_numba_cache()

NEAR = 0.01  # m: triangles with a vertex nearer than this to a camera's plane are skipped


class RenderError(ZoeticError):
    """A camera or scene the rasteriser cannot draw."""


@dataclass(frozen=True)
class Cameras:
    """C pinhole cameras with square pixels: eye (C, 3) m, rotation (C, 3, 3) rows right, up,
    forward; fov (C,) rad, the horizontal field of view; size (W, H) pixels."""

    eye: np.ndarray
    rotation: np.ndarray
    fov: np.ndarray
    size: tuple[int, int]

    def __post_init__(self) -> None:
        eye = np.atleast_2d(np.asarray(self.eye, float))
        rot = np.asarray(self.rotation, float).reshape(-1, 3, 3)
        fov = np.broadcast_to(np.asarray(self.fov, float), (len(eye),)).copy()
        if rot.shape[0] != eye.shape[0]:
            raise RenderError(f"{eye.shape[0]} camera positions but {rot.shape[0]} rotations")
        if not (np.all(fov > 0) and np.all(fov < np.pi)):
            raise RenderError(f"camera fields of view must lie in (0, pi) rad, got {fov}")
        w, h = (int(s) for s in self.size)
        if w < 1 or h < 1:
            raise RenderError(f"image size must be positive, got {self.size}")
        object.__setattr__(self, "eye", eye)
        object.__setattr__(self, "rotation", rot)
        object.__setattr__(self, "fov", fov)
        object.__setattr__(self, "size", (w, h))

    @property
    def focal(self) -> np.ndarray:
        """Return the (C,) focal lengths in pixels."""
        return 0.5 * self.size[0] / np.tan(0.5 * self.fov)


def look_rotation(forward, up=(0.0, 1.0, 0.0)) -> np.ndarray:
    """Return rotations (..., 3, 3) whose rows are right, up, forward for view directions
    ``forward`` (..., 3), the up row as near ``up`` as it can be."""
    f = np.asarray(forward, float)
    f = f / np.linalg.norm(f, axis=-1, keepdims=True)
    u0 = np.broadcast_to(np.asarray(up, float), f.shape)
    r = _cross(u0, f)  # up x forward: +z is on the left when looking along +x
    n = np.linalg.norm(r, axis=-1, keepdims=True)
    r = np.where(n > 1e-9, r / np.maximum(n, 1e-12), np.array([0.0, 0.0, -1.0]))
    return np.stack([r, _cross(f, r), f], axis=-2)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Return the cross products (..., 3) of vectors (..., 3) (``np.cross``'s numbers
    without its axis juggling, which costs more than the products for a few vectors)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def project(points, cameras: Cameras) -> tuple[np.ndarray, np.ndarray]:
    """Return the continuous pixel coordinates (C, P, 2) as (col, row) of points (P, 3) in each
    camera, and their depths (C, P) along its forward axis (m)."""
    p = np.asarray(points, float).reshape(-1, 3)
    local = np.einsum("cij,cpj->cpi", cameras.rotation, p[None] - cameras.eye[:, None])
    z = local[..., 2]
    f = cameras.focal[:, None]
    w, h = cameras.size
    with np.errstate(divide="ignore", invalid="ignore"):
        col = 0.5 * w + f * local[..., 0] / z
        row = 0.5 * h - f * local[..., 1] / z
    return np.stack([col, row], axis=-1), z


@njit(cache=True, fastmath=True)
def _raster(vert, tris, eyes, rots, focal, width, height, nearest, depth):
    """Write into nearest (C, H, W) the triangle each camera sees at each pixel (-1 none)
    and into depth (C, H, W) its depth (m along the view axis; inf for none)."""
    n_cam = eyes.shape[0]
    n_tri = tris.shape[0]
    nv = vert.shape[0]
    sx = np.empty(nv)
    sy = np.empty(nv)
    sz = np.empty(nv)
    out = np.empty(nv, np.int64)  # which sides of the picture each vertex lies beyond
    for c in range(n_cam):
        zbuf = depth[c]
        hit = nearest[c]
        zbuf[:, :] = np.inf
        hit[:, :] = -1
        for v in range(nv):
            dx = vert[v, 0] - eyes[c, 0]
            dy = vert[v, 1] - eyes[c, 1]
            dz = vert[v, 2] - eyes[c, 2]
            x = rots[c, 0, 0] * dx + rots[c, 0, 1] * dy + rots[c, 0, 2] * dz
            y = rots[c, 1, 0] * dx + rots[c, 1, 1] * dy + rots[c, 1, 2] * dz
            z = rots[c, 2, 0] * dx + rots[c, 2, 1] * dy + rots[c, 2, 2] * dz
            sz[v] = z
            if z > NEAR:
                sx[v] = 0.5 * width + focal[c] * x / z
                sy[v] = 0.5 * height - focal[c] * y / z
                out[v] = (
                    (sx[v] < 0.0) + 2 * (sx[v] > width) + 4 * (sy[v] < 0.0) + 8 * (sy[v] > height)
                )
            else:
                sx[v] = 0.0
                sy[v] = 0.0
                out[v] = 16
        for t in range(n_tri):
            a, b, d = tris[t, 0], tris[t, 1], tris[t, 2]
            # skipped: a vertex too near (or behind), or all three beyond one side
            if (out[a] | out[b] | out[d]) & 16 or out[a] & out[b] & out[d]:
                continue
            _fill(sx[a], sy[a], sx[b], sy[b], sx[d], sy[d], sz[a], sz[b], sz[d], t, zbuf, hit)


@njit(cache=True, fastmath=True, inline="always")
def _fill(x0, y0, x1, y1, x2, y2, za, zb, zd, t, zbuf, hit):
    """Draw triangle t (screen corners (x, y), depths z) into one camera's buffers: each
    pixel whose centre it covers, where it is the nearest so far. Each row is tested only
    across the triangle's span on it (a pixel wider on both sides)."""
    height, width = zbuf.shape
    area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
    if abs(area) < 1e-12:
        return
    i0 = max(int(np.floor(min(x0, x1, x2))), 0)
    i1 = min(int(np.ceil(max(x0, x1, x2))), width - 1)
    j0 = max(int(np.floor(min(y0, y1, y2))), 0)
    j1 = min(int(np.ceil(max(y0, y1, y2))), height - 1)
    if i0 > i1 or j0 > j1:
        return
    # perspective-correct depth: 1/z is affine in screen space
    iz0, iz1, iz2 = 1.0 / za, 1.0 / zb, 1.0 / zd
    inv = 1.0 / area
    for j in range(j0, j1 + 1):
        py = j + 0.5
        lo, hi = _cut(x0, y0, x1, y1, py, np.inf, -np.inf)
        lo, hi = _cut(x1, y1, x2, y2, py, lo, hi)
        lo, hi = _cut(x2, y2, x0, y0, py, lo, hi)
        if lo > hi:
            continue
        for i in range(max(i0, int(np.floor(lo)) - 1), min(i1, int(np.ceil(hi)) + 1) + 1):
            px = i + 0.5
            w0 = ((x1 - px) * (y2 - py) - (x2 - px) * (y1 - py)) * inv
            w1 = ((x2 - px) * (y0 - py) - (x0 - px) * (y2 - py)) * inv
            w2 = 1.0 - w0 - w1
            if w0 < 0.0 or w1 < 0.0 or w2 < 0.0:
                continue
            z = 1.0 / (w0 * iz0 + w1 * iz1 + w2 * iz2)
            if z < zbuf[j, i]:
                zbuf[j, i] = z
                hit[j, i] = t


@njit(cache=True, inline="always")
def _cut(xa, ya, xb, yb, py, lo, hi):
    """Return the span (lo, hi) widened to the points where edge a-b meets row py."""
    if ya == yb:
        if ya == py:
            return min(lo, xa, xb), max(hi, xa, xb)
        return lo, hi
    if min(ya, yb) <= py <= max(ya, yb):
        xc = xa + (py - ya) * (xb - xa) / (yb - ya)
        return min(lo, xc), max(hi, xc)
    return lo, hi


@njit(cache=True, fastmath=True)
def _shade(nearest, depth, colors, fog_color, fog_dist, out):
    """Write into out (C, H, W, 3) uint8 each pixel's triangle colour through the fog of
    its depth (the fog's colour where no triangle was drawn)."""
    n_cam, height, width = nearest.shape
    for c in range(n_cam):
        for j in range(height):
            for i in range(width):
                t = nearest[c, j, i]
                fog = 1.0
                if t >= 0:
                    fog = 1.0 - np.exp(-depth[c, j, i] / fog_dist) if fog_dist > 0 else 0.0
                for k in range(3):
                    v = fog_color[k] if t < 0 else colors[t, k] * (1.0 - fog) + fog_color[k] * fog
                    out[c, j, i, k] = int(min(max(v * 255.0 + 0.5, 0.0), 255.0))


def render(
    vertices,
    triangles,
    colors,
    cameras: Cameras,
    fog_color=(0.05, 0.25, 0.35),
    visibility: float = 0.0,
    with_depth: bool = False,
):
    """Return RGB images (C, H, W, 3) uint8 of triangles seen by each camera (and the depth
    buffers (C, H, W) in m along the view axis, inf where nothing was drawn, if asked).

    vertices (V, 3) m; triangles (T, 3) int; colors (T, 3) floats in [0, 1] (already shaded);
    visibility: the fog's e-folding distance in m (0: clear water); empty pixels show the fog.
    """
    v = np.ascontiguousarray(vertices, dtype=np.float64).reshape(-1, 3)
    t = np.ascontiguousarray(triangles, dtype=np.int64).reshape(-1, 3)
    col = np.ascontiguousarray(colors, dtype=np.float64).reshape(-1, 3)
    if len(col) != len(t):
        raise RenderError(f"{len(t)} triangles but {len(col)} colours")
    if len(t) and (t.min() < 0 or t.max() >= len(v)):
        raise RenderError(f"triangle indices must lie in [0, {len(v)})")
    w, h = cameras.size
    n = len(cameras.eye)
    nearest = np.empty((n, h, w), np.int32)
    depth = np.empty((n, h, w))
    eye, rot = np.ascontiguousarray(cameras.eye), np.ascontiguousarray(cameras.rotation)
    _raster(v, t, eye, rot, cameras.focal, w, h, nearest, depth)
    img = np.empty((n, h, w, 3), np.uint8)
    _shade(nearest, depth, col, np.asarray(fog_color, float), float(visibility), img)
    return (img, depth) if with_depth else img
