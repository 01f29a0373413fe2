"""The follow point of "follow" creatures (Fig. 10): dragged at constant speed along a spline."""

from __future__ import annotations

import numpy as np

__all__ = ["FollowPath"]


class FollowPath:
    """A follow point dragged at constant speed along a seeded spline; ``mirror`` reflects the
    spline about the line z = start z (its left turns become right turns and back)."""

    def __init__(
        self,
        start: np.ndarray,
        lead: float,
        speed: float,
        length: float,
        seed: int,
        lateral: bool,
        mirror: bool = False,
    ):
        rng = np.random.default_rng([seed, 7919])
        step = max(4.0 * lead, 0.2)
        n = int(length / step) + 4
        wx = start[0] + lead + step * np.arange(-1, n)
        wz = np.full(wx.shape, start[1])
        if lateral:
            side = -1.0 if mirror else 1.0
            wz = wz + side * np.concatenate([[0.0, 0.0], rng.normal(0.0, 0.6 * step, n - 1)])
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

    @classmethod
    def for_creature(
        cls,
        creature,
        start: np.ndarray,
        seed: int,
        seconds: float,
        lateral: bool,
        mirror: bool = False,
    ) -> FollowPath:
        """Return the path a ``creature`` run of ``seconds`` chases from ``start`` [x, z]: long
        enough for the point to keep moving at the creature's follow speed to the end."""
        length = creature.follow_speed * max(seconds, 1.0) * 1.5 + 2.0
        c = creature
        return cls(start, c.follow_lead, c.follow_speed, length, seed, lateral, mirror)

    def at(self, t: float) -> np.ndarray:
        """Return the follow point [x, z] at time ``t`` (s)."""
        s = self.speed * t
        return np.array(
            [np.interp(s, self.arc, self.points[:, 0]), np.interp(s, self.arc, self.points[:, 1])]
        )

    def turns(self, window: float, upto: float) -> tuple[float, float]:
        """Return the sharpest turns (rad) to the left (+z) and to the right of the point's
        heading over any ``window`` m of arc within its first ``upto`` m: how hard a pursuer
        must turn each way (both >= 0)."""
        step = min(0.02, window / 4.0)
        s = np.arange(0.0, min(upto, self.arc[-1]) + step / 2, step)
        xs = np.interp(s, self.arc, self.points[:, 0])
        zs = np.interp(s, self.arc, self.points[:, 1])
        heading = np.unwrap(np.arctan2(np.diff(zs), np.diff(xs)))
        w = max(1, int(round(window / step)))
        if heading.size <= w:
            return 0.0, 0.0
        change = heading[w:] - heading[:-w]
        return max(0.0, float(change.max())), max(0.0, float(-change.min()))
