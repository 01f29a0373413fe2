"""Plots of a learning run: the learning curve and the learned controller (Fig. 9 style)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from zoetic.viz.plots import save_figure


def plot_learning(curves: dict[str, np.ndarray], path: Path, title: str = "") -> Path:
    """Plot E against evaluations (dots) and the best so far (line) for one or more runs."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for label, e in curves.items():
        e = np.asarray(e, float)
        n = np.arange(1, len(e) + 1)
        finite = np.isfinite(e)
        line = ax.plot(n, np.minimum.accumulate(np.where(finite, e, np.inf)), label=label)[0]
        if len(curves) == 1:
            ax.plot(n[finite], e[finite], ".", ms=2, alpha=0.25, color=line.get_color())
    finite_values = [np.asarray(e, float) for e in curves.values()]
    finite_values = np.concatenate([e[np.isfinite(e)] for e in finite_values] + [np.zeros(0)])
    lo, hi = 0.0, 0.0
    if finite_values.size:
        lo, hi = np.min(finite_values), np.percentile(finite_values, 90)
    if np.isfinite(lo) and np.isfinite(hi) and hi > lo:
        ax.set_ylim(lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo))
    ax.set_xlabel("evaluations")
    ax.set_ylabel("E")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    return save_figure(fig, path, dpi=110)


def best_so_far(e: np.ndarray) -> np.ndarray:
    """Return the lowest finite E up to each evaluation (+inf before the first finite one)."""
    e = np.asarray(e, float)
    return np.minimum.accumulate(np.where(np.isfinite(e), e, np.inf))


def plot_learning_seeds(
    panels: dict[str, dict[str, list[np.ndarray]]], path: Path, title: str = ""
) -> Path:
    """Plot, in one panel per entry of ``panels``, the best-so-far E against evaluations of
    several runs per label (one per seed): the median as a line, the range as a band.

    ``panels`` maps a panel title to {label: [E of every evaluation, one array per seed]}.
    Runs of one label may differ in length (a simplex that stopped early); each is held at its
    last best value to the longest.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(
        1, len(panels), figsize=(5.2 * len(panels), 4.0), squeeze=False, sharey=True
    )
    for ax, (name, curves) in zip(axes[0], panels.items(), strict=True):
        for label, runs in curves.items():
            best = [best_so_far(e) for e in runs]
            n = max(len(b) for b in best)
            stack = np.stack([np.pad(b, (0, n - len(b)), mode="edge") for b in best])
            stack = np.where(np.isfinite(stack), stack, np.nan)
            x = np.arange(1, n + 1)
            line = ax.plot(
                x, np.nanmedian(stack, axis=0), lw=1.5, label=f"{label} ({len(runs)} seeds)"
            )[0]
            if len(runs) > 1:
                ax.fill_between(
                    x,
                    np.nanmin(stack, axis=0),
                    np.nanmax(stack, axis=0),
                    color=line.get_color(),
                    alpha=0.15,
                    lw=0,
                )
        ax.set_xlabel("evaluations")
        ax.set_title(name, fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[0, 0].set_ylabel("best E so far (median, range over seeds)")
    if title:
        fig.suptitle(title, fontsize=11)
    return save_figure(fig, path, dpi=110)


def shown_window(times: np.ndarray, u: np.ndarray, cycles: float = 3.0) -> float:
    """Return the end time (s) of the stretch of ``u`` (T, A) a controller plot shows: about
    ``cycles`` periods of its slowest strong rhythm (all of it when it is short or aperiodic)."""
    t = np.asarray(times, float)
    if len(t) < 8:
        return float(t[-1])
    x = np.asarray(u, float) - np.mean(u, axis=0)
    spec = np.abs(np.fft.rfft(x, axis=0)).sum(axis=1)
    freq = np.fft.rfftfreq(len(t), d=float(t[1] - t[0]))
    spec[0] = 0.0
    if not spec.any():
        return float(t[-1])
    f = float(freq[int(np.argmax(spec))])
    return float(min(t[-1], t[0] + cycles / f)) if f > 0 else float(t[-1])


def plot_controller(
    times: np.ndarray,
    u: np.ndarray,
    names: tuple[str, ...],
    sides: tuple[str, ...],
    path: Path,
    title: str = "",
) -> Path:
    """Plot u(t) per actuator as Fig. 9 does: one panel per segment, its left actuator (blue)
    drawn over its right one (red) on two lanes so neither hides the other; the first few
    periods of the rhythm only, so the strokes can be told apart."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups: dict[str, list[int]] = {}
    for k, name in enumerate(names):
        key = name.rsplit("_", 1)[0] if sides[k] in ("left", "right") else name
        groups.setdefault(key, []).append(k)
    t = np.asarray(times, float)
    end = shown_window(t, u)
    keep = t <= end + 1e-9
    rows = len(groups)
    fig, axes = plt.subplots(rows, 1, figsize=(7.0, 0.75 * rows + 1.2), sharex=True, squeeze=False)
    lane = {"left": 1.15, "right": 0.0}
    color = {"left": "tab:blue", "right": "tab:red"}
    for ax, (key, ids) in zip(axes[:, 0], groups.items(), strict=True):
        for k in ids:
            s = sides[k] if sides[k] in lane else "right"
            off = lane[s] if len(ids) > 1 else 0.0
            c = color[s] if len(ids) > 1 else "k"
            ax.plot(t[keep], off + u[keep, k], color=c, lw=1.3, label=names[k])
            ax.axhline(off, color="0.85", lw=0.6, zorder=0)
        top = 2.2 if len(ids) > 1 else 1.05
        ax.set_ylim(-0.08, top)
        ax.set_yticks([])
        ax.set_ylabel(key, rotation=0, ha="right", va="center", fontsize=8)
        for side in ("top", "right"):
            ax.spines[side].set_visible(False)
    axes[-1, 0].set_xlabel("t (s)")
    shown = "" if end >= t[-1] - 1e-9 else f"; first {end:.2f} s of {t[-1]:.1f} s"
    axes[0, 0].set_title(f"{title}  (left actuator blue, above; right red{shown})", fontsize=9)
    return save_figure(fig, path, dpi=110)
