"""Compiled loops (Numba) for the retinas' pixel arithmetic: the gray levels and the colour
backprojection of a batch of images, the normalised cross-correlation of a stereo point match
and the least-squares optical flow of the stabiliser. Each makes one pass over the pixels
without temporary arrays (its numbers equal the plain NumPy formulas' to rounding): the gaze
of ten fishes does these a few hundred times a second on 64 x 64 images, where array calls'
overhead and temporaries would cost more than the arithmetic.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from zoetic.jitcache import fresh_numba_cache

fresh_numba_cache()

BINS = (16, 16, 8)  # colour bins along rg, by, wb (Swain & Ballard's opponent axes)
GAUSS = np.exp(-0.5 * np.arange(-4, 5) ** 2.0)
GAUSS /= GAUSS.sum()  # sigma 1 px, truncated at 4 sigma (scipy's gaussian_filter)


def _reflected(n: int, r: int) -> np.ndarray:
    """Return the indices of a line of n samples padded by r at each end, mirrored at its
    ends (d c b a | a b c d | d c b a)."""
    k = np.arange(-r, n + r)
    k = np.where(k < 0, -k - 1, k)
    return np.where(k >= n, 2 * n - k - 1, k)


def gray_levels(images, out) -> None:
    """Write into out (K, H, W) the mean of the RGB channels of images (K, H, W, 3) / 255,
    smoothed along rows then columns by a Gaussian of 1 px (mirrored at the edges)."""
    r = len(GAUSS) // 2
    _gray_levels(images, GAUSS, _reflected(out.shape[1], r), _reflected(out.shape[2], r), out)


@njit(cache=True)
def _gray_levels(images, weights, rows, cols, out) -> None:
    g = np.empty(out.shape[1:])
    t = np.empty(out.shape[1:])
    p = np.empty(out.shape[2] + len(weights) - 1)
    for k in range(out.shape[0]):
        _gray_one(images[k], weights, rows, cols, g, t, p, out[k])


@njit(cache=True)
def _gray_one(image, weights, rows, cols, g, t, p, out) -> None:
    """Write into out (H, W) the gray of one RGB image (``gray_levels``); g, t (H, W) and
    p (W + taps - 1) are scratch."""
    h, w = out.shape
    r = len(weights) // 2
    for j in range(h):
        for i in range(w):
            c = image[j, i]
            g[j, i] = (float(c[0]) + float(c[1]) + float(c[2])) / (3.0 * 255.0)
    t[:] = 0.0
    for j in range(h):
        for d in range(2 * r + 1):
            jj = rows[j + d]
            wd = weights[d]
            for i in range(w):
                t[j, i] += wd * g[jj, i]
    for j in range(h):
        for i in range(w + 2 * r):
            p[i] = t[j, cols[i]]
        for i in range(w):
            acc = 0.0
            for d in range(2 * r + 1):
                acc += weights[d] * p[i + d]
            out[j, i] = acc


@njit(cache=True)
def disk_smooth(raw, radius: int, out) -> None:
    """Write into out (K, H, W) the mean of raw (K, H, W) over a disk of ``radius`` px around
    each pixel, zeros outside the image."""
    for k in range(raw.shape[0]):
        _disk_one(raw[k], radius, out[k])


@njit(cache=True)
def _disk_one(raw, r: int, o) -> None:
    """Write into o (H, W) the mean of raw (H, W) over a disk of r px around each pixel
    (zeros outside). Each nonzero pixel is spread over its disk (a backprojection is mostly
    zeros); every sum still runs over its disk row by row."""
    h, w = raw.shape
    n = 0
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            if dx * dx + dy * dy <= r * r:
                n += 1
    wt = 1.0 / n
    o[:, :] = 0.0
    for j in range(h):
        for i in range(w):
            v = raw[j, i]
            if v == 0.0:
                continue
            for dy in range(max(-r, -j), min(r, h - 1 - j) + 1):
                for dx in range(max(-r, -i), min(r, w - 1 - i) + 1):
                    if dx * dx + dy * dy <= r * r:
                        o[j + dy, i + dx] += v
    for j in range(h):
        for i in range(w):
            o[j, i] *= wt


@njit(cache=True)
def peaks(raw, smooth, window: int, out) -> None:
    """Write into out (K, 4) each image's (col, row, strength, mass): the first maximum of
    ``smooth`` (K, H, W), refined to the centroid of ``raw`` within ``window`` px of it
    (pixel centres at index + 0.5; the peak's own pixel and no mass when raw is empty)."""
    for k in range(raw.shape[0]):
        _peak_one(raw[k], smooth[k], window, out[k])


@njit(cache=True)
def _peak_one(raw, smooth, window: int, out) -> None:
    """Write into out (4,) one image's peak (``peaks``)."""
    h, w = raw.shape
    best, bj, bi = -np.inf, 0, 0
    for j in range(h):
        for i in range(w):
            if smooth[j, i] > best:
                best, bj, bi = smooth[j, i], j, i
    m = sx = sy = 0.0
    for j in range(max(bj - window, 0), min(bj + window + 1, h)):
        for i in range(max(bi - window, 0), min(bi + window + 1, w)):
            v = raw[j, i]
            m += v
            sx += i * v
            sy += j * v
    if m <= 0:
        out[0], out[1], out[2], out[3] = bi + 0.5, bj + 0.5, 0.0, 0.0
    else:
        out[0], out[1], out[2], out[3] = sx / m + 0.5, sy / m + 0.5, best, m


@njit(cache=True)
def ncc_scores(tpl, tn: float, pb, r0: int, r1: int, c0: int, c1: int, out) -> None:
    """Write into out (r1 - r0, c1 - c0) the normalised cross-correlation of the template
    ``tpl`` (k, k; less its mean, ``tn`` its norm) with pb's k x k squares cornered at rows
    r0..r1-1, cols c0..c1-1, each less its mean (-1 where a square is flat)."""
    k = tpl.shape[0]
    n = k * k
    # the squares' means from the running sums of pb (an integral image)
    cum = np.zeros((r1 - r0 + k, c1 - c0 + k + 1))
    for y in range(r1 - r0 + k - 1):
        row = 0.0
        for x in range(c1 - c0 + k - 1):
            row += pb[r0 + y, c0 + x]
            cum[y + 1, x + 1] = cum[y, x + 1] + row
    for r in range(r0, r1):
        for c in range(c0, c1):
            a, b = r - r0, c - c0
            mb = (cum[a + k, b + k] - cum[a, b + k] - cum[a + k, b] + cum[a, b]) / n
            num = ss = 0.0
            for y in range(k):
                for x in range(k):
                    d = pb[r + y, c + x] - mb
                    num += d * tpl[y, x]
                    ss += d * d
            norm = np.sqrt(ss) * tn
            out[r - r0, c - c0] = num / max(norm, 1e-9) if norm > 1e-9 else -1.0


@njit(cache=True)
def _bilinear(a, y: float, x: float) -> float:
    """Return image a at continuous index (y, x), linear between samples, the coordinates
    held to the image (its edge samples repeated outside)."""
    h, w = a.shape
    y = min(max(y, 0.0), h - 1.0)
    x = min(max(x, 0.0), w - 1.0)
    j, i = min(int(y), h - 2), min(int(x), w - 2)
    fy, fx = y - j, x - i
    top = a[j, i] * (1.0 - fx) + a[j, i + 1] * fx
    bot = a[j + 1, i] * (1.0 - fx) + a[j + 1, i + 1] * fx
    return top * (1.0 - fy) + bot * fy


@njit(cache=True)
def flow_shift(a, b, iterations: int, margin: int) -> tuple[float, float]:
    """Return the translation (u, v) px (cols, rows) carrying gray image a onto b: least
    squares on Ix u + Iy v + It = 0 over the image less ``margin`` px (gradients central,
    of the mean of b and a shifted by the estimate so far), refined ``iterations`` times."""
    h, w = a.shape
    u = v = 0.0
    s = np.empty((h, w))
    gt = np.empty((h, w))
    for _ in range(iterations):
        for j in range(margin - 1, h - margin + 1):
            for i in range(margin - 1, w - margin + 1):
                wv = _bilinear(a, j - v, i - u) if (u != 0.0 or v != 0.0) else a[j, i]
                s[j, i] = 0.5 * (wv + b[j, i])
                gt[j, i] = b[j, i] - wv
        sxx = sxy = syy = sxt = syt = 0.0
        for j in range(margin, h - margin):
            for i in range(margin, w - margin):
                gx = 0.5 * (s[j, i + 1] - s[j, i - 1])
                gy = 0.5 * (s[j + 1, i] - s[j - 1, i])
                sxx += gx * gx
                sxy += gx * gy
                syy += gy * gy
                sxt += gx * gt[j, i]
                syt += gy * gt[j, i]
        det = sxx * syy - sxy * sxy
        if det < 1e-9:
            break
        du = (-sxt * syy + syt * sxy) / det
        dv = (-syt * sxx + sxt * sxy) / det
        u, v = u + du, v + dv
        if abs(du) + abs(dv) < 1e-3:
            break
    return u, v


@njit(cache=True)
def _backproject_one(bins, model, hist, raw, ratio) -> None:
    """Write into hist (B,) one image's colour histogram as fractions of its pixels, from
    its pixels' colour bins (H, W), and into raw (H, W) each pixel's backprojection
    min(M_j / I_j, 1) of its bin j under the model (B,); ratio (B,) is scratch."""
    h, w = bins.shape
    hist[:] = 0.0
    for j in range(h):
        for i in range(w):
            hist[bins[j, i]] += 1.0
    for b in range(len(hist)):
        hist[b] /= h * w
        ratio[b] = min(model[b] / hist[b], 1.0) if hist[b] > 0 else 0.0
    for j in range(h):
        for i in range(w):
            raw[j, i] = ratio[bins[j, i]]


def recognise_all(images, models, keep, radius: int, target_radius: int, window: int):
    """Return what colour indexing finds in K RGB images (K, H, W, 3) uint8 under their
    models (K, B): histograms (K, B), peaks (K, 4) as ``peaks`` (backprojection smoothed
    over ``radius`` px), and for the images ``keep`` (K,) marks their grays and target
    images (K, H, W) (the gray times the backprojection smoothed over ``target_radius``
    px; zeros for the rest): each image binned, counted, backprojected, smoothed and
    located in one pass, by the same loops as the separate kernels."""
    k, h, w = images.shape[:3]
    hist = np.empty((k, models.shape[1]))
    found = np.empty((k, 4))
    grays = np.zeros((k, h, w))
    targets = np.zeros((k, h, w))
    r = len(GAUSS) // 2
    rows, cols = _reflected(h, r), _reflected(w, r)
    out = (hist, found, grays, targets)
    _recognise_all(images, models, keep, radius, target_radius, window, GAUSS, rows, cols, out)
    return hist, found, grays, targets


@njit(cache=True)
def _recognise_all(
    images, models, keep, radius, target_radius, window, weights, rows, cols, out
) -> None:
    hist, found, grays, targets = out
    k_n, h, w = images.shape[:3]
    bins = np.empty((h, w), np.int64)
    raw = np.empty((h, w))
    smooth = np.empty((h, w))
    ratio = np.empty(hist.shape[1])
    g, t, p = np.empty((h, w)), np.empty((h, w)), np.empty(w + len(weights) - 1)
    for k in range(k_n):
        colour_bins(images[k].reshape(h * w, 3), bins.reshape(h * w))
        _backproject_one(bins, models[k], hist[k], raw, ratio)
        if radius > 0:
            _disk_one(raw, radius, smooth)
            _peak_one(raw, smooth, window, found[k])
        else:
            _peak_one(raw, raw, window, found[k])
        if keep[k]:
            _gray_one(images[k], weights, rows, cols, g, t, p, grays[k])
            _disk_one(raw, target_radius, smooth)
            for j in range(h):
                for i in range(w):
                    targets[k, j, i] = grays[k, j, i] * smooth[j, i]


@njit(cache=True)
def colour_bins(pixels, out) -> None:
    """Write into out (P,) the colour bin of each RGB pixel (P, 3): rg = R - G,
    by = 2B - R - G and wb = R + G + B binned ``BINS`` ways each (``recognition.bin_index``)."""
    n_rg, n_by, n_wb = BINS
    for p in range(pixels.shape[0]):
        r, g, b = int(pixels[p, 0]), int(pixels[p, 1]), int(pixels[p, 2])
        rg = (r - g + 255) * n_rg // 511
        by = (2 * b - r - g + 510) * n_by // 1021
        wb = (r + g + b) * n_wb // 766
        out[p] = (rg * n_by + by) * n_wb + wb


@njit(cache=True)
def box_sums(x, k: int, s1, s2) -> None:
    """Write into s1 and s2 (H - k + 1, W - k + 1) the sums of x (H, W) and of its squares
    over each k x k square (cornered at the index), added up square by square, rows first."""
    h, w = x.shape
    rows1 = np.zeros((h, w - k + 1))
    rows2 = np.zeros((h, w - k + 1))
    for j in range(h):
        for i in range(w - k + 1):
            a = b = 0.0
            for d in range(k):
                v = x[j, i + d]
                a += v
                b += v * v
            rows1[j, i], rows2[j, i] = a, b
    for j in range(h - k + 1):
        for i in range(w - k + 1):
            a = b = 0.0
            for d in range(k):
                a += rows1[j + d, i]
                b += rows2[j + d, i]
            s1[j, i], s2[j, i] = a, b
