"""Pictures of the SAN slice: rollout frames (matplotlib Agg, no pyplot), the ranking of a
search and the course of a tuning.

Public interface::

    draw_frame(ax, creature, rollout, i) -> None
        draws record i of a recorded rollout: each link as its shape (capsule, box, sphere)
        from ``rollout.poses[i]``, the ground (flat line or the rough profile; none for a
        top-view creature), the follow point and its trail when the rollout has one, and the
        time; the view follows the creature with a fixed scale
    render_frames(creature, rollout, side_panel=None, size=(640, 360)) -> Iterator[np.ndarray]
        yields one RGB uint8 frame (H, W, 3) per record, reusing one figure; ``side_panel``
        is an optional callable(ax, i) that draws into an axes to the right of the creature
        (e.g. sensor and node states)

A video: ``zoetic.viz.video.write_mp4(render_frames(c, r), "out.mp4", fps=1 / (r.times[1]
- r.times[0]))``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np

from zoetic.san.creature import Creature, Link

__all__ = ["draw_frame", "link_outline", "plot_ranking", "plot_tuning", "render_frames"]

LINK_COLOURS = ("#4c72b0", "#dd8452", "#55a868", "#c44e52", "#8172b3", "#937860")


def link_outline(link: Link, pose: np.ndarray, n: int = 10) -> np.ndarray:
    """Return the (K, 2) outline of ``link`` at pose [x, z, angle] in world coordinates."""
    a, b, r = link.start, link.start + link.length, link.radius
    if link.shape == "sphere":
        t = np.linspace(0, 2 * np.pi, 4 * n, endpoint=False)
        local = np.stack([link.centre + r * np.cos(t), r * np.sin(t)], axis=1)
    elif link.shape == "box":
        local = np.array([[a, -r], [b, -r], [b, r], [a, r]])
    else:
        t = np.linspace(-np.pi / 2, np.pi / 2, n)
        right = np.stack([b + r * np.cos(t), r * np.sin(t)], axis=1)
        left = np.stack([a - r * np.cos(t), -r * np.sin(t)], axis=1)
        local = np.concatenate([right, left])
    x, z, ang = pose
    c, s = np.cos(ang), np.sin(ang)
    return np.stack(
        [x + c * local[:, 0] - s * local[:, 1], z + s * local[:, 0] + c * local[:, 1]], 1
    )


def _extent(creature: Creature) -> float:
    return max(sum(ln.length + 2 * ln.radius for ln in creature.links), 0.3)


def draw_frame(ax, creature: Creature, rollout, i: int) -> None:
    """Draw record ``i`` of ``rollout`` into the matplotlib axes ``ax``."""
    from matplotlib.patches import Polygon

    pose = rollout.poses[i]
    outlines = [link_outline(ln, p) for ln, p in zip(creature.links, pose, strict=True)]
    pts = np.concatenate(outlines)
    span = 1.2 * _extent(creature)
    cx = float(pts[:, 0].mean())
    vertical = creature.plane == "vertical"
    if vertical:
        z0 = 0.0 if rollout.terrain is None else float(np.interp(cx, *rollout.terrain.T))
        cz = z0 + 0.35 * span
    else:
        cz = float(pts[:, 1].mean())
    aspect = 16 / 9
    ax.set_xlim(cx - span * aspect / 2, cx + span * aspect / 2)
    ax.set_ylim(cz - span / 2, cz + span / 2)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xticks([])
    ax.set_yticks([])
    x0, x1 = ax.get_xlim()
    if vertical:
        if rollout.terrain is None:
            gx, gz = np.array([x0, x1]), np.zeros(2)
        else:
            keep = (rollout.terrain[:, 0] > x0 - 0.1) & (rollout.terrain[:, 0] < x1 + 0.1)
            gx, gz = rollout.terrain[keep, 0], rollout.terrain[keep, 1]
        ax.fill_between(gx, gz, cz - span, color="#d9d2c3", zorder=0)
        ax.plot(gx, gz, color="#7a6a4f", lw=1.5, zorder=1)
        # ticks on the ground every 10 cm so the motion reads against it
        for t in np.arange(np.ceil(x0 * 10) / 10, x1, 0.1):
            gt = 0.0 if rollout.terrain is None else np.interp(t, *rollout.terrain.T)
            ax.plot([t, t], [gt, gt - 0.01 * span], color="#7a6a4f", lw=0.8, zorder=1)
    else:
        ax.set_facecolor("#e8f1f8" if creature.medium == "water" else "#f1ede4")
        for t in np.arange(np.ceil(x0 * 10) / 10, x1, 0.1):
            ax.axvline(t, color="#cccccc", lw=0.5, zorder=0)
    if rollout.follow is not None:
        f = rollout.follow
        ax.plot(f[: i + 1, 0], f[: i + 1, 1], color="#e377c2", lw=0.8, ls=":", zorder=2)
        ax.plot(*f[i], marker="*", ms=12, color="#e377c2", zorder=5)
    for k, outline in enumerate(outlines):
        colour = LINK_COLOURS[k % len(LINK_COLOURS)]
        ax.add_patch(Polygon(outline, closed=True, fc=colour, ec="k", lw=0.8, alpha=0.9, zorder=3))
    ax.set_title(
        f"{creature.name}   t = {rollout.times[i]:5.2f} s   x = {pose[0, 0]:+.2f} m",
        fontsize=9,
        loc="left",
    )


def render_frames(
    creature: Creature,
    rollout,
    side_panel: Callable | None = None,
    size: tuple[int, int] = (640, 360),
) -> Iterator[np.ndarray]:
    """Yield RGB uint8 frames (H, W, 3), one per recorded sample of ``rollout``."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    if len(rollout.times) == 0:
        raise ValueError("the rollout recorded nothing: run it with record_every > 0")
    w, h = size
    fig = Figure(figsize=(w / 100, h / 100), dpi=100)
    canvas = FigureCanvasAgg(fig)
    if side_panel is None:
        ax, side = fig.add_axes((0.02, 0.03, 0.96, 0.88)), None
    else:
        ax = fig.add_axes((0.02, 0.03, 0.62, 0.88))
        side = fig.add_axes((0.68, 0.08, 0.30, 0.83))
    for i in range(len(rollout.times)):
        ax.cla()
        draw_frame(ax, creature, rollout, i)
        if side is not None:
            side.cla()
            side_panel(side, i)
        canvas.draw()
        buf = np.asarray(canvas.buffer_rgba())
        yield buf[..., :3].copy()


def plot_ranking(result, path, top: int = 10):
    """Write ranking.png: every trial's metric from best to worst (the long-tailed curve)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from zoetic.viz.plots import save_figure

    order = result.order
    m = result.metrics[order]
    m = np.where(np.isfinite(m), m, np.nan)
    ranks = np.arange(1, len(m) + 1)
    c = result.creature
    fig, ax = plt.subplots(figsize=(7, 4), dpi=110)
    ax.plot(ranks, m, color="0.3", lw=1.2)
    ax.scatter(ranks[:top], m[:top], color="tab:red", s=14, zorder=3, label=f"kept ({top})")
    from zoetic.san.search import useful_mask

    use = useful_mask(result)[order]
    if use.any():
        ax.scatter(ranks[use], m[use], facecolor="none", edgecolor="tab:green", s=40,
                   label=f"useful ({use.sum()}/{len(m)})")  # fmt: skip
    ax.set_xlabel("rank of the random network")
    unit = {"distance": "|x| (m), 0 if fallen", "follow": "∫ v·F dt (m)", "hop": "∫ ẋ + k y² dt"}
    ax.set_ylabel(f"metric: {unit.get(c.metric, c.metric)}")
    ax.set_title(f"{c.name}: {len(m)} random SANs, {result.seconds:g} s each, "
                 f"{result.terrain} terrain (seed {result.seed})", fontsize=10)  # fmt: skip
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    sec = ax.secondary_yaxis(
        "right",
        functions=(lambda v: 100 * v / result.seconds, lambda s: s * result.seconds / 100),
    )
    if c.metric in ("distance", "follow"):
        sec.set_ylabel("speed (cm/s)")
    else:
        sec.remove()
    return save_figure(fig, path)


def plot_tuning(result, path, title: str = ""):
    """Write tuning.png: each candidate's metric, the accepted and the best against trials."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from zoetic.viz.plots import save_figure

    t = np.arange(1, result.trials + 1)
    fig, ax = plt.subplots(figsize=(7, 4), dpi=110)
    tried = np.where(np.isfinite(result.tried), result.tried, np.nan)
    ax.scatter(t, tried, s=4, color="0.7", label="candidate")
    ax.plot(t, result.current, color="tab:blue", lw=1, label="current")
    ax.plot(t, result.best, color="tab:red", lw=1.5, label="best")
    ax.axhline(result.before, color="0.3", ls=":", lw=1, label="start")
    ax.set_xlabel("trial")
    ax.set_ylabel("metric")
    ax.set_title(title or f"{result.method}: {result.before:.4g} -> {result.after:.4g}")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return save_figure(fig, path)
