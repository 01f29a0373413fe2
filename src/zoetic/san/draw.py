"""The SAN pictures now live in ``zoetic.viz.san`` (drawing belongs to viz); this name
stays so that older imports keep working."""

from __future__ import annotations

from zoetic.viz.san import draw_frame, link_outline, render_frames

__all__ = ["draw_frame", "link_outline", "render_frames"]
