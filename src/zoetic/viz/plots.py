"""Static figures of runs: the top view of the paths animals swam or crawled."""

from __future__ import annotations

import io
import os
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from zoetic.io import atomic_write_bytes


def new_figure(figsize: tuple[float, float], dpi: float | None = None):
    """Return a matplotlib Figure drawn by its own Agg canvas (``fig.canvas``): no pyplot
    (slow to import), no pyplot state to close, no GUI backend."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=dpi)
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig, path: str | os.PathLike, dpi: float | None = None) -> Path:
    """Lay ``fig`` out tightly and write it atomically to ``path`` (format from the suffix).

    ``dpi`` defaults to the figure's own. A figure made through pyplot is closed afterwards,
    so that long runs writing many plots do not keep them all alive.
    """
    fig.tight_layout()
    # tight_layout leaves a placeholder layout engine behind, for which savefig draws the
    # whole figure once more (text and all) before drawing it for the file; the layout is
    # done, so none is kept
    fig.set_layout_engine(None)
    path = Path(path)
    buf = io.BytesIO()
    fig.savefig(buf, format=(path.suffix.lstrip(".") or "png").lower(), dpi=dpi or "figure")
    if "matplotlib.pyplot" in sys.modules:
        sys.modules["matplotlib.pyplot"].close(fig)
    return atomic_write_bytes(path, buf.getvalue())


def _paths(com: np.ndarray | Sequence[np.ndarray]) -> list[np.ndarray]:
    """Return the centre-of-mass paths as a list of (R, 3) arrays."""
    if isinstance(com, np.ndarray) and com.ndim == 2:
        return [np.asarray(com, float)]
    return [np.asarray(c, float).reshape(-1, 3) for c in com]


def plot_path(
    com: np.ndarray | Sequence[np.ndarray],
    path: str | os.PathLike,
    targets: np.ndarray | None = None,
    starts: Sequence[int] | None = None,
    title: str = "",
) -> Path:
    """Write a top view (x right, z up) of centre-of-mass paths to an image; returns its path.

    com: (R, 3) m, or several such paths; targets: (M, 2) goal points (x, z) drawn as black
    dots; starts: indices into the first path where a new controller took over, drawn as white
    dots with a black edge (the style of the paper's Fig. 5).
    """
    paths = _paths(com)
    fig = new_figure((6.0, 4.5), dpi=120)
    ax = fig.add_subplot()
    for i, p in enumerate(paths):
        good = p[np.isfinite(p).all(axis=1)]
        (line,) = ax.plot(
            p[:, 0], p[:, 2], lw=1.6, label=f"path {i + 1}" if len(paths) > 1 else None
        )
        if len(good):
            first = i == 0
            ax.plot(
                *good[0, [0, 2]],
                "s",
                color=line.get_color(),
                ms=7,
                label="start" if first else None,
            )
            ax.plot(
                *good[-1, [0, 2]],
                "o",
                color=line.get_color(),
                ms=8,
                mec="k",
                label="end" if first else None,
            )
    if starts is not None and len(starts) and len(paths[0]):
        idx = np.clip(np.asarray(starts, int), 0, len(paths[0]) - 1)
        ax.plot(
            paths[0][idx, 0],
            paths[0][idx, 2],
            "o",
            mfc="white",
            mec="black",
            ms=7,
            mew=1.3,
            ls="none",
            label="controller start",
            zorder=4,
        )
    if targets is not None and len(targets):
        tg = np.asarray(targets, float).reshape(-1, 2)
        ax.plot(tg[:, 0], tg[:, 1], "o", color="black", ms=6, ls="none", label="target", zorder=5)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.legend(loc="best", fontsize=8, framealpha=0.8)
    if title:
        ax.set_title(title)
    return save_figure(fig, path)
