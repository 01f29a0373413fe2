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

The pictures of the SAN commands, drawn from what ``zoetic.san`` computed (its results and
replays; ``san`` itself draws nothing)::

    show_video(network, creature, path, ...) -> (path, rollout)   the gait with its network
    draw_search(result, out, top, video) -> files   ranking.png, videos/NN.mp4
    draw_tune(result, creature, out, terrain, video) -> files   tuning.png, video.mp4
    draw_evolve(result, out, terrain, video) -> files   video.mp4
    draw_modes(creature, networks, doc, ...) -> files   one labelled clip per gait mode
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

from zoetic.san.creature import Creature, Link
from zoetic.viz.plots import new_figure

__all__ = [
    "draw_evolve",
    "draw_frame",
    "draw_modes",
    "draw_search",
    "draw_tune",
    "link_outline",
    "plot_ranking",
    "plot_tuning",
    "render_frames",
    "show_video",
]

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
    if len(rollout.times) == 0:
        raise ValueError("the rollout recorded nothing: run it with record_every > 0")
    w, h = size
    fig = new_figure((w / 100, h / 100), dpi=100)
    canvas = fig.canvas
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
        ax.scatter(
            ranks[use],
            m[use],
            facecolor="none",
            edgecolor="tab:green",
            s=40,
            label=f"useful ({use.sum()}/{len(m)})",
        )
    ax.set_xlabel("rank of the random network")
    from matplotlib.ticker import MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(integer=True))  # ranks are whole numbers
    unit = {"distance": "|x| (m), 0 if fallen", "follow": "∫ v·F dt (m)", "hop": "∫ ẋ + k y² dt"}
    ax.set_ylabel(f"metric: {unit.get(c.metric, c.metric)}")
    ax.set_title(
        f"{c.name}: {len(m)} random SANs, {result.seconds:g} s each, "
        f"{result.terrain} terrain (seed {result.seed})",
        fontsize=10,
    )
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


def _fps(rollout, fps: float = 30.0) -> float:
    """Return the frame rate that plays a recorded rollout in real time."""
    times = np.asarray(rollout.times, dtype=float)
    return 1.0 / float(times[1] - times[0]) if len(times) > 1 else float(fps)


def show_video(
    network,
    creature,
    path: str | os.PathLike,
    seconds: float | None = None,
    terrain: str = "flat",
    seed: int = 0,
    fps: float = 30.0,
    window: float = 2.0,
    size: tuple[int, int] = (1120, 416),
    rollout=None,
) -> tuple[Path, object]:
    """Write a video of the creature with its network's activity beside it (the scrolling
    raster of ``san.show.labelled_raster``); return the video's path and the Rollout."""
    from zoetic.san.show import BLANK, labelled_raster, replay
    from zoetic.viz.video import write_mp4

    tuned = network.tuned_creature(creature)
    if rollout is None:
        rollout = replay(network, creature, seconds, terrain, seed, fps)
    raster, labels = labelled_raster(network, creature, rollout)
    times = np.asarray(rollout.times, dtype=float)
    step = 1.0 / _fps(rollout, fps)
    width = max(2, int(round(window / step)))
    bounds = (network.n_sensors, network.n_sensors + network.n_hidden)
    bounds += (network.n_sensors + network.n_nodes,)

    def panel(ax, i: int) -> None:
        lo = max(0, i + 1 - width)
        img = np.full((raster.shape[0], width, 3), BLANK)
        seg = raster[:, lo : i + 1]
        img[:, width - seg.shape[1] :] = seg
        extent = (-width * step, 0.0, raster.shape[0] - 0.5, -0.5)
        ax.imshow(img, aspect="auto", interpolation="nearest", extent=extent)
        ax.set_yticks(range(len(labels)))
        ax.set_yticklabels(labels, fontsize=7)
        ax.set_xlabel("seconds before now", fontsize=7)
        ax.tick_params(axis="x", labelsize=7)
        for y in bounds:
            ax.axhline(y - 0.5, color="0.5", lw=0.6)
        ax.set_title(f"SAN  t = {times[i]:.2f} s", fontsize=8)

    frames = render_frames(tuned, rollout, side_panel=panel, size=size)
    return write_mp4(frames, path, fps=1.0 / step), rollout  # real time


def _gait_video(job: tuple) -> str:
    """Replay one network and write its video, with ``text`` beside it when given."""
    from zoetic.san.show import replay
    from zoetic.viz.video import write_mp4

    net, creature, seconds, terrain, seed, path, text = job
    rollout = replay(net, creature, seconds, terrain, seed, fps=30)
    panel = None
    if text is not None:

        def panel(ax, i: int) -> None:
            ax.axis("off")
            ax.text(
                0.0,
                1.0,
                text,
                va="top",
                ha="left",
                fontsize=8,
                family="monospace",
                transform=ax.transAxes,
            )

    frames = render_frames(creature, rollout, side_panel=panel)
    return str(write_mp4(frames, path, fps=_fps(rollout)))


def _gait_videos(jobs: list[tuple], workers: int | None = None) -> list[str]:
    """Render gait videos, on all cores (or ``workers`` processes)."""
    from concurrent.futures import ProcessPoolExecutor

    from zoetic.san.search import pool_context

    n = max(1, min(int(workers or os.cpu_count() or 1), len(jobs)))
    if n == 1:
        return [_gait_video(job) for job in jobs]
    with ProcessPoolExecutor(max_workers=n, mp_context=pool_context()) as pool:
        return list(pool.map(_gait_video, jobs))


def draw_search(result, out, top: int = 10, video: bool = True) -> dict[str, str]:
    """Draw a search run's pictures: ranking.png and, with ``video``, one video per kept
    gait (videos/NN.mp4); return what was written."""
    out = Path(out)
    kept = result.top(top)
    files = {"ranking": str(plot_ranking(result, out / "ranking.png", top=min(top, len(kept))))}
    if video:
        jobs = [
            (
                result.networks[i],
                result.creature,
                result.seconds,
                result.terrain,
                result.seed,
                out / "videos" / f"{rank:02d}.mp4",
                None,
            )
            for rank, i in enumerate(kept, start=1)
        ]
        _gait_videos(jobs)
        files["videos"] = str(out / "videos")
    return files


def draw_tune(result, creature, out, terrain: str = "flat", video: bool = True) -> dict[str, str]:
    """Draw a tune run's pictures: tuning.png and, with ``video``, the tuned gait with its
    network (video.mp4); return what was written."""
    out = Path(out)
    title = f"{creature.name} {result.method}"
    files = {"tuning_plot": str(plot_tuning(result, out / "tuning.png", title))}
    if video:
        path, _ = show_video(result.network, creature, out / "video.mp4", terrain=terrain)
        files["video"] = str(path)
    return files


def draw_evolve(result, out, terrain: str = "flat", video: bool = True) -> dict[str, str]:
    """Draw an evolve run's video: the evolved creature with its network (video.mp4)."""
    if not video:
        return {}
    path, _ = show_video(result.network, result.creature, Path(out) / "video.mp4", terrain=terrain)
    return {"video": str(path)}


def draw_modes(
    creature,
    networks: list,
    doc: dict,
    seconds: float | None = None,
    terrain: str = "flat",
    seed: int = 0,
    workers: int | None = None,
) -> list[str]:
    """Draw each gait mode's clip that ``san.gaits.write_modes`` named (its fastest network,
    with the mode's caption beside it); return the clips written."""
    from zoetic.san.gaits import mode_caption

    n = len(doc["modes"])
    jobs = [
        (
            networks[m["network"]],
            creature,
            seconds,
            terrain,
            seed,
            Path(m["clip"]),
            mode_caption(m, n),
        )
        for m in doc["modes"]
        if "clip" in m
    ]
    return _gait_videos(jobs, workers) if jobs else []
