"""Pictures of tracking and macro-controller runs: a top view of the paths with the targets
(or goal) and obstacle discs, beside a side view of the depth along each path."""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path

import numpy as np


def plot_plan(
    paths: Sequence[np.ndarray],
    labels: Sequence[str],
    path: Path,
    goal: Sequence[float] | np.ndarray,
    obstacles: np.ndarray,
    starts: Sequence[np.ndarray] | None = None,
    title: str = "",
    band: float | None = None,
) -> Path:
    """Write the top and side views of (R, 3) centre-of-mass paths; returns the image's path.

    goal: one (x, z) point, or (M, 3) targets (x, y, z in the world, y their height);
    obstacles: (O, 3) discs x, z, r; starts: per path, the indices where a new controller
    starts (white dots); band: m above and below the start depth drawn shaded on the side view.
    """
    from zoetic.io import atomic_write_bytes
    from zoetic.viz.plots import new_figure

    g = np.asarray(goal, float)
    y0 = float(paths[0][0, 1])
    targets = g.reshape(-1, 3) if g.size % 3 == 0 and g.ndim == 2 else None
    if targets is None:
        g = g.reshape(-1, 2)
        targets = np.column_stack([g[:, 0], np.full(len(g), y0), g[:, 1]])
    fig = new_figure((11.0, 4.8), dpi=110)
    top, side = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.1, 1.0]})
    _top_view(top, paths, labels, targets, obstacles, starts)
    _side_view(side, paths, labels, targets, starts, y0, band)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return atomic_write_bytes(path, buf.getvalue())


def _white_dots(ax, xs, ys, color) -> None:
    ax.plot(xs, ys, "o", mfc="white", mec=color, ms=6, mew=1.3, ls="none", zorder=4)


def _top_view(ax, paths, labels, targets, obstacles, starts) -> None:
    """Draw x (forward) against z (left) with the targets and the obstacle discs."""
    from matplotlib.patches import Circle

    for k, (x, z, r) in enumerate(np.asarray(obstacles, float).reshape(-1, 3)):
        ax.add_patch(
            Circle((x, z), r, fc="0.75", ec="0.35", hatch="//", lw=1, label="obstacle" * (k == 0))
        )
    for i, (p, label) in enumerate(zip(paths, labels, strict=True)):
        (line,) = ax.plot(p[:, 0], p[:, 2], lw=1.8, label=label)
        if starts is not None and len(starts[i]):
            idx = np.clip(np.asarray(starts[i], int), 0, len(p) - 1)
            _white_dots(ax, p[idx, 0], p[idx, 2], line.get_color())
    ax.plot(*paths[0][0, [0, 2]], "s", color="0.2", ms=7, label="start", zorder=5)
    if len(targets):
        ax.plot(targets[:, 0], targets[:, 2], "o", color="black", ms=8, label="target", zorder=5)
    for k, t in enumerate(targets):
        ax.annotate(str(k + 1), (t[0], t[2]), xytext=(5, 5), textcoords="offset points")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m, forward)")
    ax.set_ylabel("z (m, left)")
    ax.set_title("top view", fontsize=9)
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.legend(loc="best", fontsize=8, framealpha=0.85)


def _side_view(ax, paths, labels, targets, starts, y0: float, band: float | None) -> None:
    """Draw the height above the start depth against the distance swum (top view), each
    target at the distance where the first path came closest to it."""
    for i, (p, label) in enumerate(zip(paths, labels, strict=True)):
        s = np.concatenate(
            [[0.0], np.cumsum(np.linalg.norm(np.diff(p[:, [0, 2]], axis=0), axis=1))]
        )
        (line,) = ax.plot(s, p[:, 1] - y0, lw=1.8, label=label)
        if starts is not None and len(starts[i]):
            idx = np.clip(np.asarray(starts[i], int), 0, len(p) - 1)
            _white_dots(ax, s[idx], p[idx, 1] - y0, line.get_color())
        if i == 0:
            first, dist = p, s
    if band:
        ax.axhspan(-band, band, color="tab:green", alpha=0.12, label=f"start depth ±{band:g} m")
    near = np.argmin(np.linalg.norm(first[:, None, :] - targets[None], axis=-1), axis=0)
    if len(targets):
        ax.plot(dist[near], targets[:, 1] - y0, "o", color="black", ms=8, label="target", zorder=5)
    for k, (d, t) in enumerate(zip(dist[near], targets, strict=True)):
        ax.annotate(str(k + 1), (d, t[1] - y0), xytext=(5, 5), textcoords="offset points")
    ax.set_xlabel("distance swum (m, top view)")
    ax.set_ylabel("height above the start depth (m)")
    ax.set_title("side view", fontsize=9)
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.legend(loc="best", fontsize=8, framealpha=0.85)
