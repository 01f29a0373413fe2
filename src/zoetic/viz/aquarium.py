"""Pictures of an aquarium's life: the fishes' minds as stacked timelines, and the tank's video
(a camera following the predator over the tank, the fishes in their species' skins, rocks,
seaweed and food, an intention tag over each fish placed clear of the others, a legend and a
map of the whole tank)."""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from zoetic.bodies import Body
from zoetic.viz.plots import save_figure

INTENTION_COLORS = {
    "avoid": "#7f7f7f",
    "escape": "#d62728",
    "school": "#1f77b4",
    "eat": "#2ca02c",
    "mate": "#e377c2",
    "hunt": "#8c564b",
    "wander": "#bcbd22",
    "leave": "#17becf",
}


def plot_minds(
    times: np.ndarray,
    drives: np.ndarray,
    intentions: np.ndarray,
    alive: np.ndarray,
    names: Sequence[str],
    intention_names: Sequence[str],
    path: str | os.PathLike,
) -> Path:
    """Draw hunger, libido and fear (K, n, 3) of each fish over time as stacked timelines,
    the chosen intention (K, n) as coloured bands beneath the curves; returns the path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    n = len(names)
    fig, axes = plt.subplots(n, 1, figsize=(10, 0.9 + 1.1 * n), sharex=True, squeeze=False)
    times = np.asarray(times, float)
    edges = np.append(times, times[-1] + (times[-1] - times[-2] if len(times) > 1 else 0.1))
    for i, ax in enumerate(axes[:, 0]):
        it = intentions[:, i]
        start = 0
        for k in range(1, len(it) + 1):
            if k == len(it) or it[k] != it[start]:
                col = INTENTION_COLORS.get(intention_names[it[start]], "#dddddd")
                ax.axvspan(edges[start], edges[k], color=col, alpha=0.3, lw=0)
                start = k
        dead = ~alive[:, i]
        if dead.any():
            ax.axvspan(times[np.argmax(dead)], edges[-1], color="black", alpha=0.5, lw=0)
        ax.plot(times, drives[:, i, 0], color="#2ca02c", lw=1.2, label="hunger")
        ax.plot(times, drives[:, i, 1], color="#e377c2", lw=1.2, label="libido")
        ax.plot(times, drives[:, i, 2], color="#d62728", lw=1.2, label="fear")
        ax.set_ylim(-0.02, 1.05)
        ax.set_ylabel(names[i], rotation=0, ha="right", va="center", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[-1, 0].set_xlabel("time (s)")
    lines = axes[0, 0].get_legend_handles_labels()[0]
    bands = [
        Patch(color=INTENTION_COLORS[k], alpha=0.4, label=k)
        for k in intention_names
        if k in INTENTION_COLORS
    ]
    axes[0, 0].legend(
        handles=[*lines, *bands, Patch(color="black", alpha=0.5, label="caught")],
        ncol=12,
        fontsize=7,
        loc="lower left",
        bbox_to_anchor=(0, 1.02),
        frameon=False,
    )
    return save_figure(fig, path, dpi=100)


FOOD = (250.0, 150, 30)
ROCK = np.array([150.0, 132, 108])
WEED = np.array([46.0, 132, 64])
FOG = 14.0  # m: the tank's water is clear (the fishes' view range is 6 m)
NEAR = 9.0  # m: fishes nearer the camera are drawn with the finer skin (16x the lattice's)
BOX, CYLINDER = 0, 1  # physics.objects' kinds of fixed shape


def follow_camera(
    nodes: np.ndarray, times: np.ndarray, half_size: float, distance: float, side: float = 65.0
):
    """Return (R, 3) eyes and targets of a camera following a fish (its nodes (R, N, 3), the
    nose first): aimed at its centre smoothed over a second and kept inside the tank, from
    ``side`` degrees off its heading (smoothed over two seconds, so the fish is seen from the
    side and the view turns slowly), 48 degrees above, ``distance`` m away."""
    from scipy.ndimage import gaussian_filter1d

    from zoetic.viz.render3d import _fill_nan

    nodes = np.asarray(nodes, float)
    target = _fill_nan(nodes.mean(axis=1))
    fwd = _fill_nan(nodes[:, 0] - nodes.mean(axis=1))
    heading = np.unwrap(np.arctan2(fwd[:, 2], fwd[:, 0]))  # forward = (cos, 0, sin)
    dt = float(np.median(np.diff(times))) if len(times) > 1 else 1.0
    if len(times) > 1:
        target = gaussian_filter1d(target, 1.0 / max(dt, 1e-6), axis=0, mode="nearest")
        heading = gaussian_filter1d(heading, 2.0 / max(dt, 1e-6), mode="nearest")
    target[:, [0, 2]] = np.clip(target[:, [0, 2]], -0.8 * half_size, 0.8 * half_size)
    az, el = heading + np.radians(side), np.radians(48.0)
    direction = np.stack(
        [-np.cos(el) * np.cos(az), np.full_like(az, np.sin(el)), -np.cos(el) * np.sin(az)], 1
    )
    return target + distance * direction, target


def _blocks(c: np.ndarray, half: np.ndarray, a: np.ndarray, b: np.ndarray) -> bool:
    """Return whether the box (centre, half sizes) crosses the segment from a to b."""
    d = b - a
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = (c - half - a) / d
        t1 = (c + half - a) / d
    lo = np.where(d == 0, np.where(np.abs(a - c) <= half, -np.inf, np.inf), np.minimum(t0, t1))
    hi = np.where(d == 0, np.where(np.abs(a - c) <= half, np.inf, -np.inf), np.maximum(t0, t1))
    return bool(max(lo.max(), 0.0) <= min(hi.min(), 1.0))


def _static_items(
    statics, view: tuple, times_r: float, focus=None, weed: bool = True
) -> tuple[list, list]:
    """Painter items of the rocks (shaded boxes) and, when ``weed``, seaweed as a picture of
    swaying blades (fixed plants), and apart the faces of rocks that stand between the eye
    and the point ``focus`` (drawn see-through)."""
    from zoetic.viz.render3d import project_points, water_tint

    eye, rot, focal, size, medium = view
    kinds, centers, sizes, names = statics
    items: list[tuple] = []
    ghosts: list[tuple] = []
    for kind, c, sz, name in zip(kinds, centers, sizes, names, strict=True):
        if name == "wall":
            continue
        if kind == BOX:
            c, sz = np.asarray(c, float), np.asarray(sz, float)
            hides = focus is not None and _blocks(c, sz, eye, np.asarray(focus, float))
            (ghosts if hides else items).extend(_box_items(c, sz, view))
            continue
        if not weed:
            continue
        r, half = float(sz[0]), float(sz[1])
        for k in range(7):
            a = 2.4 * k
            root = np.asarray(c, float) + [0.6 * r * np.cos(a), -half, 0.6 * r * np.sin(a)]
            h = np.linspace(0.0, 1.0, 7)
            sway = 0.25 * np.sin(1.3 * times_r + k + 2 * h) * h
            pts = root + np.stack([sway, 2 * half * h * (0.7 + 0.05 * k), 0.5 * sway], 1)
            scr, z = project_points(pts, eye, rot, focal, size)
            if (z <= 0.1).any():
                continue
            col = water_tint((WEED * (0.8 + 0.05 * k))[None], pts.mean(0)[None], eye, medium, FOG)
            wpx = max(2.0, focal * 0.12 / float(z.mean()))
            rgb = tuple(np.clip(col[0], 0, 255).astype(int))
            items.append((float(z.mean()), 2, (scr.ravel().tolist(), wpx), rgb))
    return items, ghosts


def _strand_items(nodes: np.ndarray, view: tuple, width: float = 0.08) -> list[tuple]:
    """Painter items of dynamic seaweed: every strand (its nodes (S, M, 3) now) as thick
    segments ``width`` m wide, in the shape the simulation gave it."""
    from zoetic.viz.render3d import project_points, water_tint

    eye, rot, focal, size, medium = view
    s, m = nodes.shape[:2]
    mid = 0.5 * (nodes[:, 1:] + nodes[:, :-1]).reshape(-1, 3)
    shade = np.repeat(0.8 + 0.05 * (np.arange(s) % 7), m - 1)[:, None]
    col = np.clip(water_tint(WEED[None] * shade, mid, eye, medium, FOG), 0, 255).astype(int)
    scr, z = project_points(nodes.reshape(-1, 3), eye, rot, focal, size)
    scr, z = scr.reshape(s, m, 2), z.reshape(s, m)
    items = []
    for k in range(s):
        for j in range(m - 1):
            zz = 0.5 * (z[k, j] + z[k, j + 1])
            if min(z[k, j], z[k, j + 1]) <= 0.1:
                continue
            line = (scr[k, j : j + 2].ravel().tolist(), max(2.0, focal * width / zz))
            items.append((float(zz), 2, line, tuple(col[k * (m - 1) + j].tolist())))
    return items


def _see_through(img, items: list[tuple], alpha: int = 90):
    """Return the picture with polygon items laid over it, mostly transparent."""
    from PIL import Image, ImageDraw

    if not items:
        return img
    layer = Image.new("RGBA", img.size, (0, 0, 0, 0))
    d = ImageDraw.Draw(layer)
    for _, _, geom, col in sorted(items, key=lambda it: -it[0]):
        d.polygon(geom, fill=(*col, alpha), outline=(*col, 200))
    return Image.alpha_composite(img.convert("RGBA"), layer).convert("RGB")


def _box_items(c: np.ndarray, half: np.ndarray, view: tuple) -> list[tuple]:
    """Painter items of a rock: the box's faces turned to the eye, lit from above."""
    from zoetic.viz.render3d import project_points, water_tint

    eye, rot, focal, size, medium = view
    items = []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = np.zeros(3)
            n[axis] = sign
            if np.dot(eye - (c + n * half), n) <= 0:
                continue
            u, v = [k for k in range(3) if k != axis]
            quad = []
            for du, dv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = c + n * half
                p[u] += du * half[u]
                p[v] += dv * half[v]
                quad.append(p)
            quad = np.array(quad)
            scr, z = project_points(quad, eye, rot, focal, size)
            if (z <= 0.1).any():
                continue
            light = 0.55 + 0.45 * max(n[1], 0.0) + 0.15 * n[0]
            col = water_tint((ROCK * light)[None], quad.mean(0)[None], eye, medium, FOG)[0]
            rgb = tuple(np.clip(col, 0, 255).astype(int))
            items.append((float(z.mean()), 0, scr.ravel().tolist(), rgb))
    return items


def tank_frames(
    bodies: Sequence[Body],
    positions: Sequence[np.ndarray],
    times: np.ndarray,
    colors: Sequence[tuple[int, int, int]],
    obstacles: np.ndarray,
    food: np.ndarray,
    eaten: np.ndarray,
    labels: Sequence[Sequence[str]] | None,
    half_size: float,
    size: tuple[int, int] = (768, 432),
    looks: Sequence[str] | None = None,
    statics=None,
    focus: int = 0,
    plants: np.ndarray | None = None,
) -> Iterator[np.ndarray]:
    """Yield the tank's frames: a camera following fish ``focus`` (the predator) over the
    tank, the fishes in their species' looks (``looks``, else plain ``colors``), rocks and
    seaweed (``statics``: kind, centre, size and name of each fixed shape; without them the
    ``obstacles`` as grey buoys), uneaten food as orange buoys, and, when ``labels`` (R, n)
    ("name: intention") are given, each fish's intention as a tag and a legend; ``plants``
    (R, S, M, 3): dynamic seaweed's strands, drawn in their simulated shape."""
    scene = _scene(bodies, positions[focus], times, colors, looks, half_size, size, statics)
    obstacles = np.asarray(obstacles, float).reshape(-1, 3)
    for r in range(len(scene["times"])):
        pos = [np.asarray(p[r], float) for p in positions]
        strands = None if plants is None else np.asarray(plants[r], float)
        shapes = (statics, obstacles, strands)
        yield _frame(scene, r, pos, focus, food[r][~eaten[r]], shapes, labels)


def _scene(bodies, followed, times, colors, looks, half_size, size, statics) -> dict:
    """Return what every frame of ``tank_frames`` shares: the skins (fine, and coarse for
    fishes far from the camera), the camera's rays and its path following the fish whose
    nodes are ``followed`` (R, N, 3), the floor, the fonts and each fish's colour."""
    from zoetic.physics.media import get_medium
    from zoetic.viz.paint import label_font
    from zoetic.viz.render3d import animal_skins

    times = np.asarray(times, float)
    skins = animal_skins(bodies, colors, looks)
    w, h = size
    focal = 0.5 * h / np.tan(np.radians(50.0) / 2)  # a 50 degree field of view
    eyes, targets = follow_camera(followed, times, half_size, distance=7.0)
    return {
        "medium": get_medium("water"),
        "times": times,
        "skins": skins,
        "coarse": animal_skins(bodies, colors, looks, levels=1),
        "focal": focal,
        "size": size,
        "rays": (
            ((np.arange(w) + 0.5 - w / 2) / focal).astype(np.float32),
            ((h / 2 - np.arange(h) - 0.5) / focal).astype(np.float32),
        ),
        "camera": (eyes, targets),
        "floor": -2.0 if statics is None else float(np.min(statics[1][:, 1] - statics[2][:, 1])),
        "fonts": (label_font(max(12, h // 26)), label_font(max(11, h // 32))),
        "fish_rgb": [255.0 * s.face_colors.mean(axis=0) for s in skins],
        "looks": looks,
        "half_size": half_size,
    }


def _frame(scene: dict, r: int, pos, focus: int, left, shapes, labels) -> np.ndarray:
    """Return frame r of ``tank_frames`` (``scene``: ``_scene``): the fishes at ``pos``
    (the camera on fish ``focus``), the uneaten food ``left``, the ``shapes`` (statics,
    obstacles as buoys, dynamic seaweed's strands), the labels' tags and legend, the map and
    the clock."""
    from PIL import Image, ImageDraw

    from zoetic.viz.paint import paint_items
    from zoetic.viz.render3d import background, face_items, look_at, skins_mesh, skins_vertices

    statics, obstacles, strands = shapes
    (w, h), medium, t = scene["size"], scene["medium"], float(scene["times"][r])
    eyes, targets = scene["camera"]
    eye, rot = eyes[r], look_at(eyes[r], targets[r])
    view = (eye, rot, scene["focal"], scene["size"], medium)
    img = Image.fromarray(background(medium, eye, rot, *scene["rays"], scene["floor"], FOG))
    shown, dist = in_sight(pos, view)
    drawn = [scene["skins"][i] if dist[i] < NEAR else scene["coarse"][i] for i in shown]
    shown_pos = [pos[i] for i in shown]
    items = face_items(skins_vertices(drawn, shown_pos), skins_mesh(drawn), *view, fog=FOG)
    items += _buoys(left, FOOD, 0.1, view)
    ghosts: list[tuple] = []
    if statics is not None:
        solid, ghosts = _static_items(statics, view, t, pos[focus].mean(0), strands is None)
        items += solid
    if strands is not None:
        items += _strand_items(strands, view)
    else:
        items += _buoys(obstacles, (120.0, 120, 120), 0.4, view)
    paint_items(ImageDraw.Draw(img), items)
    img = _see_through(img, ghosts)
    draw = ImageDraw.Draw(img)
    font, small = scene["fonts"]
    if labels is not None:
        corner = (w - h // 3 - 16, 0, w, h // 3 + 60)  # the map and the species key
        taken = [(0, 0, 260, 34), corner, (0, h - 26, w, h)]
        _tags(draw, [labels[r][i] for i in shown], shown_pos, view, small, taken)
        _legend(draw, labels, h, small)
    fish_rgb = scene["fish_rgb"]
    _species_key(draw, scene["looks"], fish_rgb, w, h // 3 + 20, small)
    half = scene["half_size"]
    _minimap(img, pos, fish_rgb, left, statics, obstacles, half, targets[r], strands)
    caught = 0 if labels is None else sum(lb.endswith(": caught") for lb in labels[r])
    text = f"t = {t:5.1f} s" + (f"    caught {caught}" if labels is not None else "")
    draw.text((10, 8), text, font=font, **_STYLE)
    return np.array(img)


_STYLE = {"fill": (255, 255, 255), "stroke_width": 2, "stroke_fill": (0, 0, 0)}
FAR = 45.0  # m: fishes farther from the camera are lost in the fog (7/8 water) and not drawn


def in_sight(pos: list[np.ndarray], view: tuple) -> tuple[list[int], np.ndarray]:
    """Return the fishes (their nodes ``pos``) worth drawing in the view: nearer than ``FAR``
    to the eye, in front of it and within a body length of the picture; and every fish's
    distance (m) from the eye. A crowd of a thousand fishes mostly lies out of the picture."""
    from zoetic.viz.paint import project_points

    eye, rot, focal, size = view[:4]
    centre = np.array([np.nanmean(p, 0) for p in pos])
    dist = np.linalg.norm(centre - eye, axis=1)
    scr, z = project_points(centre, eye, rot, focal, size)
    margin = focal / np.maximum(z, 0.1)  # px a metre spans at the fish's depth
    inside = (scr[:, 0] > -margin) & (scr[:, 0] < size[0] + margin)
    inside &= (scr[:, 1] > -margin) & (scr[:, 1] < size[1] + margin)
    keep = (dist < FAR) & (z > -1.0) & (inside | (dist < 2.0))
    return np.flatnonzero(keep).tolist(), dist


def _buoys(points: np.ndarray, color, radius: float, view: tuple) -> list[tuple]:
    """Painter items of balls (food, or obstacles without their shapes) at ``points``."""
    from zoetic.viz.render3d import project_points, water_tint

    eye, rot, focal, size, medium = view
    if not len(points):
        return []
    scr, z = project_points(points, eye, rot, focal, size)
    col = water_tint(np.tile(np.asarray(color, float), (len(points), 1)), points, eye, medium, FOG)
    return [
        (float(z[i]), 1, (scr[i, 0], scr[i, 1], focal * radius / z[i]), col[i])
        for i in range(len(points))
        if z[i] > 0.1 + radius
    ]


def _tags(draw, labels: Sequence[str], pos: list[np.ndarray], view: tuple, font, taken) -> None:
    """Write each visible fish's intention over it in its intention's colour, clear of the
    other tags and of the boxes ``taken`` (``render3d.place_tags``)."""
    from PIL import ImageColor

    from zoetic.viz.paint import place_tags

    texts = [lb.split(": ", 1)[-1] for lb in labels]
    tags = [(t, ImageColor.getrgb(INTENTION_COLORS.get(t, "#ffffff"))) for t in texts]
    place_tags(draw, tags, pos, view, font, taken)


def _legend(draw, labels, height: int, font) -> None:
    """Draw the intentions that occur in the run as coloured swatches along the bottom."""
    from PIL import ImageColor

    seen = sorted(
        {lb.split(": ", 1)[-1] for row in labels[:: max(1, len(labels) // 50)] for lb in row}
    )
    x, y = 10, height - 22
    for name in seen:
        col = ImageColor.getrgb(
            INTENTION_COLORS.get(name, "#000000" if name == "caught" else "#ffffff")
        )
        draw.rectangle((x, y + 3, x + 12, y + 15), fill=col, outline=(255, 255, 255))
        draw.text((x + 16, y), name, font=font, **_STYLE)
        x += 26 + int(draw.textlength(name, font=font))


def _species_key(draw, looks, fish_rgb, width: int, top: int, font) -> None:
    """Name each species under the map, with a swatch of its mean colour."""
    if not looks:
        return
    y = top
    for name in dict.fromkeys(looks):
        rgb = tuple(np.clip(fish_rgb[list(looks).index(name)], 0, 255).astype(int).tolist())
        x = width - 8 - 18 - int(draw.textlength(name, font=font))
        draw.rectangle((x, y + 3, x + 12, y + 15), fill=rgb, outline=(255, 255, 255))
        draw.text((x + 16, y), name, font=font, **_STYLE)
        y += 18


def _minimap(img, pos, fish_rgb, food, statics, obstacles, half: float, target, strands=None):
    """Draw a map of the whole tank from above in the top right corner: rocks, seaweed (and
    its ``strands`` (S, M, 3) seen from above), food, every fish in its colour and a ring
    where the camera looks."""
    from PIL import Image, ImageDraw

    side = max(90, img.size[1] // 3)
    layer = Image.new("RGBA", img.size, (0, 0, 0, 0))
    d = ImageDraw.Draw(layer)
    x0, y0 = img.size[0] - side - 8, 8

    def at(p) -> tuple[float, float]:  # x right, z up on the map (seen from above)
        return x0 + side * (0.5 + 0.5 * p[0] / half), y0 + side * (0.5 - 0.5 * p[2] / half)

    d.rectangle(
        (x0, y0, x0 + side, y0 + side), fill=(10, 30, 50, 170), outline=(255, 255, 255, 200)
    )
    shapes = [] if statics is None else zip(*statics, strict=True)
    for kind, c, sz, name in shapes:
        if name == "wall":
            continue
        (cx, cy), k = at(c), side / (2 * half)
        if kind == BOX:
            d.rectangle(
                (cx - sz[0] * k, cy - sz[2] * k, cx + sz[0] * k, cy + sz[2] * k),
                fill=(150, 140, 125, 255),
            )
        else:
            d.ellipse(
                (cx - sz[0] * k, cy - sz[0] * k, cx + sz[0] * k, cy + sz[0] * k),
                fill=(60, 160, 80, 255),
            )
    if statics is None:
        for c in obstacles:
            cx, cy = at(c)
            d.ellipse((cx - 3, cy - 3, cx + 3, cy + 3), fill=(150, 150, 150, 255))
    for nodes in [] if strands is None else strands:
        d.line([at(p) for p in nodes], fill=(120, 230, 120, 255), width=1)
    for p in food:
        cx, cy = at(p)
        d.ellipse((cx - 1.5, cy - 1.5, cx + 1.5, cy + 1.5), fill=(250, 150, 30, 255))
    for p, rgb in zip(pos, fish_rgb, strict=True):
        if not np.isfinite(p).all():
            continue
        (hx, hy), (tx, ty) = at(p[0]), at(p[-1])
        d.line((tx, ty, hx, hy), fill=(*np.clip(rgb, 0, 255).astype(int).tolist(), 255), width=3)
    cx, cy = at(target)
    d.ellipse((cx - 6, cy - 6, cx + 6, cy + 6), outline=(255, 255, 255, 230), width=1)
    img.alpha_composite(layer) if img.mode == "RGBA" else img.paste(
        Image.alpha_composite(img.convert("RGBA"), layer).convert("RGB")
    )


def write_tank_video(path: str | os.PathLike, fps: float = 15.0, **kw) -> Path:
    """Write the tank's frames (``tank_frames`` arguments) to an MP4; returns the path."""
    from zoetic.viz.video import write_mp4

    return write_mp4(tank_frames(**kw), path, fps)
