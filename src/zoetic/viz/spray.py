"""Spray of a stunt's video: drops thrown up where the body's faces cross the water surface."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Splash:
    """Spray launched where body faces crossed the surface: time (s), point (3,), and the
    crossing's area x normal speed (m^3/s; going in or coming out)."""

    times: np.ndarray  # (E,)
    points: np.ndarray  # (E, 3)
    flux: np.ndarray  # (E,)


def surface_crossings(body, positions: np.ndarray, times: np.ndarray, level: float) -> Splash:
    """Return the faces' surface crossings of one recorded motion (R, N, 3) as spray sources
    (the splash measure's own per-face crossings, ``Signals.crossing_flux``)."""
    from zoetic.tasks.terms import BodyFrame, Signals

    pos = np.asarray(positions, float)[None]
    r = pos.shape[1]
    s = Signals(
        np, BodyFrame.of(body), pos, np.zeros((1, r, 0)), np.asarray(times, float), level, 1.0
    )
    flux = np.abs(np.nan_to_num(s.crossing_flux[0]))  # (R-1, P)
    rows, faces = np.nonzero(flux > 0)
    c = s.face_centres[0]
    pts = 0.5 * (c[rows, faces] + c[rows + 1, faces])
    pts[:, 1] = level
    t = 0.5 * (np.asarray(times)[rows] + np.asarray(times)[rows + 1])
    return Splash(t, pts, flux[rows, faces])


def spray_launches(
    splash: Splash, per_flux: float = 150.0, seed: int = 0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the spray drops' launch times (D,) s, points (D, 3) m and velocities (D, 3) m/s:
    each crossing throws round(per_flux x its area x normal speed) drops (at most 60) up and
    out at speeds that grow with it."""
    rng = np.random.default_rng(seed)
    t0, p0, v0 = [np.zeros(0)], [np.zeros((0, 3))], [np.zeros((0, 3))]
    for t, p, f in zip(splash.times, splash.points, splash.flux, strict=True):
        n = int(min(60, round(per_flux * f)))
        if n == 0:
            continue
        up = (1.0 + 2.0 * min(1.0, f)) * rng.uniform(0.6, 1.4, n)
        side = 0.5 * up[:, None] * rng.normal(0.0, 0.6, (n, 2))
        t0.append(np.full(n, t))
        p0.append(p + rng.normal(0.0, 0.05, (n, 3)) * [1, 0, 1])
        v0.append(np.stack([side[:, 0], up, side[:, 1]], axis=1))
    return np.concatenate(t0), np.concatenate(p0), np.concatenate(v0)


def spray_particles(
    splash: Splash, level: float, gravity: float = 9.81, per_flux: float = 150.0, seed: int = 0
):
    """Return a function of time t giving the spray drops (D, 3) in the air then: the drops
    of ``spray_launches`` fly ballistically until they fall back in."""
    t0a, p0a, v0a = spray_launches(splash, per_flux, seed)

    def at(t: float) -> np.ndarray:
        dt = t - t0a
        p = p0a + v0a * dt[:, None]
        p[:, 1] -= 0.5 * gravity * dt**2
        return p[(dt >= 0) & (p[:, 1] >= level)]

    return at
