"""Pictures of an aquarium's life: the fishes' minds as stacked timelines, and the tank's video."""

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
    size: tuple[int, int] = (640, 360),
) -> Iterator[np.ndarray]:
    """Yield the tank's frames from a fixed camera: fishes in their species' colours,
    obstacles as grey buoys, uneaten food as orange ones, each fish labelled when ``labels``
    (R, n) are given."""
    from zoetic.viz.render3d import Camera, render_frames

    cam = Camera(
        azimuth=30.0, elevation=65.0, distance=2.0 * half_size, fov=50.0, target=(0.0, 0.0, 0.0)
    )
    obstacles = np.asarray(obstacles, float).reshape(-1, 3)
    for r in range(len(times)):
        left = food[r][~eaten[r]]
        mk = np.concatenate([obstacles, left]) if len(left) else obstacles
        mc = [(120, 120, 120)] * len(obstacles) + [(250, 150, 30)] * len(left)
        yield next(
            render_frames(
                list(bodies),
                [p[r : r + 1] for p in positions],
                times[r : r + 1],
                "water",
                size=size,
                camera=cam,
                markers=mk if len(mk) else None,
                marker_colors=mc or None,
                labels=None if labels is None else labels[r],
                colors=list(colors),
                marker_radius=0.2,
            )
        )


def write_tank_video(path: str | os.PathLike, fps: float = 15.0, **kw) -> Path:
    """Write the tank's frames (``tank_frames`` arguments) to an MP4; returns the path."""
    from zoetic.viz.video import write_mp4

    return write_mp4(tank_frames(**kw), path, fps)
