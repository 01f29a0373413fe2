"""The follow point of "follow" creatures (Fig. 10): dragged at constant speed along a spline."""

from __future__ import annotations

import numpy as np

__all__ = ["FollowPath"]


class FollowPath:
    """A follow point dragged at constant speed along a seeded spline."""

    def __init__(
        self, start: np.ndarray, lead: float, speed: float, length: float, seed: int, lateral: bool
    ):
        rng = np.random.default_rng([seed, 7919])
        step = max(4.0 * lead, 0.2)
        n = int(length / step) + 4
        wx = start[0] + lead + step * np.arange(-1, n)
        wz = np.full(wx.shape, start[1])
        if lateral:
            wz = wz + np.concatenate([[0.0, 0.0], rng.normal(0.0, 0.6 * step, n - 1)])
        pts = np.stack([wx, wz], axis=1)
        dense = []
        for i in range(1, len(pts) - 2):  # Catmull-Rom between pts[i] and pts[i+1]
            p0, p1, p2, p3 = pts[i - 1], pts[i], pts[i + 1], pts[i + 2]
            t = np.linspace(0.0, 1.0, 50, endpoint=False)[:, None]
            dense.append(
                0.5
                * (
                    2 * p1
                    + (p2 - p0) * t
                    + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t**2
                    + (3 * p1 - p0 - 3 * p2 + p3) * t**3
                )
            )
        self.points = np.concatenate(dense)
        seg = np.linalg.norm(np.diff(self.points, axis=0), axis=1)
        self.arc = np.concatenate([[0.0], np.cumsum(seg)])
        self.speed = speed

    def at(self, t: float) -> np.ndarray:
        """Return the follow point [x, z] at time ``t`` (s)."""
        s = self.speed * t
        return np.array(
            [np.interp(s, self.arc, self.points[:, 0]), np.interp(s, self.arc, self.points[:, 1])]
        )
