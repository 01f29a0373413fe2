"""Drawing on a frame with Pillow: where world points land on the picture, painter items far
to near (triangles, balls, thick segments, drops), shaded buoys, and text tags over animals
that never overlap."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from PIL import ImageDraw, ImageFont


def project_points(pts: np.ndarray, eye, rot, focal: float, size) -> tuple[np.ndarray, np.ndarray]:
    """Return screen coordinates (..., 2) and camera depths (...) of world points."""
    cam = (pts - eye) @ rot.T
    z = cam[..., 2]
    zs = np.where(z > 1e-3, z, 1e-3)
    lim = 4.0 * max(size)
    sx = np.clip(size[0] / 2 + focal * cam[..., 0] / zs, -lim, lim)
    sy = np.clip(size[1] / 2 - focal * cam[..., 1] / zs, -lim, lim)
    return np.stack([sx, sy], axis=-1), z


def draw_buoy(draw: ImageDraw.ImageDraw, x: float, y: float, r: float, col: np.ndarray) -> None:
    """Draw a shaded ball at pixel (x, y), radius r px (at least 1.5), base colour col RGB."""
    r = max(r, 1.5)
    for k, (scale, off) in enumerate(((1.0, 0.0), (0.75, 0.15), (0.4, 0.35), (0.15, 0.45))):
        c = tuple(np.clip(col * (0.55 + 0.3 * k) + 40 * (k == 3), 0, 255).astype(int).tolist())
        cx, cy, rr = x - off * r, y - off * r, scale * r
        draw.ellipse((cx - rr, cy - rr, cx + rr, cy + rr), fill=c)


def paint_items(draw: ImageDraw.ImageDraw, items: list[tuple]) -> None:
    """Draw painter items far to near: 0 polygons, 1 balls, 2 thick segments, 3 drops."""
    for _, kind, geom, col in sorted(items, key=lambda it: -it[0]):
        if kind == 0:
            draw.polygon(geom, fill=col, outline=col)
        elif kind == 1:
            draw_buoy(draw, *geom, np.asarray(col, float))
        elif kind == 2:
            draw.line(geom[0], fill=col, width=int(round(geom[1])))
        else:
            x, y, rr = geom
            c = tuple(int(v) for v in col)
            draw.ellipse((x - rr, y - rr, x + rr, y + rr), fill=c)


def place_tags(draw, tags, points, view: tuple, font, taken=()) -> list[tuple]:
    """Write each text over its animal (tags: (text, RGB); points: (N_i, 3) nodes each), the
    nearest animals' first, each moved up until it overlaps no tag already placed nor the
    boxes ``taken`` (l, t, r, b px); a tag with no room left is not written. Returns the
    boxes used."""
    eye, rot, focal, size = view[:4]
    placed = [tuple(b) for b in taken]
    dist = [float(np.linalg.norm(np.nanmean(p, 0) - eye)) for p in points]
    for i in np.argsort(dist):
        scr, z = project_points(np.asarray(points[i], float), eye, rot, focal, size)
        good = (z > 0.05) & np.isfinite(scr).all(axis=1)
        if not good.any() or not tags[i][0]:
            continue
        x, y = float(scr[good, 0].mean()), float(scr[good, 1].min()) - 5
        if not (0 <= x <= size[0] and 0 <= y <= size[1]):
            continue
        box = list(draw.textbbox((x, y), tags[i][0], font=font, anchor="md", stroke_width=2))
        for _ in range(8):
            if not any(
                box[0] < q[2] and box[2] > q[0] and box[1] < q[3] and box[3] > q[1] for q in placed
            ):
                break
            shift = box[3] - box[1] + 2
            y, box[1], box[3] = y - shift, box[1] - shift, box[3] - shift
        else:
            continue
        placed.append(tuple(box))
        draw.text(
            (x, y),
            tags[i][0],
            font=font,
            anchor="md",
            fill=tags[i][1],
            stroke_width=2,
            stroke_fill=(0, 0, 0),
        )
    return placed


@lru_cache(maxsize=8)
def label_font(px: int) -> ImageFont.ImageFont | ImageFont.FreeTypeFont:
    """Return Pillow's default font at ``px`` pixels (cached, 8 sizes)."""
    return ImageFont.load_default(size=px)
