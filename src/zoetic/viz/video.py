"""Writing frame sequences to MP4 files."""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

import numpy as np


def write_mp4(frames: Iterable[np.ndarray], path: str | os.PathLike, fps: float = 30.0) -> Path:
    """Write RGB uint8 frames (H, W, 3) to an H.264 MP4 at ``path``; returns the path.

    The file is written to a temporary name and renamed, so an interrupted write never
    leaves a truncated video behind.
    """
    import imageio.v2 as imageio

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.stem + ".part" + path.suffix)
    writer = imageio.get_writer(
        tmp,
        fps=fps,
        codec="libx264",
        quality=7,
        macro_block_size=8,
        ffmpeg_log_level="error",
        output_params=["-preset", "veryfast"],
    )
    try:
        for frame in frames:
            writer.append_data(np.asarray(frame, dtype=np.uint8))
    finally:
        writer.close()
    os.replace(tmp, path)
    return path


def figure_to_rgb(fig) -> np.ndarray:
    """Return the pixels of a drawn matplotlib figure as an (H, W, 3) uint8 array."""
    fig.canvas.draw()
    buf = np.asarray(fig.canvas.buffer_rgba())
    return buf[..., :3].copy()
