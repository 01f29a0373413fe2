"""Pictures of stunts: what the style terms read, over the stunt's time."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from zoetic.render.skin import body_skin
from zoetic.render.skin import subdivision as subdivision  # the display surface's map


def plot_score(
    times: np.ndarray,
    series: Mapping[str, np.ndarray],
    path: str | Path,
    starts: Sequence[float] = (),
    title: str = "",
) -> Path:
    """Write one panel per named series (R,) over ``times`` (R,), with the plan's segment
    starts (s) as dotted lines and the instants wholly out of the water shaded when a series 'nodes
    out of water' (a fraction, 1 = all) is given; returns the path."""
    from zoetic.viz.plots import new_figure, save_figure

    n = max(1, len(series))
    fig = new_figure((7.0, 1.6 * n + 0.6), dpi=110)
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    out = np.asarray(series.get("nodes out of water", []), float)
    for ax, (label, y) in zip(axes, series.items(), strict=False):
        ax.plot(times, y, lw=1.5)
        ax.set_ylabel(label, fontsize=8)
        if out.shape == np.shape(times):
            ax.fill_between(
                times,
                0,
                1,
                where=out >= 1.0,
                color="tab:orange",
                alpha=0.2,
                transform=ax.get_xaxis_transform(),
                lw=0,
            )
        for s in starts:
            ax.axvline(s, color="0.5", ls=":", lw=0.8)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time (s)  (dotted: a new entry starts; shaded: wholly in the air)")
    if title:
        axes[0].set_title(title, fontsize=9)
    return save_figure(fig, path)


# ---------------------------------------------------------------- the stunt's video

_BALL_COLOR = np.array([236.0, 70, 60])
_POST_COLOR = np.array([222.0, 214, 196])
_BAR_COLOR = np.array([250.0, 196, 40])
_TILE_COLORS = (np.array([206.0, 226, 232]), np.array([180.0, 208, 220]))
_COPING = np.array([236.0, 232, 222])
_WATER_SHEET = (64, 160, 200, 70)  # RGBA of the surface drawn over what is under it
_SPRAY = np.array([236.0, 246, 255])


@dataclass(frozen=True)
class Pool:
    """The pool drawn around a stunt (display only: the physics has open water).

    depth: its floor below the surface (m); margin: the end walls beyond the stunt's extent
    along x, and the far wall beyond it along z (m); rim: the walls' height above the water."""

    depth: float = 4.0
    margin: float = 2.0
    rim: float = 0.3


def deep_enough(pool: Pool, deepest: float, room: float = 1.0) -> Pool:
    """Return the pool with its floor at least ``room`` m below the deepest point drawn
    (``deepest``: m below the surface), so a dive from a deep start stays above the floor."""
    return replace(pool, depth=max(pool.depth, deepest + room))


def stunt_camera(
    points: np.ndarray,
    times: np.ndarray,
    size: tuple[int, int],
    fov: float,
    direction: np.ndarray,
    window: float = 0.5,
    smoothing: float = 0.4,
    level: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Return (R, 3) eyes and targets of a camera that frames the whole stunt: at each record
    the bounding box of ``points`` (R, M, 3: body, balls, hurdle) over the surrounding
    ``window`` s, its centre smoothed over ``smoothing`` s, seen from ``direction`` (unit, from
    the target to the eye) at one distance that fits the largest such box."""
    from scipy.ndimage import gaussian_filter1d, maximum_filter1d, minimum_filter1d

    pts = np.asarray(points, float)
    lo = np.nanmin(np.where(np.isfinite(pts), pts, np.inf), axis=1)
    hi = np.nanmax(np.where(np.isfinite(pts), pts, -np.inf), axis=1)
    ok = np.isfinite(lo).all(1) & np.isfinite(hi).all(1)
    lo[~ok], hi[~ok] = lo[ok][0] if ok.any() else 0.0, hi[ok][0] if ok.any() else 1.0
    steps = np.diff(times)
    dt = float(np.median(steps[steps > 0])) if (steps > 0).any() else 1.0
    w = min(len(times), max(1, int(round(window / dt))))
    lo = minimum_filter1d(lo, 2 * w + 1, axis=0, mode="nearest")
    hi = maximum_filter1d(hi, 2 * w + 1, axis=0, mode="nearest")
    centre = 0.5 * (lo + hi)
    if len(times) > 1:
        centre = gaussian_filter1d(centre, max(smoothing / dt, 1e-3), axis=0, mode="nearest")
    half = 0.5 * (hi - lo).max(axis=0) + 0.15  # the largest box, plus a margin
    tan = np.tan(np.radians(fov) / 2)
    right = np.array([direction[2], 0.0, -direction[0]])
    right /= max(float(np.linalg.norm(right)), 1e-9)
    up = np.cross(direction, right)
    width, height = float(half @ np.abs(right)), float(half @ np.abs(up))
    dist = max(height / tan, width / (size[0] / size[1] * tan)) + 0.5 * half @ np.abs(direction)
    eye = centre + dist * direction
    eye[:, 1] = np.maximum(eye[:, 1], level + 0.15 * dist)  # above the water
    return eye, centre


def _quad_items(quads, colors, eye, rot, focal, size, medium) -> list[tuple]:
    """Painter items for flat polygons (k, 3) split at the water surface, tinted below it."""
    from zoetic.viz.render3d import project_points, split_at_level, water_tint

    level = medium.water_level
    items = []
    for q, col in zip(quads, colors, strict=True):
        for part in split_at_level(np.asarray(q, float), level):
            if len(part) < 3:
                continue
            _, z = project_points(part, eye, rot, focal, size)
            if (z <= 0.05).any():
                continue
            c = water_tint(np.asarray(col, float)[None], part.mean(0)[None], eye, medium)[0]
            flat = project_points(part, eye, rot, focal, size)[0].ravel().tolist()
            items.append((float(z.max()), 0, flat, tuple(np.clip(c, 0, 255).astype(int))))
    return items


def _pool_quads(lo: np.ndarray, hi: np.ndarray, pool: Pool, level: float, eye: np.ndarray):
    """The pool's far and end walls as tiled bands (quads, colours), the near side left open."""
    x0, x1 = lo[0] - pool.margin, hi[0] + pool.margin
    zfar = hi[2] + pool.margin if eye[2] < 0.5 * (lo[2] + hi[2]) else lo[2] - pool.margin
    znear = 2 * (0.5 * (lo[2] + hi[2])) - zfar
    bottom, top = level - pool.depth, level + pool.rim
    quads, colors = [], []
    bands = np.arange(bottom, level, 0.5).tolist() + [level, top]
    for k, (y0, y1) in enumerate(zip(bands[:-1], bands[1:], strict=True)):
        col = _COPING if y0 >= level else _TILE_COLORS[k % 2]
        quads.append([[x0, y0, zfar], [x1, y0, zfar], [x1, y1, zfar], [x0, y1, zfar]])
        colors.append(col)
        for x in (x0, x1):
            quads.append([[x, y0, znear], [x, y0, zfar], [x, y1, zfar], [x, y1, znear]])
            colors.append(0.9 * col)
    return quads, colors, (x0, x1, min(zfar, znear), max(zfar, znear))


def stunt_frames(
    body,
    positions: np.ndarray,
    times: np.ndarray,
    medium,
    objects=(),
    balls: np.ndarray | None = None,
    size: tuple[int, int] = (640, 360),
    pool: Pool | None = None,
    title: str = "",
    azimuth: float = 75.0,
    elevation: float = 14.0,
    fov: float = 45.0,
):
    """Yield (H, W, 3) uint8 frames of a stunt: the dolphin as a smooth shaded surface over its
    lattice, the pool (floor, walls, a translucent tinted surface), the trick's ball, post and
    bar, and spray where the body crosses the surface; the camera frames the whole stunt.

    positions (R, N, 3) and balls (R, K, 3) at ``times`` (R,); objects: the trick's objects."""
    from PIL import Image

    from zoetic.physics.media import get_medium
    from zoetic.render.skin import skin_vertices
    from zoetic.viz.paint import label_font
    from zoetic.viz.render3d import background, face_items, look_at, skins_mesh
    from zoetic.viz.spray import spray_particles, surface_crossings

    medium = get_medium(medium)
    level = medium.water_level if abs(medium.water_level) < 1e8 else 0.0
    times = np.asarray(times, float)
    pos = np.asarray(positions, float)
    pool = pool or deep_enough(Pool(), level - float(pos[..., 1].min()))
    bl, radii, fixed = _stunt_objects(objects, balls, len(times))
    frame_pts = _framed_points(pos, bl, radii, fixed)
    az, el = np.radians(azimuth), np.radians(elevation)
    direction = np.array([-np.cos(el) * np.cos(az), np.sin(el), -np.cos(el) * np.sin(az)])
    eyes, targets = stunt_camera(frame_pts, times, size, fov, direction, level=level)
    every = _framed_points(pos, bl, radii, fixed, near=np.inf)  # the pool holds them all
    fin = np.isfinite(every).all(axis=2)
    lo = np.min(np.where(fin[..., None], every, np.inf), axis=(0, 1))
    hi = np.max(np.where(fin[..., None], every, -np.inf), axis=(0, 1))
    quads, qcols, (px0, px1, pz0, pz1) = _pool_quads(lo, hi, pool, level, eyes[0])
    skin = body_skin(body)
    mesh = skins_mesh([skin])
    spray = spray_particles(surface_crossings(body, pos, times, level), level, medium.gravity)
    w, h = size
    focal = 0.5 * h / np.tan(np.radians(fov) / 2)
    xs = ((np.arange(w) + 0.5 - w / 2) / focal).astype(np.float32)
    ys = ((h / 2 - np.arange(h) - 0.5) / focal).astype(np.float32)
    font = label_font(max(10, h // 22))
    sheet = [[px0, level, pz0], [px1, level, pz0], [px1, level, pz1], [px0, level, pz1]]
    for r in range(len(times)):
        eye, rot = eyes[r], look_at(eyes[r], targets[r])
        img = Image.fromarray(background(medium, eye, rot, xs, ys, level - pool.depth))
        verts = skin_vertices(skin, np.nan_to_num(pos[r]))
        view = (eye, rot, focal, size, medium, level)
        below, above = [], []
        _wall_items(quads, qcols, view, below, above)
        _fixed_items(fixed, view, level - pool.depth, below, above)
        _ball_items(bl[r], radii, view, below, above)
        below += face_items(verts, mesh, eye, rot, focal, size, medium, side=-1)
        above += face_items(verts, mesh, eye, rot, focal, size, medium, side=1)
        _spray_items(spray(times[r]), view, above)
        label = f"t = {times[r]:.2f} s" + (f"   {title}" if title else "")
        yield _compose(img, below, above, np.asarray(sheet, float), view, label, font)


def _stunt_objects(objects, balls: np.ndarray | None, records: int) -> tuple:
    """Return the balls' recorded centres (R, K, 3), their radii (K,) (0.15 m for a ball
    without an object) and the fixed objects (posts, bars, boxes) of a trick's ``objects``."""
    from zoetic.physics.objects import Ball, Box, Cylinder

    nb = 0 if balls is None else np.asarray(balls).shape[1]
    bl = np.zeros((records, 0, 3)) if balls is None else np.asarray(balls, float)
    ball_objs = [o for o in objects if isinstance(o, Ball)]
    fixed = [o for o in objects if isinstance(o, Cylinder | Box)]
    radii = np.array([ball_objs[k].radius if k < len(ball_objs) else 0.15 for k in range(nb)])
    return bl, radii, fixed


def _framed_points(
    pos: np.ndarray, bl: np.ndarray, radii: np.ndarray, fixed, near: float = 3.0
) -> np.ndarray:
    """Return (R, M, 3) points the camera keeps in view: the body's nodes, and each ball's
    extent along the axes and the fixed objects' ends while within ``near`` body lengths of
    the body (NaN when farther, so the body is never framed out for a distant object)."""
    fp = _fixed_points(fixed)
    ball_box = [bl + radii[:, None] * np.eye(3)[i] * sign for i in range(3) for sign in (-1, 1)]
    objs = np.concatenate([*ball_box, np.broadcast_to(fp, (len(pos), *fp.shape))], axis=1)
    centre = np.nanmean(pos, axis=1, keepdims=True)
    first = pos[int(np.argmax(np.isfinite(pos).all(axis=(1, 2))))]
    length = float(np.ptp(np.nan_to_num(first), axis=0).max())
    far = np.linalg.norm(objs - centre, axis=2) > near * max(length, 0.1)
    return np.concatenate([pos, np.where(far[..., None], np.nan, objs)], axis=1)


def _wall_items(quads, colors, view: tuple, below: list, above: list) -> None:
    """Append painter items of the pool's walls to ``below`` and ``above`` the water."""
    eye, rot, focal, size, medium, level = view
    for q, c in zip(quads, colors, strict=True):
        for it in _quad_items([q], [c], eye, rot, focal, size, medium):
            (above if np.mean(np.asarray(q)[:, 1]) >= level else below).append(it)


def _spray_items(drops: np.ndarray, view: tuple, above: list) -> None:
    """Append painter items of the spray drops in the air (D, 3) to ``above``."""
    from zoetic.viz.render3d import project_points

    eye, rot, focal, size, _, _ = view
    for p in drops:
        scr, z = project_points(p[None], eye, rot, focal, size)
        if z[0] > 0.05:
            above.append(
                (float(z[0]), 3, (scr[0, 0], scr[0, 1], max(1.5, focal * 0.025 / z[0])), _SPRAY)
            )


def _fixed_points(fixed) -> np.ndarray:
    """Return (M, 3) points the camera keeps in view for the fixed objects: a post's top, a
    bar's two ends, a box's two corners."""
    from zoetic.physics.objects import Cylinder

    pts = []
    for o in fixed:
        c = np.asarray(o.center, float)
        if isinstance(o, Cylinder):
            d = np.zeros(3)
            d["xyz".index(o.axis)] = 0.5 * o.length
            top = c + d
            pts += [top, c - d] if o.axis != "y" else [top]
        else:
            pts += [c - o.half_size, c + o.half_size]
    return np.asarray(pts).reshape(-1, 3)


def _fixed_items(fixed, view: tuple, floor: float, below: list, above: list) -> None:
    """Append painter items of the posts and bars (thick segments, split at the surface) to
    ``below`` and ``above`` the water; a post stands on the floor, a bar on two stands."""
    from zoetic.physics.objects import Cylinder
    from zoetic.viz.render3d import project_points, water_tint

    eye, rot, focal, size, medium, level = view
    for o in fixed:
        if not isinstance(o, Cylinder):
            continue
        c = np.asarray(o.center, float)
        d = np.zeros(3)
        d["xyz".index(o.axis)] = 0.5 * o.length
        col = _BAR_COLOR if o.axis != "y" else _POST_COLOR
        ends = np.stack([c - d, c + d])
        if o.axis == "y":  # a post stands on the pool's floor
            ends[0, 1] = min(ends[0, 1], floor)
        segments = [(ends, col)]
        if o.axis != "y":  # a bar rests on two stands at its ends
            segments += [(np.stack([e, [e[0], floor, e[2]]]), _POST_COLOR) for e in ends]
        parts = [(p, cl) for seg, cl in segments for p in _segment_split(seg, level)]
        for part, col in parts:
            scr, z = project_points(part, eye, rot, focal, size)
            if (z > 0.05).all():
                tint = water_tint(col[None], part.mean(0)[None], eye, medium)[0]
                wpx = max(2.0, 2 * focal * o.radius / z.mean())
                it = (
                    float(z.mean()),
                    2,
                    (scr.ravel().tolist(), wpx),
                    tuple(np.clip(tint, 0, 255).astype(int)),
                )
                (above if part[:, 1].mean() >= level else below).append(it)


def _ball_items(
    balls: np.ndarray, radii: np.ndarray, view: tuple, below: list, above: list
) -> None:
    """Append painter items of the balls at one frame ((K, 3) m) to ``below``/``above``."""
    from zoetic.viz.render3d import project_points, water_tint

    eye, rot, focal, size, medium, level = view
    for k in range(len(radii)):
        rad = radii[k]
        scr, z = project_points(balls[k][None], eye, rot, focal, size)
        if z[0] > 0.05 + rad:
            tint = water_tint(_BALL_COLOR[None], balls[k][None], eye, medium)[0]
            it = (float(z[0]), 1, (scr[0, 0], scr[0, 1], focal * rad / z[0]), tint)
            (above if balls[k, 1] >= level else below).append(it)


def _compose(
    img, below: list, above: list, sheet: np.ndarray, view: tuple, label: str, font
) -> np.ndarray:
    """Return the frame: what is under water, the translucent surface sheet, what is above,
    and the label."""
    from PIL import Image, ImageDraw

    from zoetic.viz.paint import paint_items
    from zoetic.viz.render3d import TEXT_STYLE, project_points

    eye, rot, focal, size, _, _ = view
    paint_items(ImageDraw.Draw(img), below)
    layer = Image.new("RGBA", img.size, (0, 0, 0, 0))
    scr, z = project_points(sheet, eye, rot, focal, size)
    if (z > 0.05).all():
        ImageDraw.Draw(layer).polygon(scr.ravel().tolist(), fill=_WATER_SHEET)
    img = Image.alpha_composite(img.convert("RGBA"), layer).convert("RGB")
    draw = ImageDraw.Draw(img)
    paint_items(draw, above)
    draw.text((8, 6), label, font=font, **TEXT_STYLE)
    return np.array(img)


def _segment_split(ends: np.ndarray, level: float) -> list[np.ndarray]:
    """Return a segment (2, 3) as its parts above and below y = level."""
    a, b = ends
    sa, sb = a[1] - level, b[1] - level
    if sa * sb >= 0:
        return [ends]
    p = a + (b - a) * (sa / (sa - sb))
    return [np.stack([a, p]), np.stack([p, b])]


def render_stunt_video(
    body,
    positions: np.ndarray,
    times: np.ndarray,
    medium,
    path: str | Path,
    objects=(),
    balls: np.ndarray | None = None,
    fps: float = 30,
    macro: str | Path | None = None,
    **kw,
) -> Path:
    """Write the stunt's video (``stunt_frames`` at ``fps``) to an MP4; returns the path.
    With the stunt's ``macro`` (macro.json), a record that ends with the body out of the
    water is replayed further, so the clip runs on until after re-entry."""
    from zoetic.viz.render3d import resample
    from zoetic.viz.video import write_mp4

    if macro is not None:
        times, positions, balls = through_reentry(body, macro, times, positions, balls, medium)
    times = np.asarray(times, float)
    arrays = [np.asarray(positions, float)]
    if balls is not None and np.asarray(balls).shape[1]:
        arrays.append(np.asarray(balls, float))
    t_new, res = resample(arrays, times, fps)
    bl = res[1] if len(res) > 1 else None
    return write_mp4(stunt_frames(body, res[0], t_new, medium, objects, bl, **kw), path, fps)


def settled_after(positions: np.ndarray, times: np.ndarray, level: float) -> float | None:
    """Return the time (s) the body was last wholly back under the surface after its last
    moment with a node in the air, or None if it is still (partly) out at the end."""
    out = np.nanmax(np.asarray(positions, float)[..., 1], axis=1) > level
    if not out.any():
        return float(times[0])
    last = int(np.flatnonzero(out)[-1])
    return None if last == len(times) - 1 else float(times[last + 1])


def through_reentry(
    body, macro, times, positions, balls, medium, after: float = 0.8, most: float = 4.0
) -> tuple:
    """Return (times, positions, balls) of the stunt, replayed from ``macro`` for up to
    ``most`` s more when the record ends less than ``after`` s past the body's re-entry, and
    cut ``after`` s past it (the record as it is when it already shows the re-entry)."""
    from zoetic.behavior.stunts import replay
    from zoetic.physics.media import get_medium

    level = get_medium(medium).water_level
    level = level if abs(level) < 1e8 else 0.0
    times = np.asarray(times, float)
    back = settled_after(positions, times, level)
    if back is not None and times[-1] >= back + after:
        return times, positions, balls
    traj, bl = replay(body, macro, float(times[-1] - times[0]) + most)
    t, pos = np.asarray(traj.times, float), np.asarray(traj.positions[0], float)
    back = settled_after(pos, t, level)
    keep = t <= (t[-1] if back is None else back + after)
    return t[keep], pos[keep], None if bl is None or not np.shape(bl)[1] else bl[keep]


def frame_strip(frames: Sequence[np.ndarray], path: str | Path, labels: Sequence[str] = ()) -> Path:
    """Write frames side by side (a strip like Plate 5 (a)-(d)) with optional labels; returns
    the path."""
    import io

    from PIL import Image, ImageDraw

    from zoetic.io import atomic_write_bytes
    from zoetic.viz.paint import label_font
    from zoetic.viz.render3d import TEXT_STYLE

    h, w = frames[0].shape[:2]
    strip = Image.new("RGB", (w * len(frames), h))
    draw = ImageDraw.Draw(strip)
    for k, f in enumerate(frames):
        strip.paste(Image.fromarray(np.asarray(f, np.uint8)), (k * w, 0))
        if k < len(labels):
            font = label_font(max(10, h // 22))
            draw.text((k * w + 8, h - 24), labels[k], font=font, **TEXT_STYLE)
    buf = io.BytesIO()
    strip.save(buf, format="PNG")
    return atomic_write_bytes(path, buf.getvalue())
