"""Pictures of animat vision: the gaze angles over a pursuit (seed 003, Fig. 7), a strip of
retinal frames (Fig. 8), and video frames of the world beside the two retinas."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from zoetic.perception.eyes import composite
from zoetic.viz.plots import new_figure, save_figure


def gaze_ends(eye_pos: np.ndarray, eye_dirs: np.ndarray, distance) -> np.ndarray:
    """Return where the drawn gaze rays end (..., 2, 3) m: from each eye along its direction
    to the triangulated range (``distance``, m; 3 m where there is none), at most 6 m."""
    d = np.asarray(distance, float)
    reach = np.minimum(np.where(np.isfinite(d), d, 3.0), 6.0)
    return np.asarray(eye_pos, float) + reach[..., None, None] * np.asarray(eye_dirs, float)


def plot_gaze(log: Sequence, path: str | os.PathLike) -> Path:
    """Write Fig. 7: left and right theta and phi, the vergence angle theta_V and the turn
    angles theta_P, phi_P (degrees) over the frames of a pursuit."""
    a = np.degrees(np.array([r.angles for r in log]).reshape(-1, 2, 2))
    tp = np.degrees([r.theta_p for r in log])
    pp = np.degrees([r.phi_p for r in log])
    k = np.arange(len(a))
    fig = new_figure((8, 7))
    ax = fig.subplots(3, 1, sharex=True)
    ax[0].plot(k, a[:, 0, 0], label="left theta")
    ax[0].plot(k, a[:, 1, 0], label="right theta")
    ax[0].plot(k, a[:, 0, 1], label="left phi")
    ax[0].plot(k, a[:, 1, 1], label="right phi")
    ax[0].set_ylabel("gaze angle (deg)")
    ax[0].legend(loc="upper right", fontsize=8, ncol=2)
    ax[1].plot(k, a[:, 1, 0] - a[:, 0, 0], color="k")
    ax[1].set_ylabel("vergence theta_V (deg)")
    ax[2].plot(k, tp, label="theta_P (left/right)")
    ax[2].plot(k, pp, label="phi_P (up/down)")
    ax[2].set_ylabel("turn angle (deg)")
    ax[2].set_xlabel("frame")
    ax[2].legend(loc="upper right", fontsize=8)
    return save_figure(fig, path, dpi=100)


def retina(record, eye: int = 0, size: int = 256) -> np.ndarray:
    """Return the composited retinal image (size, size, 3) of one eye in a vision record."""
    return composite(record.images[eye], size)


def plot_frames(
    log: Sequence, path: str | os.PathLike, frames: Sequence[int] | None = None, size: int = 160
) -> Path:
    """Write Fig. 8: a strip of the left eye's retinal images at chosen frames, labelled."""
    if frames is None:
        n = len(log)
        frames = sorted({0, 1, min(7, n - 1), *np.linspace(0, n - 1, 6).astype(int).tolist()})
    frames = [f for f in frames if 0 <= f < len(log)]
    pad = 18
    strip = Image.new("RGB", (len(frames) * (size + 4), size + pad), (255, 255, 255))
    draw = ImageDraw.Draw(strip)
    for i, f in enumerate(frames):
        strip.paste(Image.fromarray(retina(log[f], 0, size)), (i * (size + 4), pad))
        draw.text((i * (size + 4) + 2, 2), f"frame {f}", fill=(0, 0, 0))
    import io

    from zoetic.io import atomic_write_bytes

    buf = io.BytesIO()
    strip.save(buf, format="PNG")
    return atomic_write_bytes(path, buf.getvalue())


def video_frame(
    world_view: np.ndarray, record, gaze_px: Sequence | None = None, size: int | None = None
) -> np.ndarray:
    """Return one video frame: the world view (H, W, 3) with the gaze rays drawn (pairs of
    pixel points per eye in ``gaze_px``), and the two retinas beside it, H x H each."""
    h = world_view.shape[0]
    size = size or h
    img = Image.fromarray(world_view)
    if gaze_px is not None:
        draw = ImageDraw.Draw(img)
        for (x0, y0), (x1, y1) in gaze_px:
            if np.isfinite([x0, y0, x1, y1]).all():
                draw.line([(x0, y0), (x1, y1)], fill=(255, 255, 120), width=1)
    left, right = (retina(record, e, size) for e in (0, 1))
    out = np.concatenate([np.asarray(img), left, right], axis=1)
    return out[:, : out.shape[1] - out.shape[1] % 2]


def chase_frames(
    world,
    scenery,
    result,
    width: int = 320,
    height: int = 240,
    every: int = 1,
    fog=(0.05, 0.25, 0.35),
    visibility: float = 12.0,
):
    """Yield video frames of a chase: the world seen from above and behind the predator
    (rasterised), the gaze rays drawn, the two retinas beside it."""
    from zoetic.render import Cameras, look_rotation, project, render

    pred, prey = result.positions[0], result.positions[1]
    centre = 0.5 * (pred.mean(1) + prey.mean(1))
    # a camera path smoothed over about a second, so the picture does not shake
    k = max(1, int(len(centre) / max(1.0, result.times[-1] + 1e-9)))
    ker = np.ones(k) / k
    smooth = np.stack(
        [
            np.convolve(np.pad(centre[:, i], (k, k), mode="edge"), ker, "same")[k:-k]
            for i in range(3)
        ],
        1,
    )
    for i in range(0, len(result.log), every):
        rec = result.log[i]
        pos = [p[i] for p in result.positions]
        mesh = scenery.mesh(world, pos)
        gap = np.linalg.norm(pred[i].mean(0) - prey[i].mean(0))
        eye = smooth[i] + np.array([-1.5 - 0.8 * gap, 2.0 + 0.6 * gap, 0.5])
        cam = Cameras(
            eye[None],
            look_rotation((smooth[i] - eye)[None]),
            np.array([np.radians(60.0)]),
            (width, height),
        )
        view = render(mesh.vertices, mesh.triangles, mesh.colors, cam, fog, visibility)[0]
        ends = gaze_ends(rec.eye_pos, rec.eye_dirs, rec.range)
        uv0, z0 = project(rec.eye_pos, cam)
        uv1, z1 = project(ends, cam)
        rays = [
            (tuple(uv0[0, e]), tuple(uv1[0, e])) for e in range(2) if z0[0, e] > 0 and z1[0, e] > 0
        ]
        yield video_frame(view, rec, rays)
