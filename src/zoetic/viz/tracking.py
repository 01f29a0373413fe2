"""Pictures of tracking and macro-controller runs: top views of paths, goals and obstacles."""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path

import numpy as np


def plot_plan(
    paths: Sequence[np.ndarray],
    labels: Sequence[str],
    path: Path,
    goal: Sequence[float],
    obstacles: np.ndarray,
    starts: Sequence[np.ndarray] | None = None,
    title: str = "",
) -> Path:
    """Write a top view of (R, 3) paths with the goal and the obstacle discs; returns the path."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle

    from zoetic.io import atomic_write_bytes

    fig = Figure(figsize=(6.4, 4.8), dpi=120)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for k, (x, z, r) in enumerate(np.asarray(obstacles, float).reshape(-1, 3)):
        ax.add_patch(
            Circle(
                (x, z),
                r,
                fc="0.75",
                ec="0.35",
                hatch="//",
                lw=1,
                label="obstacle" if k == 0 else None,
            )
        )
    for i, (p, label) in enumerate(zip(paths, labels, strict=True)):
        (line,) = ax.plot(p[:, 0], p[:, 2], lw=1.8, label=label)
        if starts is not None and len(starts[i]):
            idx = np.clip(np.asarray(starts[i], int), 0, len(p) - 1)
            ax.plot(
                p[idx, 0],
                p[idx, 2],
                "o",
                mfc="white",
                mec=line.get_color(),
                ms=6,
                mew=1.3,
                ls="none",
                zorder=4,
            )
    ax.plot(*paths[0][0, [0, 2]], "s", color="0.2", ms=7, label="start", zorder=5)
    ax.plot(*goal, "o", color="black", ms=8, label="goal", zorder=5)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m, forward)")
    ax.set_ylabel("z (m, left)")
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.legend(loc="best", fontsize=8, framealpha=0.85)
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return atomic_write_bytes(path, buf.getvalue())
