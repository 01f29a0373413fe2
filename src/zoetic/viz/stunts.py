"""Pictures of stunts: what the style terms read, over the stunt's time."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np


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
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from zoetic.viz.plots import save_figure

    n = max(1, len(series))
    fig = Figure(figsize=(7.0, 1.6 * n + 0.6), dpi=110)
    FigureCanvasAgg(fig)
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    out = np.asarray(series.get("nodes out of water", []), float)
    for ax, (label, y) in zip(axes, series.items(), strict=False):
        ax.plot(times, y, lw=1.5)
        ax.set_ylabel(label, fontsize=8)
        if out.shape == np.shape(times):
            ax.fill_between(times, 0, 1, where=out >= 1.0, color="tab:orange", alpha=0.2,
                            transform=ax.get_xaxis_transform(), lw=0)  # fmt: skip
        for s in starts:
            ax.axvline(s, color="0.5", ls=":", lw=0.8)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time (s)  (dotted: a new entry starts; shaded: wholly in the air)")
    if title:
        axes[0].set_title(title, fontsize=9)
    return save_figure(fig, path)
