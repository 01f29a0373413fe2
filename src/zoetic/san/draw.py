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

from zoetic.viz.san import draw_frame, link_outline, render_frames

__all__ = ["draw_frame", "link_outline", "render_frames"]
