"""Gaze control: saccades to a detected target, vergence of both eyes on it, range by
triangulation, and stabilisation of the fovea by least-squares translational optical flow
(seed 003, section 3.1; Horn's Robot Vision for the flow constraint). Each eye is controlled
independently; the vergence angle is theta_V = theta_R - theta_L (Fig. 6). Vergence finds the
spot the left fovea fixates in the right eye's images to a fraction of a foveal pixel
(``GazeController.vergence``: the foveas' correlation for a far target, the spot itself
matched coarse to fine for a near one), so that both eyes look at the same
point of the target's surface and the range is that point's.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from scipy import fft as sfft
from scipy.signal import fftconvolve

from zoetic.perception.eyes import (
    LEFT,
    RIGHT,
    EyeSpec,
    HeadFrame,
    eye_positions,
    gaze_angles,
    gaze_direction,
    pixel_direction,
)
from zoetic.perception.kernels import box_sums, flow_shift, ncc_scores
from zoetic.perception.recognition import (
    TARGET_RADIUS,
    Recognition,
    backproject,
    gray,
    histogram,
    intersection,
    locate,
)
from zoetic.render import Cameras


def saccade(frame: HeadFrame, cameras: Cameras, index: int, col: float, row: float):
    """Return the gaze angles (theta, phi) that bring pixel (col, row) of camera ``index`` to
    the centre of that eye's images."""
    th, ph = gaze_angles(frame, pixel_direction(cameras, index, col, row))
    return float(th), float(ph)


def triangulate(origins: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, float]:
    """Return the point (3,) nearest both gaze rays (origins, directions (2, 3)) and its range
    (m) from the midpoint between the eyes; inf for rays that do not converge ahead."""
    p, q = origins
    d, e = directions / np.linalg.norm(directions, axis=1, keepdims=True)
    w = p - q
    b = d @ e
    den = 1.0 - b * b
    if den < 1e-12:
        return np.full(3, np.nan), float("inf")
    s = (b * (e @ w) - (d @ w)) / den
    t = ((e @ w) - b * (d @ w)) / den
    if s <= 0 or t <= 0:
        return np.full(3, np.nan), float("inf")
    x = 0.5 * (p + s * d + q + t * e)
    return x, float(np.linalg.norm(x - 0.5 * (p + q)))


def vergence_range(theta_left: float, theta_right: float, baseline: float) -> float:
    """Return the range (m) to a fixated point straight from the eyes' theta angles in the
    horizontal plane (eyes at +-baseline/2 along the left axis): the sine rule on the triangle
    the baseline and the two gaze rays make; inf when they do not converge."""
    verg = theta_right - theta_left
    if verg <= 1e-9:
        return float("inf")
    # distance from the left eye along its ray, then the range from the midpoint
    s = baseline * np.cos(theta_right) / np.sin(verg)
    x, z = s * np.cos(theta_left), 0.5 * baseline + s * np.sin(theta_left)
    return float(np.hypot(x, z))


def _gray(img: np.ndarray) -> np.ndarray:
    return gray(img)


def image_shift(prev: np.ndarray, cur: np.ndarray, iterations: int = 3) -> tuple[float, float]:
    """Return the translation (u, v) in pixels (cols, rows) that carries image ``prev`` onto
    ``cur`` (RGB or gray), by least squares on the optical-flow constraint
    Ix u + Iy v + It = 0 over the image, refined by warping a few times."""
    a = _gray(prev) if prev.ndim == 3 else np.asarray(prev, float)
    b = _gray(cur) if cur.ndim == 3 else np.asarray(cur, float)
    # ignore a 3 px margin, where warping invents pixels
    u, v = flow_shift(np.ascontiguousarray(a), np.ascontiguousarray(b), iterations, 3)
    return float(u), float(v)


def correlate(a: np.ndarray, b: np.ndarray) -> tuple[float, float, float]:
    """Return the shift (u, v) in pixels (cols, rows) with b(x + (u, v)) ~ a(x), found by
    phase correlation (sub-pixel by a parabola through the peak), and the peak's height."""
    ga = _gray(a) if a.ndim == 3 else np.asarray(a, float)
    gb = _gray(b) if b.ndim == 3 else np.asarray(b, float)
    win = _hanning(*ga.shape)
    fa = sfft.rfft2((ga - ga.mean()) * win)
    fb = sfft.rfft2((gb - gb.mean()) * win)
    cross = fb * np.conj(fa)
    r = sfft.irfft2(cross / (np.abs(cross) + 1e-12), ga.shape)
    j, i = np.unravel_index(int(np.argmax(r)), r.shape)
    h, w = r.shape
    di = _peak_offset(r[j, i - 1], r[j, i], r[j, (i + 1) % w])
    dj = _peak_offset(r[j - 1, i], r[j, i], r[(j + 1) % h, i])
    u = (i + w // 2) % w - w // 2 + di
    v = (j + h // 2) % h - h // 2 + dj
    return float(u), float(v), float(r[j, i])


@lru_cache(maxsize=8)
def _hanning(h: int, w: int) -> np.ndarray:
    """Return the (h, w) Hann window that tapers images to their edges before an FFT."""
    return np.outer(np.hanning(h), np.hanning(w))


def _peak_offset(m1: float, m0: float, p1: float) -> float:
    """Return the sub-pixel offset (px, within +-0.5) of a parabola's vertex through three
    samples around a peak."""
    den = m1 - 2 * m0 + p1
    return min(max(0.5 * (m1 - p1) / den, -0.5), 0.5) if abs(den) > 1e-12 else 0.0


def match(
    a: np.ndarray,
    b: np.ndarray,
    col: float,
    row: float,
    half: int = 8,
    near: tuple[float, float] | None = None,
    radius: int = 3,
) -> tuple[float, float, float]:
    """Return the point (col, row) of gray image ``b`` that looks like point (col, row) of
    gray image ``a`` (continuous pixel coordinates), and the match's score in [-1, 1]: the
    normalised cross-correlation of a's (2 half + 1)-px square around the point with b's
    squares, best over all of b (or within ``radius`` px of ``near``), refined to a sub-pixel
    peak by a parabola in each direction. Stereo matching of one point, not of the whole
    image: the two eyes then look at the same spot of the target's surface."""
    k = 2 * half + 1
    j, i = int(np.floor(row)), int(np.floor(col))
    pa = np.pad(np.asarray(a, float), half)
    tpl = pa[j : j + k, i : i + k]
    tpl = tpl - tpl.mean()
    tn = float(np.sqrt((tpl * tpl).sum()))
    pb = np.pad(np.asarray(b, float), half)
    h, w = pb.shape[0] - k + 1, pb.shape[1] - k + 1
    rows, cols = slice(0, h), slice(0, w)
    if near is not None:
        nj, ni = int(np.floor(near[1])), int(np.floor(near[0]))
        rows = slice(max(nj - radius, 0), max(min(nj + radius + 1, h), 0))
        cols = slice(max(ni - radius, 0), max(min(ni + radius + 1, w), 0))
    if tn < 1e-9 or rows.stop <= rows.start or cols.stop <= cols.start:
        return col, row, 0.0
    if near is None:
        score = ncc_everywhere(np.ascontiguousarray(tpl), tn, pb)
    else:
        score = np.empty((rows.stop - rows.start, cols.stop - cols.start))
        ncc_scores(
            np.ascontiguousarray(tpl), tn, pb, rows.start, rows.stop, cols.start, cols.stop, score
        )
    y, x = np.unravel_index(int(np.argmax(score)), score.shape)
    dy = (
        _peak_offset(score[y - 1, x], score[y, x], score[y + 1, x])
        if 0 < y < score.shape[0] - 1
        else 0.0
    )
    dx = (
        _peak_offset(score[y, x - 1], score[y, x], score[y, x + 1])
        if 0 < x < score.shape[1] - 1
        else 0.0
    )
    # the square around pixel j of a maps to the square around pixel y of b: same fraction
    return (
        float(cols.start + x + dx + (col - i)),
        float(rows.start + y + dy + (row - j)),
        float(score[y, x]),
    )


def ncc_everywhere(tpl: np.ndarray, tn: float, pb: np.ndarray) -> np.ndarray:
    """Return the normalised cross-correlation (H - k + 1, W - k + 1) of the template ``tpl``
    (k, k; less its mean, ``tn`` its norm) with every k x k square of ``pb`` (H, W) less its
    mean, as ``kernels.ncc_scores`` gives it square by square: the products summed for all
    squares at once by FFT, each square's mean and spread from its sums; -1 where a square
    is flat (its spread under 1e-12 of its energy: all zeros, or one value to rounding)."""
    k = tpl.shape[0]
    n = k * k
    s1 = np.empty((pb.shape[0] - k + 1, pb.shape[1] - k + 1))
    s2 = np.empty_like(s1)
    box_sums(pb, k, s1, s2)
    mean = s1 / n
    num = fftconvolve(pb, tpl[::-1, ::-1], mode="valid") - mean * tpl.sum()
    spread = s2 - s1 * mean
    norm = np.sqrt(np.maximum(spread, 0.0)) * tn
    flat = (spread <= 1e-12 * s2) | (norm <= 1e-9)
    return np.where(flat, -1.0, num / np.where(flat, 1.0, norm))


def target_image(image: np.ndarray, model: np.ndarray) -> np.ndarray:
    """Return the gray image (H, W) weighted by the backprojection of the target's colour
    ``model``: what the two eyes' vergence should match, the target's own pixels,
    not the background behind it (which lies at another disparity)."""
    return _gray(image) * backproject(image, model, radius=TARGET_RADIUS)


@dataclass
class GazeState:
    """What the gaze controller remembers: angles (2, 2) rows (theta, phi) for the left and
    right eyes relative to the head, whether each eye holds the target, its last foveal
    image in gray (``recognition.gray``), and the gaze directions (2, 3) in the world (None
    before the first frame)."""

    angles: np.ndarray = field(default_factory=lambda: np.zeros((2, 2)))
    locked: np.ndarray = field(default_factory=lambda: np.zeros(2, bool))
    fovea: list = field(default_factory=lambda: [None, None])
    saccades: int = 0
    directions: np.ndarray | None = None


@dataclass(frozen=True)
class GazeController:
    """Foveation, stabilisation and vergence for two eyes hunting a colour model.

    threshold: backprojection strength that counts as a detection; max_shift: the largest
    image motion (fovea px) trusted to the flow; centre_tol: fovea px off centre at which a
    detected target is re-foveated by a saccade; match: the histogram intersection of the
    fovea with the model below which the fovea no longer holds the target; verge: find the
    spot the left fovea centres on in the right eye's images (``vergence``, with
    ``verge_peak``, ``verge_half`` and ``match_peak``; near: the range the eyes verged on in
    the last frame under ``near_range`` m) so that the right eye fixates the point the left
    one does.
    """

    model: np.ndarray
    spec: EyeSpec
    threshold: float = 0.2
    max_shift: float = 4.0
    centre_tol: float = 2.0
    match: float = 0.05
    max_theta: float = np.radians(60.0)
    max_phi: float = np.radians(45.0)
    verge: bool = True
    verge_peak: float = 0.1
    verge_half: int = 8
    match_peak: float = 0.5
    near_range: float = 1.5

    def hold(self, state: GazeState, frame: HeadFrame) -> GazeState:
        """Return the state with its angles re-expressed in the head's new ``frame`` so that
        each eye keeps looking along its world direction: the vestibulo-ocular reflex, which
        cancels the head's own rotation (the animal knows its body's motion) before the
        image is taken, leaving the flow only the target's motion to follow."""
        if state.directions is None:
            return state
        th, ph = gaze_angles(frame, state.directions)
        a = np.stack(
            [
                np.clip(th, -self.max_theta, self.max_theta),
                np.clip(ph, -self.max_phi, self.max_phi),
            ],
            1,
        )
        return GazeState(
            a, state.locked.copy(), list(state.fovea), state.saccades, state.directions
        )

    def step(
        self,
        state: GazeState,
        frame: HeadFrame,
        images: np.ndarray,
        cameras: Cameras,
        seen: Recognition | None = None,
    ) -> GazeState:
        """Return the gaze state after one frame: stabilise each eye on its fovea's motion,
        re-foveate (saccade) when the target drifts or is lost, verge both eyes on it.
        ``seen``: the model already looked for in all 2 x levels images (``recognise``, left
        eye's levels first), as a batch of fishes' eyes does; else looked for here."""
        n = self.spec.levels

        def held(eye: int) -> bool:
            h = histogram(images[eye, n - 1]) if seen is None else seen.histograms[eye * n + n - 1]
            return intersection(h, self.model) >= self.match

        def fovea(eye: int) -> np.ndarray:
            return _gray(images[eye, n - 1]) if seen is None else seen.grays[eye * n + n - 1]

        def detect(eye: int, lev: int):
            return (
                locate(images[eye, lev], self.model)
                if seen is None
                else seen.detections[eye * n + lev]
            )

        s = self.spec.size
        new = GazeState(state.angles.copy(), state.locked.copy(), list(state.fovea), state.saccades)
        aim: list = [None, None]  # the foveal pixel each eye now centres on, when it has one
        for eye in (LEFT, RIGHT):
            fov = fovea(eye)
            if new.locked[eye] and held(eye) and new.fovea[eye] is not None:
                u, v = image_shift(new.fovea[eye], fov)
                if np.hypot(u, v) <= self.max_shift:  # optokinetic: follow the image motion
                    th, ph = saccade(frame, cameras, eye * n + n - 1, 0.5 * s + u, 0.5 * s + v)
                    new.angles[eye] = (th, ph)
                    aim[eye] = (0.5 * s + u, 0.5 * s + v)
                else:
                    new.locked[eye] = False
            found = None
            for lev in range(n - 1, -1, -1):  # finest level that sees the target
                det = detect(eye, lev)
                if det.strength >= self.threshold:
                    found = (lev, det)
                    break
            if found is None:
                new.locked[eye] = False
                new.angles[eye] *= 0.8  # drift back toward straight ahead while searching
            else:
                lev, det = found
                off = np.hypot(det.col - 0.5 * s, det.row - 0.5 * s) * 2.0 ** (n - 1 - lev)
                if not new.locked[eye] or off > self.centre_tol:
                    th, ph = saccade(frame, cameras, eye * n + lev, det.col, det.row)
                    new.angles[eye] = (th, ph)
                    new.saccades += 1
                    aim[eye] = (det.col, det.row) if lev == n - 1 else None
                elif aim[eye] is None:
                    aim[eye] = (0.5 * s, 0.5 * s)
                new.locked[eye] = True
            new.fovea[eye] = fov
        if self.verge and new.locked.all() and aim[LEFT] is not None:
            # near: verged under near_range m last frame, or not verged at all (rays apart)
            last = fixation(frame, state.angles, self.spec)[1]
            near = last < self.near_range or not np.isfinite(last)
            found = self.vergence(images, aim[LEFT], bool(state.locked.all() and near), seen)
            if found is not None:
                lev, col, row = found
                new.angles[RIGHT] = saccade(frame, cameras, RIGHT * n + lev, col, row)
        new.angles[:, 0] = np.clip(new.angles[:, 0], -self.max_theta, self.max_theta)
        new.angles[:, 1] = np.clip(new.angles[:, 1], -self.max_phi, self.max_phi)
        new.directions = gaze_direction(frame, new.angles[:, 0], new.angles[:, 1])
        return new

    def vergence(
        self,
        images: np.ndarray,
        aim: tuple[float, float],
        near: bool,
        seen: Recognition | None = None,
    ):
        """Return (level, col, row): where in the right eye's component image of that level
        lies the spot of the target the left fovea centres on (``aim``, left foveal px), or
        None when no match is good enough. On the target's own pixels (``target_image``). A far
        target: the two foveas' correlation (its outline fixes the disparity; accepted when
        the peak reaches ``verge_peak``). A ``near`` one, whose outline spans depths as long
        as its range (a fish seen along its length): its spot at ``aim`` matched (``match``,
        a square of 2 ``verge_half`` + 1 px, accepted from a normalised correlation of
        ``match_peak``),
        coarse to fine: in the level below the fovea (twice its field, so a near target's
        disparity stays in view), then within a few px of that in the fovea, whose pixels
        are half the size: the finer the image, the finer the vergence angle and the range.
        ``seen``: the target images already made (``recognise``)."""
        n, s = self.spec.levels, self.spec.size
        c = 0.5 * s

        def target(eye: int, lev: int) -> np.ndarray:
            if seen is None:
                return target_image(images[eye, lev], self.model)
            return seen.targets[eye * n + lev]

        left, right = (target(e, n - 1) for e in (LEFT, RIGHT))
        if n < 2 or not near:
            u, v, peak = correlate(left, right)
            if peak >= self.verge_peak and np.hypot(u, v) < 0.25 * s:
                return n - 1, aim[0] + u, aim[1] + v
            return None
        lo, ro = (target(e, n - 2) for e in (LEFT, RIGHT))
        coarse = (c + 0.5 * (aim[0] - c), c + 0.5 * (aim[1] - c))
        col, row, score = match(lo, ro, *coarse, self.verge_half)
        if score < self.match_peak:
            return None
        fine = (c + 2.0 * (col - c), c + 2.0 * (row - c))
        if min(fine) >= self.verge_half and max(fine) <= s - self.verge_half:
            f_col, f_row, f_score = match(left, right, *aim, self.verge_half, fine, 3)
            if f_score >= self.match_peak:
                return n - 1, f_col, f_row
        return n - 2, col, row


def fixation(frame: HeadFrame, angles: np.ndarray, spec: EyeSpec) -> tuple[np.ndarray, float]:
    """Return the point both gaze rays verge on and its range (m) (inf if they diverge)."""
    dirs = gaze_direction(frame, angles[:, 0], angles[:, 1])
    return triangulate(eye_positions(frame, spec), dirs)
