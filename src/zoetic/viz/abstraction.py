"""Fig. 9 of the muscle paper: a learned controller, its primary modes, and its abstraction."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from zoetic.viz.plots import new_figure, save_figure


def plot_abstraction(
    original_t: np.ndarray,
    original_u: np.ndarray,
    abstract_u: np.ndarray,
    names: tuple[str, ...],
    freq: np.ndarray,
    amp: np.ndarray,
    phase: np.ndarray,
    kept: np.ndarray,
    path: Path,
    title: str = "",
) -> Path:
    """Write the three panels of Fig. 9 to ``path``; returns it.

    original_t (T,) s; original_u, abstract_u (T, A) activations; freq, amp, phase (A, K):
    every mode of the spectrum, drawn on the polar chart as a circle at distance = frequency
    (Hz) from the centre and angle = phase, of radius proportional to its amplitude; kept
    (A, K) bool marks the primary modes (filled) apart from the dropped ones (faint).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from zoetic.viz.learning import shown_window

    groups: dict[str, list[int]] = {}
    for a, name in enumerate(names):
        stem, _, side = name.rpartition("_")
        groups.setdefault(stem if side in ("left", "right") and stem else name, []).append(a)
    t = np.asarray(original_t, float)
    end = shown_window(t, original_u)
    keep = t <= end + 1e-9
    rows = max(len(groups), 1)
    fig = plt.figure(figsize=(12.0, max(4.0, 0.8 * rows + 1.4)))
    grid = fig.add_gridspec(rows, 2, width_ratios=(1.6, 1.0))
    ax_p = fig.add_subplot(grid[:, 1], projection="polar")
    colors = plt.get_cmap("tab10")(np.arange(len(names)) % 10)
    for r, (stem, ids) in enumerate(groups.items()):
        ax = fig.add_subplot(grid[r, 0])
        for j, a in enumerate(ids):
            off = 1.15 * (len(ids) - 1 - j)  # left above right
            ax.plot(t[keep], off + original_u[keep, a], color="0.6", lw=1.0)
            ax.plot(t[keep], off + abstract_u[keep, a], color=colors[a], lw=1.6, label=names[a])
        ax.set_ylim(-0.08, 1.15 * len(ids) - 0.1)
        ax.set_yticks([])
        ax.set_ylabel(stem, rotation=0, ha="right", va="center", fontsize=8)
        ax.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.0, 0.5), frameon=False)
        if r < rows - 1:
            ax.set_xticklabels([])
        else:
            ax.set_xlabel("time (s)")
        if r == 0:
            shown = "" if end >= t[-1] - 1e-9 else f", first {end:.2f} s"
            ax.set_title(f"learned (grey) and abstracted (colour){shown}", fontsize=10)

    scale = 350.0 / max(float(np.max(amp, initial=0.0)), 1e-9)
    for a in range(len(names)):
        for keep, alpha in ((False, 0.12), (True, 0.75)):
            m = kept[a] == keep
            if m.any():
                ax_p.scatter(
                    phase[a, m],
                    freq[a, m],
                    s=scale * amp[a, m],
                    color=colors[a],
                    alpha=alpha,
                    edgecolors="k" if keep else "none",
                    lw=0.5,
                )
    fmax = float(np.max(np.where(kept, freq, 0.0), initial=0.0))
    ax_p.set_rmax(max(1.5 * fmax, float(np.min(freq, initial=1.0)) * 2, 0.5))
    ax_p.set_title("primary modes (r = Hz, angle = phase, size = amplitude)", fontsize=9)
    ax_p.tick_params(labelsize=7)
    if title:
        fig.suptitle(title, fontsize=11)
    return save_figure(fig, path, dpi=110)


def plot_repertoire(
    signals: dict[str, tuple[np.ndarray, np.ndarray]],
    paths: dict[str, np.ndarray],
    names: tuple[str, ...],
    path: Path,
    title: str = "",
) -> Path:
    """Write a repertoire's entries to ``path``: each one's activations (one row per actuator,
    shade = activation) and all their paths (an arrow at each end).

    signals: entry -> (t (T,) s, u (T, A)); paths: entry -> centre-of-mass path (R, 3) m from
    rest, drawn from above (x right, z up) and from the side (x right, y up), the animal
    starting at the origin facing +x.
    """
    n = max(len(signals), 1)
    fig = new_figure((11.0, 1.7 * n + 1.0))
    grid = fig.add_gridspec(n, 2, width_ratios=(1.3, 1.0))
    for i, (entry, (t, u)) in enumerate(signals.items()):
        ax = fig.add_subplot(grid[i, 0])
        t = np.asarray(t, float)
        ax.imshow(
            np.asarray(u, float).T,
            aspect="auto",
            cmap="magma",
            vmin=0.0,
            vmax=1.0,
            extent=(float(t[0]), float(t[-1]), len(names) - 0.5, -0.5),
            interpolation="nearest",
        )
        ax.set_yticks(range(len(names)), names, fontsize=6)
        key = "   (activation: black 0 ... yellow 1)" if i == 0 else ""
        ax.set_title(entry + key, fontsize=8, loc="left")
        ax.tick_params(labelsize=7)
        if i == n - 1:
            ax.set_xlabel("time (s)")
    right = grid[:, 1].subgridspec(3, 1, height_ratios=(1.0, 1.0, 0.8))
    top, side, key = (fig.add_subplot(right[k]) for k in range(3))
    _draw_paths(top, paths, 2, "z (m), left")
    top.set_title("paths from rest, each entry played 3 times: from above", fontsize=9)
    _draw_paths(side, paths, 1, "y (m), up")
    side.set_title("from the side: depth kept, or changed on purpose", fontsize=9)
    side.set_xlabel("x (m)")
    top.set_anchor("S")
    side.set_anchor("N")
    key.axis("off")
    key.legend(*top.get_legend_handles_labels(), loc="upper center", ncol=2, fontsize=8)
    lo = min(top.get_xlim()[0], side.get_xlim()[0])
    hi = max(top.get_xlim()[1], side.get_xlim()[1])
    for ax in (top, side):
        ax.set_xlim(lo, hi)
    if title:
        fig.suptitle(title, fontsize=11)
    return save_figure(fig, path, dpi=110)


def _draw_paths(ax, paths: dict[str, np.ndarray], across: int, label: str) -> None:
    """Draw each entry's centre-of-mass path on ``ax``: x against column ``across`` of the
    path (2: z, seen from above; 1: y, seen from the side), from the start at the origin, one
    metre as long on both axes, an arrow head where the entry leaves the animal heading."""
    for entry, com in paths.items():
        c = np.asarray(com, float)
        xy = c[:, [0, across]] - c[0, [0, across]]
        (line,) = ax.plot(xy[:, 0], xy[:, 1], lw=1.5, label=entry)
        end, before = xy[-1], xy[max(0, len(xy) - 4)]
        ax.annotate(
            "",
            xy=end,
            xytext=before,
            arrowprops={"arrowstyle": "-|>", "color": line.get_color(), "lw": 1.5},
        )
    ax.plot(0, 0, "k^", ms=7)
    ax.set_aspect("equal", adjustable="box")
    ax.set_ylabel(label)
    ax.grid(alpha=0.3)
