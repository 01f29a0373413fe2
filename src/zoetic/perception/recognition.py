"""Colour indexing (Swain & Ballard 1991): colour-histogram models, histogram intersection to
recognise an object, and histogram backprojection to locate it in an image.

Colour axes rg = R - G, by = 2B - R - G, wb = R + G + B binned 16 x 16 x 8 (2048 bins).
match = sum_j min(I_j, M_j) / sum_j M_j; backprojection R_j = min(M_j / I_j, 1) per pixel
(both histograms as fractions of their pixels), smoothed with a disk, peak located.
A few lines of NumPy (``bincount``) do this; OpenCV would add a 60 MB wheel for no gain here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from zoetic.perception.kernels import (
    BINS,
    colour_bins,
    disk_smooth,
    gray_levels,
    peaks,
    recognise_all,
)

N_BINS = BINS[0] * BINS[1] * BINS[2]


def bin_index(image: np.ndarray) -> np.ndarray:
    """Return the colour bin (..., H, W) int of each pixel of RGB images (..., H, W, 3)."""
    c = np.asarray(image)
    if c.dtype != np.uint8:
        c = np.asarray(c, dtype=np.int32)
        r, g, b = c[..., 0], c[..., 1], c[..., 2]
        rg = (r - g + 255) * BINS[0] // 511
        by = (2 * b - r - g + 510) * BINS[1] // 1021
        wb = (r + g + b) * BINS[2] // 766
        return (rg * BINS[1] + by) * BINS[2] + wb
    out = np.empty(c.shape[:-1], np.int64)
    colour_bins(np.ascontiguousarray(c).reshape(-1, 3), out.reshape(-1))
    return out


def histogram(image: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
    """Return the colour histogram (2048,) of an RGB image's pixels (those in ``mask``) as
    fractions summing to 1 (all zeros for no pixels)."""
    idx = bin_index(image)
    if mask is not None:
        idx = idx[np.asarray(mask, bool)]
    h = np.bincount(idx.ravel(), minlength=N_BINS).astype(float)
    s = h.sum()
    return h / s if s > 0 else h


def intersection(image_hist: np.ndarray, model: np.ndarray) -> float:
    """Return Swain & Ballard's match sum_j min(I_j, M_j) / sum_j M_j in [0, 1]."""
    m = float(np.sum(model))
    return float(np.minimum(image_hist, model).sum() / m) if m > 0 else 0.0


def _ratio(image: np.ndarray, model: np.ndarray) -> np.ndarray:
    idx = bin_index(image)
    ih = np.bincount(idx.ravel(), minlength=N_BINS) / idx.size
    ratio = np.minimum(np.where(ih > 0, model / np.maximum(ih, 1e-12), 0.0), 1.0)
    return ratio[idx]


def backproject(image: np.ndarray, model: np.ndarray, radius: int = 1) -> np.ndarray:
    """Return the backprojection (H, W) in [0, 1] of a model histogram onto an RGB image:
    each pixel gets min(M_j / I_j, 1) of its bin j, smoothed with a disk of ``radius`` px."""
    b = _ratio(image, model)
    return _smooth(b[None], radius)[0] if radius > 0 else b


def _smooth(raw: np.ndarray, radius: int) -> np.ndarray:
    """Return images (K, H, W) each averaged over a disk of ``radius`` px (zero outside)."""
    out = np.empty_like(raw)
    disk_smooth(np.ascontiguousarray(raw, float), radius, out)
    return out


@dataclass(frozen=True)
class Detection:
    """Where a model was found in an image: its peak (col, row) in continuous pixel
    coordinates (centre of the pixel = index + 0.5), the peak's strength in [0, 1], and the
    backprojected mass (pixels' worth) around it."""

    col: float
    row: float
    strength: float
    mass: float


def locate(image: np.ndarray, model: np.ndarray, radius: int = 1, window: int = 8) -> Detection:
    """Return the peak of the smoothed backprojection of ``model`` in ``image``, refined to
    the centroid of the raw backprojection within ``window`` px of it."""
    raw = _ratio(image, model)[None]
    b = _smooth(raw, radius) if radius > 0 else raw
    return _peaks(raw, b, window)[0]


def _peaks(raw: np.ndarray, b: np.ndarray, window: int) -> list[Detection]:
    """Return each image's peak of the smoothed backprojection ``b`` (K, H, W), refined to
    the centroid of the raw backprojection ``raw`` within ``window`` px of it."""
    out = np.empty((len(raw), 4))
    peaks(np.ascontiguousarray(raw, float), np.ascontiguousarray(b, float), window, out)
    return [Detection(*(float(x) for x in row)) for row in out.tolist()]


def gray(images: np.ndarray) -> np.ndarray:
    """Return the gray levels (..., H, W) in [0, 1] of RGB images (..., H, W, 3), smoothed by
    a Gaussian of 1 px within each image: what the gaze's flow and vergence compare."""
    img = np.asarray(images)
    if img.dtype != np.uint8:
        img = img.astype(float)
    flat = np.ascontiguousarray(img.reshape(-1, *img.shape[-3:]))
    out = np.empty(flat.shape[:-1])
    gray_levels(flat, out)
    return out.reshape(img.shape[:-1])


@dataclass(frozen=True)
class Recognition:
    """What colour indexing finds in K images at once: each image's histogram (K, 2048) as
    fractions of its pixels, its model's ``locate`` detection (K of them), its ``gray``
    (K, H, W) and its target image (K, H, W): the gray weighted by the model's
    backprojection smoothed over ``TARGET_RADIUS`` px (``gaze.target_image``)."""

    histograms: np.ndarray
    detections: list[Detection]
    grays: np.ndarray
    targets: np.ndarray

    def part(self, start: int, stop: int) -> Recognition:
        """Return what was found in images ``start`` to ``stop`` - 1."""
        return Recognition(
            self.histograms[start:stop],
            self.detections[start:stop],
            self.grays[start:stop],
            self.targets[start:stop],
        )


TARGET_RADIUS = 2  # px: the disk smoothing a target image's backprojection


def recognise(
    images: np.ndarray,
    models: np.ndarray,
    radius: int = 1,
    window: int = 8,
    keep: np.ndarray | None = None,
) -> Recognition:
    """Return the histograms of K RGB images (K, H, W, 3), where each image's model
    (K, 2048) peaks in it, their grays and target images: ``histogram``, ``locate``,
    ``gray`` and ``gaze.target_image`` of every image, the pixels binned, counted,
    backprojected and smoothed for all images in one pass (the same numbers image by
    image). ``keep`` (K,) bool: the images whose gray and target image are wanted (the
    others' left zero); default all. Raises ValueError for images not uint8 (0-255 a channel,
    as the rasteriser draws them): a cast would wrap or truncate other values silently."""
    img = np.asarray(images)
    if img.dtype != np.uint8:
        raise ValueError(f"recognise takes uint8 RGB images (0-255 a channel), not {img.dtype}")
    img = np.ascontiguousarray(img)
    sel = np.ones(len(img), bool) if keep is None else np.asarray(keep, bool)
    hist, found, g, target = recognise_all(
        img, np.ascontiguousarray(models, float), sel, radius, TARGET_RADIUS, window
    )
    dets = [Detection(*(float(x) for x in row)) for row in found.tolist()]
    return Recognition(hist, dets, g, target)
