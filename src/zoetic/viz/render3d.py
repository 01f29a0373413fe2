"""A small, fast software renderer: look-at camera, painter's algorithm, Pillow polygons.

Screen conventions follow the project's axes (x forward, y up, z LEFT): seen from behind, +z is
on the left of the picture. The environment (ground checkerboard, sea floor, water surface, sky)
is computed per pixel with NumPy; the animals' triangles are depth-sorted and filled by Pillow.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from numbers import Real
from pathlib import Path

import numpy as np
from PIL import Image, ImageColor, ImageDraw

from zoetic.bodies import Body
from zoetic.errors import ZoeticError
from zoetic.physics.media import Medium, get_medium
from zoetic.render.skin import Look, Skin, body_skin, make_skin, name_color, skin_vertices
from zoetic.viz.paint import draw_buoy, label_font, place_tags, project_points

_LIGHT = np.array([-0.2, 1.0, -0.7]) / np.linalg.norm([-0.2, 1.0, -0.7])
_SKY_TOP, _SKY_LOW = np.array([96.0, 150, 214]), np.array([214.0, 228, 240])
_GROUND = (np.array([186.0, 176, 150]), np.array([150.0, 140, 116]))
_WATER_UP, _WATER_DOWN = np.array([64.0, 136, 178]), np.array([14.0, 46, 82])
_SEABED = (np.array([92.0, 120, 118]), np.array([66.0, 96, 102]))
_SURFACE = np.array([34.0, 104, 146])
_SPACE_UP, _SPACE_DOWN = np.array([40.0, 44, 60]), np.array([12.0, 12, 20])
TEXT_STYLE = {"fill": (255, 255, 255), "stroke_width": 2, "stroke_fill": (0, 0, 0)}
_TILE, _SURFACE_TILE, _SEABED_DEPTH, _WATER_FOG, _AIR_FOG = 0.5, 2.0, 3.0, 4.0, 25.0


@dataclass(frozen=True)
class Camera:
    """A look-at camera that follows the animals' mean centre of mass from a fixed direction.

    azimuth: degrees around the vertical from straight behind (-x) toward the animal's right
    (-z); elevation: degrees above the horizontal; distance: metres to the target (None fits
    the animals in view); fov: vertical field of view in degrees; smoothing: time scale in
    seconds of the (lag-free, Gaussian) smoothing of the followed point; target: a fixed point
    to look at instead of following. Over a sea the eye stays in the air; the default elevation
    is 12 degrees there (the horizon and the sky in view), else 25.
    """

    azimuth: float = 40.0
    elevation: float | None = None
    distance: float | None = None
    fov: float = 45.0
    smoothing: float = 0.25
    target: tuple[float, float, float] | None = None

    def direction(self, medium: Medium) -> np.ndarray:
        """Return the unit vector from the target to the eye (lower over a sea, to see the sky)."""
        el = self.elevation
        if el is None:
            el = 12.0 if abs(medium.water_level) < 1e8 else 25.0
        az, el = np.radians(self.azimuth), np.radians(np.clip(el, -89.0, 89.0))
        return np.array([-np.cos(el) * np.cos(az), np.sin(el), -np.cos(el) * np.sin(az)])


def body_color(body: Body) -> tuple[int, int, int]:
    """Return the display colour (RGB 0-255) of an animal, by name."""
    return name_color(body.name)


def look_at(eye: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Return the (3, 3) camera rotation whose rows are the right, up and forward unit axes."""
    f = np.asarray(target, float) - np.asarray(eye, float)
    f /= max(np.linalg.norm(f), 1e-12)
    r = np.cross([0.0, 1.0, 0.0], f)  # y x f: +z is on the left when looking along +x
    r = r / np.linalg.norm(r) if np.linalg.norm(r) > 1e-9 else np.array([0.0, 0.0, -1.0])
    return np.stack([r, np.cross(f, r), f])


def camera_path(
    coms: np.ndarray, times: np.ndarray, camera: Camera, medium: Medium, extent: float
) -> tuple[np.ndarray, np.ndarray]:
    """Return the (R, 3) eye and target positions of a camera following ``coms`` (R, 3)."""
    if camera.target is not None:
        target = np.tile(np.asarray(camera.target, float), (len(times), 1))
    else:
        target = _fill_nan(coms)
        dt = float(np.median(np.diff(times))) if len(times) > 1 else 1.0
        if camera.smoothing > 0 and len(times) > 1 and dt > 0:
            from scipy.ndimage import gaussian_filter1d

            target = gaussian_filter1d(target, camera.smoothing / dt, axis=0, mode="nearest")
    dist = camera.distance or 1.3 * extent / np.tan(np.radians(camera.fov) / 2)
    eye = target + dist * camera.direction(medium)
    level = medium.water_level
    if abs(level) < 1e8:  # keep the eye in the air, well above a finite water surface
        eye[:, 1] = np.maximum(eye[:, 1], level + 0.2 * dist)
    return eye, target


def _fill_nan(x: np.ndarray) -> np.ndarray:
    """Return ``x`` (R, 3) with non-finite rows replaced by the last finite one (or zeros)."""
    good = np.isfinite(x).all(axis=1)
    if not good.any():
        return np.zeros_like(x)
    idx = np.maximum.accumulate(np.where(good, np.arange(len(x)), np.argmax(good)))
    return x[idx]


# ---------------------------------------------------------------- environment (per pixel)


def _lerp(a: np.ndarray, b: np.ndarray, t) -> np.ndarray:
    t = np.asarray(t, np.float64)[..., None]
    return a * (1 - t) + b * t


def _u8(c: np.ndarray) -> np.ndarray:
    return np.clip(c, 0, 255).astype(np.uint8)


def _parity(eye, rot, xs, ys, t, tile: float) -> np.ndarray:
    """Return the (h, W) checker parity where rows' rays (ray parameter ``t``) meet a plane."""
    ti = (np.minimum(t, 500.0) / tile).astype(np.float32)
    cells = []
    for k in (0, 2):  # world x and z of the hit points, in tiles, offset to stay positive
        along = np.multiply.outer(ti, (xs * rot[0, k]).astype(np.float32))
        along += (ti * (ys * rot[1, k] + rot[2, k]) + (eye[k] / tile + 2e4)).astype(np.float32)[
            :, None
        ]
        cells.append(along.astype(np.int32))
    return ((cells[0] + cells[1]) & 1).astype(bool)


def _fill_checker(out, eye, rot, xs, ys, t, ca, cb, tile: float = _TILE) -> None:
    """Fill ``out`` (h, W, 3) with row colours ``ca``/``cb`` (h, 3) by checker parity."""
    par = _parity(eye, rot, xs, ys, t, tile)
    palette = np.stack([_u8(cb), _u8(ca)], axis=1).reshape(-1, 3)  # (2h, 3): row-wise pairs
    index = np.arange(0, 2 * len(ys), 2, dtype=np.int32)[:, None] + par
    out[:] = np.take(palette, index, axis=0)


def fresnel(sin_elevation: np.ndarray) -> np.ndarray:
    """Return the opacity of the water surface seen along a ray of that elevation sine."""
    return 0.45 + 0.45 * (1 - np.abs(sin_elevation)) ** 3


def background(
    medium: Medium,
    eye: np.ndarray,
    rot: np.ndarray,
    xs,
    ys,
    seabed: float | None = None,
    fog: float = _WATER_FOG,
) -> np.ndarray:
    """Return the (H, W, 3) uint8 environment seen by a camera at ``eye`` with rotation ``rot``.

    ``xs`` (W,) and ``ys`` (H,) are the pixel centres on the image plane at unit depth;
    ``seabed`` is the height of the sea floor drawn under water (default 3 m down).
    """
    h, w = len(ys), len(xs)
    out = np.empty((h, w, 3), np.uint8)
    dy = ys * rot[1, 1] + rot[2, 1]  # rows only: the camera never rolls; decreasing down
    norm = np.sqrt(1 + ys * ys)
    sin_el = dy / norm  # elevation of each row's ray (centre column)
    level = medium.water_level
    n_up = int(np.count_nonzero(dy >= -1e-6))
    up, down = slice(0, n_up), slice(n_up, h)
    dd, nd, yd = dy[down], norm[down], ys[down]
    sky = _lerp(_SKY_LOW, _SKY_TOP, np.clip(sin_el, 0, 1) ** 0.7)
    if medium.floor and eye[1] > 0:
        out[up] = _u8(sky[up])[:, None]
        t = -eye[1] / dd
        haze = 1 - np.exp(-t * nd / _AIR_FOG)
        ca, cb = (_lerp(c, _SKY_LOW, haze) for c in _GROUND)
        _fill_checker(out[down], eye, rot, xs, yd, t, ca, cb)
    elif abs(level) > 1e8:  # open water, or empty space
        hi, lo = (_WATER_UP, _WATER_DOWN) if level > 1e8 else (_SPACE_UP, _SPACE_DOWN)
        bg = _lerp(lo, hi, np.clip(0.5 + 0.8 * sin_el, 0, 1))
        seabed = -_SEABED_DEPTH if seabed is None else seabed
        if eye[1] <= seabed:
            up = slice(0, h)
        out[up] = _u8(bg[up])[:, None]
        if eye[1] > seabed:
            t = (seabed - eye[1]) / dd
            haze = 1 - np.exp(-t * nd / fog)
            pair = _SEABED if level > 1e8 else (lo + 30, lo + 14)
            ca, cb = (_lerp(c, bg[down], haze) for c in pair)
            _fill_checker(out[down], eye, rot, xs, yd, t, ca, cb)
    else:  # the sea seen from the air (the camera never goes under a finite surface)
        out[up] = _u8(sky[up])[:, None]
        t_s = (level - eye[1]) / dd
        t_f = ((level - _SEABED_DEPTH if seabed is None else seabed) - eye[1]) / dd
        haze = 1 - np.exp(-(t_f - t_s) * nd / fog)
        grazing = 1 - np.abs(sin_el[down])
        surf = _lerp(_SURFACE, _SKY_LOW, 0.8 * grazing**8)
        ca, cb = (_lerp(_lerp(c, _WATER_DOWN, haze), surf, fresnel(sin_el[down])) for c in _SEABED)
        _fill_checker(out[down], eye, rot, xs, yd, t_f, ca, cb)
        ripple = _parity(eye, rot, xs, yd, t_s, _SURFACE_TILE)
        out[down] += ripple[..., None].astype(np.uint8) * np.uint8(7)
    return out


# ---------------------------------------------------------------- animals and buoys


def water_tint(
    col: np.ndarray, pts: np.ndarray, eye: np.ndarray, medium: Medium, fog: float = _WATER_FOG
) -> np.ndarray:
    """Return colours (K, 3) of points (K, 3) seen through water: fog (e-folding ``fog`` m
    in open water, half that under a surface) and the surface."""
    level = medium.water_level
    if level < -1e8:
        return col
    d = pts - eye
    dist = np.linalg.norm(d, axis=1) + 1e-9
    if level > 1e8:
        return _lerp(col, 0.5 * (_WATER_UP + _WATER_DOWN), 1 - np.exp(-dist / (2 * fog)))
    below = pts[:, 1] < level  # the eye is always above a finite surface
    wet = np.clip((level - pts[:, 1]) / np.maximum(eye[1] - pts[:, 1], 1e-9), 0, 1)
    col = _lerp(col, _WATER_DOWN, 1 - np.exp(-dist * wet / _WATER_FOG))
    return np.where(below[:, None], _lerp(col, _SURFACE, fresnel(d[:, 1] / dist)), col)


def split_at_level(poly: np.ndarray, level: float) -> tuple[np.ndarray, np.ndarray]:
    """Return the parts of a planar polygon (k, 3) above and below the plane y = level."""
    above, below = [], []
    for i in range(len(poly)):
        a, b = poly[i], poly[(i + 1) % len(poly)]
        sa, sb = a[1] - level, b[1] - level
        (above if sa >= 0 else below).append(a)
        if (sa < 0) != (sb < 0):
            p = a + (b - a) * (sa / (sa - sb))
            above.append(p)
            below.append(p)
    return np.array(above), np.array(below)


@dataclass(frozen=True)
class SceneMesh:
    """All animals' triangles in one index space, with colours and closedness."""

    faces: np.ndarray  # (F, 3) into the concatenated nodes
    color: np.ndarray  # (F, 3) float RGB
    closed: np.ndarray  # (F,) bool: the animal's surface is closed (back faces can be culled)


def plain_look(name: str, color) -> Look:
    """Return a look of one colour (RGB 0-255 or a colour name), the belly paler."""
    c = ImageColor.getrgb(color) if isinstance(color, str) else color
    c = np.asarray(c, float)[:3] / 255.0
    return Look(name, tuple(c), tuple(0.6 * c + 0.4))


def animal_skins(bodies: Sequence[Body], colors=None, looks=None, levels: int = 2) -> list[Skin]:
    """Return each animal's display skin (``levels`` subdivisions): in the look named
    ``looks[i]``, else one of colour ``colors[i]``, else the body's own look."""
    out = []
    for i, body in enumerate(bodies):
        if looks is not None and looks[i]:
            out.append(body_skin(body, looks[i], levels))
        elif colors is not None:
            look = plain_look(body.name, colors[i])
            out.append(make_skin(body.faces, body.rest_pos, look, None, body.forward, levels))
        else:
            out.append(body_skin(body, None, levels))
    return out


def skins_mesh(skins: Sequence[Skin]) -> SceneMesh:
    """Return the skins' triangles in one index space (their vertices concatenated), coloured
    RGB 0-255 per triangle."""
    base = np.cumsum([0] + [len(s.index) for s in skins[:-1]])
    return SceneMesh(
        np.concatenate([s.triangles + b for s, b in zip(skins, base, strict=True)]),
        np.concatenate([255.0 * s.face_colors for s in skins]),
        np.concatenate([s.closed for s in skins]),
    )


def skins_vertices(skins: Sequence[Skin], positions: Sequence[np.ndarray]) -> np.ndarray:
    """Return the skins' vertices (V, 3) concatenated, for each animal's nodes (N_i, 3)."""
    return np.concatenate([skin_vertices(s, p) for s, p in zip(skins, positions, strict=True)])


def smooth_normals(n: np.ndarray, faces: np.ndarray, closed: np.ndarray, n_vertices: int):
    """Return per-face shading normals (F, 3) of a closed surface, smooth across its edges: the
    mean of the face's vertex normals, each the mean of the unit normals of the closed
    faces around it (``n``, unit, outward). The painter's fill is one colour per face,
    so this is Gouraud shading at the face's centre: facets of the subdivided skin no longer
    show as steps of light."""
    vn = np.zeros((n_vertices, 3))
    for k in range(3):
        np.add.at(vn, faces[closed, k], n[closed])
    vn /= np.linalg.norm(vn, axis=1, keepdims=True) + 1e-12
    fn = vn[faces].sum(axis=1)
    return fn / (np.linalg.norm(fn, axis=1, keepdims=True) + 1e-12)


def face_items(
    pos, mesh: SceneMesh, eye, rot, focal, size, medium, side: int = 0, fog: float = _WATER_FOG
) -> list[tuple]:
    """Return (depth, kind 0, flat screen coords, RGB) items for the visible triangles; with
    ``side`` 1 only their parts above a finite water surface, -1 only those below."""
    scr, z = project_points(pos, eye, rot, focal, size)
    tri = pos[mesh.faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True) + 1e-12
    cen = tri.mean(axis=1)
    front = np.einsum("fk,fk->f", n, cen - eye) < 0
    keep = np.isfinite(tri).all(axis=(1, 2)) & (z[mesh.faces] > 0.05).all(axis=1)
    keep &= front | ~mesh.closed
    fs = scr[mesh.faces]  # (F, 3, 2): triangles wholly off the picture are not drawn
    keep &= (fs[..., 0].max(1) >= 0) & (fs[..., 0].min(1) <= size[0])
    keep &= (fs[..., 1].max(1) >= 0) & (fs[..., 1].min(1) <= size[1])
    smooth = smooth_normals(n, mesh.faces, mesh.closed, len(pos))
    n = np.where(front[:, None], n, -n)  # a fin is lit on the side the camera sees
    ns = np.where(mesh.closed[:, None], smooth, n)
    shade = 0.3 + 0.12 * ns[:, 1] + 0.7 * np.maximum(ns @ _LIGHT, 0.0)
    col = mesh.color * shade[:, None]
    depth = z[mesh.faces].mean(axis=1)
    level = medium.water_level
    straddle = np.zeros(len(tri), bool)
    if abs(level) < 1e8:
        ty = tri[:, :, 1] - level
        straddle = keep & (ty.min(axis=1) < 0) & (ty.max(axis=1) > 0)
    tinted = water_tint(col, cen, eye, medium, fog)
    if side and abs(level) < 1e8:
        keep = keep & (straddle | ((cen[:, 1] >= level) == (side > 0)))
    idx = np.flatnonzero(keep & ~straddle)
    coords = scr[mesh.faces[idx]].reshape(len(idx), 6).tolist()
    rgb = np.clip(tinted[idx], 0, 255).astype(int).tolist()
    items = [(d, 0, c, tuple(k)) for d, c, k in zip(depth[idx].tolist(), coords, rgb, strict=True)]
    for f in np.flatnonzero(straddle):
        for k, part in enumerate(split_at_level(tri[f], level)):
            if len(part) < 3 or (side and (k == 0) != (side > 0)):
                continue
            pc = water_tint(col[f][None], part.mean(axis=0)[None], eye, medium, fog)[0]
            flat = project_points(part, eye, rot, focal, size)[0].ravel().tolist()
            items.append((depth[f], 0, flat, tuple(np.clip(pc, 0, 255).astype(int).tolist())))
    return items


def _marker_items(markers, colors, radius, eye, rot, focal, size, medium) -> list[tuple]:
    """Return (depth, kind 1, (x, y, r), RGB) items for buoys in front of the camera."""
    scr, z = project_points(markers, eye, rot, focal, size)
    col = water_tint(colors, markers, eye, medium)
    return [
        (z[i], 1, (scr[i, 0], scr[i, 1], focal * radius / z[i]), col[i])
        for i in range(len(markers))
        if z[i] > 0.05 + radius
    ]


# ---------------------------------------------------------------- public API


def _as_lists(bodies, positions, n_times: int) -> tuple[list[Body], list[np.ndarray]]:
    """Return one Body and one (R, N, 3) position array per animal, checked."""
    if isinstance(positions, np.ndarray):
        positions = [positions] if positions.ndim == 3 else list(positions)
    positions = [np.asarray(p, float) for p in positions]
    bodies = [bodies] * len(positions) if isinstance(bodies, Body) else list(bodies)
    if len(bodies) != len(positions) or not bodies:
        raise ZoeticError(f"{len(bodies)} bodies but {len(positions)} position arrays")
    for b, p in zip(bodies, positions, strict=True):
        if p.shape != (n_times, b.n_nodes, 3):
            raise ZoeticError(
                f"positions of {b.name} are {p.shape}, expected ({n_times}, {b.n_nodes}, 3)"
            )
    return bodies, positions


def _group(bodies: list[Body], positions: list[np.ndarray]) -> tuple[np.ndarray, float]:
    """Return the animals' mean centre of mass (R, 3) and the group's radius at the start."""
    w = [b.mass / b.total_mass for b in bodies]
    coms = np.stack([np.einsum("rnk,n->rk", p, m) for m, p in zip(w, positions, strict=True)])
    ok = np.isfinite(coms).all(axis=2)
    com = np.where(ok[..., None], coms, 0).sum(0) / np.maximum(ok.sum(0), 1)[:, None]
    com[~ok.any(0)] = np.nan
    first = np.concatenate([p[int(np.argmax(np.isfinite(p).all(axis=(1, 2))))] for p in positions])
    first = first[np.isfinite(first).all(axis=1)]
    extent = float(np.linalg.norm(first - first.mean(0), axis=1).max()) if len(first) else 1.0
    return com, max(extent, 0.05)


def _marker_colors(marker_colors, m: int) -> np.ndarray:
    if marker_colors is None:
        marker_colors = (250, 130, 20)
    if isinstance(marker_colors, str) or all(isinstance(c, Real) for c in marker_colors):
        marker_colors = [marker_colors] * m
    rgb = [ImageColor.getrgb(c) if isinstance(c, str) else c for c in marker_colors]
    return np.array([c[:3] for c in rgb], float).reshape(m, 3)


def render_frames(
    bodies: Sequence[Body] | Body,
    positions: np.ndarray | Sequence[np.ndarray],
    times: np.ndarray,
    medium: Medium | str,
    size: tuple[int, int] = (640, 360),
    camera: Camera | None = None,
    markers: np.ndarray | None = None,
    marker_colors=None,
    labels: Sequence[str] | None = None,
    colors: Sequence | None = None,
    marker_radius: float | None = None,
    looks: Sequence[str] | None = None,
    skins: Sequence[Skin] | None = None,
) -> Iterator[np.ndarray]:
    """Yield one (H, W, 3) uint8 picture per recorded time of the animals in their medium.

    positions: per animal (R, N, 3) m, or one (B, R, N, 3) array of B animals of one body;
    markers: (M, 3) fixed world points drawn as buoys, or (R, M, 3) moving ones;
    labels: one text per animal;
    colors: one RGB tuple or colour name per animal (default: the animal's look);
    looks: one look name per animal (``render/looks``), before ``colors``;
    skins: one display skin per animal, before both.
    """
    times = np.asarray(times, float).reshape(-1)
    bodies, positions = _as_lists(bodies, positions, len(times))
    medium = get_medium(medium)
    camera = camera or Camera()
    size = (int(size[0]), int(size[1]))
    w, h = size
    focal = 0.5 * h / np.tan(np.radians(camera.fov) / 2)
    xs = ((np.arange(w) + 0.5 - w / 2) / focal).astype(np.float32)
    ys = ((h / 2 - np.arange(h) - 0.5) / focal).astype(np.float32)
    com, extent = _group(bodies, positions)
    eyes, targets = camera_path(com, times, camera, medium, extent)
    base = medium.water_level if abs(medium.water_level) < 1e8 else 0.0
    seabed = min(base - _SEABED_DEPTH, targets[:, 1].min() - 2 * extent - 1.0)  # under them all
    skins = list(skins) if skins is not None else animal_skins(bodies, colors, looks)
    mesh = skins_mesh(skins)
    mk = None if markers is None else np.asarray(markers, float)
    if mk is not None and not (mk.ndim == 3 and len(mk) == len(times)):  # (R, M, 3): moving
        mk = np.broadcast_to(mk.reshape(-1, 3), (len(times), *mk.reshape(-1, 3).shape))
    mk_col = None if mk is None else _marker_colors(marker_colors, mk.shape[1])
    radius = marker_radius or 0.12 * extent
    font, small = label_font(max(10, h // 22)), label_font(max(9, h // 28))
    for r in range(len(times)):
        eye, rot = eyes[r], look_at(eyes[r], targets[r])
        img = Image.fromarray(background(medium, eye, rot, xs, ys, seabed))
        draw = ImageDraw.Draw(img)
        pos = skins_vertices(skins, [p[r] for p in positions])
        items = face_items(pos, mesh, eye, rot, focal, size, medium)
        if mk is not None and mk.shape[1]:
            items += _marker_items(mk[r], mk_col, radius, eye, rot, focal, size, medium)
        items.sort(key=lambda it: -it[0])
        for _, kind, geom, col in items:
            if kind == 0:
                draw.polygon(geom, fill=col, outline=col)
            else:
                draw_buoy(draw, *geom, col)
        t_box = draw.textbbox((8, 6), f"t = {times[r]:.2f} s", font=font, stroke_width=2)
        if labels:
            view = (eye, rot, focal, size)
            tags = [(str(lb), (255, 255, 255)) for lb in labels]
            place_tags(draw, tags, [p[r] for p in positions], view, small, [t_box])
        draw.text((8, 6), f"t = {times[r]:.2f} s", font=font, **TEXT_STYLE)
        yield np.array(img)


def resample(
    positions: Sequence[np.ndarray], times: np.ndarray, fps: float
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Return frame times at ``fps`` over ``times`` and positions linearly interpolated there."""
    times = np.asarray(times, float)
    n = int(np.floor((times[-1] - times[0]) * fps + 1e-6)) + 1
    t_new = times[0] + np.arange(n) / fps
    if len(times) == 1:
        return t_new, [np.repeat(p, n, axis=0) for p in positions]
    i = np.clip(np.searchsorted(times, t_new, side="right") - 1, 0, len(times) - 2)
    frac = np.clip((t_new - times[i]) / np.maximum(times[i + 1] - times[i], 1e-12), 0, 1)
    frac = frac[:, None, None]
    return t_new, [p[i] * (1 - frac) + p[i + 1] * frac for p in positions]


def render_video(
    bodies: Sequence[Body] | Body,
    positions: np.ndarray | Sequence[np.ndarray],
    times: np.ndarray,
    medium: Medium | str,
    path: str | os.PathLike,
    fps: float = 30,
    **kw,
) -> Path:
    """Render the animals at ``fps`` frames per second to an MP4 at ``path``; returns the path."""
    from zoetic.viz.video import write_mp4

    times = np.asarray(times, float).reshape(-1)
    bodies, positions = _as_lists(bodies, positions, len(times))
    mk = kw.get("markers")
    moving = mk is not None and np.ndim(mk) == 3 and len(mk) == len(times)  # (R, M, 3)
    t_new, pos_new = resample(
        [*positions, *([np.asarray(mk, float)] if moving else [])], times, fps
    )
    if moving:
        kw["markers"] = pos_new.pop()
    return write_mp4(render_frames(bodies, pos_new, t_new, medium, **kw), path, fps)
