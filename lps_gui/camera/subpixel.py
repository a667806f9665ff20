"""Corner positions without pixel locking: the last sub-pixel step of every detection.

cv2.cornerSubPix samples its window at the current estimate by bilinear
interpolation (getRectSubPix), and the interpolation smooths by an amount that
depends on the sub-pixel phase: on an ideal blurred X-junction it pulls a
corner by up to 0.013 px towards the pixel edges (a sine of the phase). Over
a board those errors do not average out, because neighbouring corners share
their phase pattern; on a planar gantry they leaned the measured squareness by
about 4 sigma (issue 35, docs/planar.md). This step solves the same
gradient-orthogonality equations (every gradient in the window is orthogonal
to the vector from the corner to its pixel) on the image's own pixels: the
gradients are central differences at pixel centres, nothing is interpolated,
and the weights, centred on the estimate, fall smoothly to zero inside the
window, so the solution moves continuously with the image. On an ideal
junction it is exact to 1e-4 px at every phase. Vectorized over all corners.
"""
from __future__ import annotations

import numpy as np

ITERATIONS = 20  # fixed-point steps; starting from cornerSubPix, 3-5 reach 1e-6 px
TOLERANCE_PX = 1e-6
WEIGHT_RADIUS = 1.5  # the weights vanish at this many cornerSubPix half windows (0.45 of a square: no other corner)
MAX_SHIFT_PX = 0.5  # a corner the polish moves farther than this keeps cornerSubPix's position (not a junction)


def polish_corners(grey: np.ndarray, corners_px: np.ndarray, half_window: int) -> np.ndarray:
    """Corners (N, 2) px refined by interpolation-free gradient orthogonality; shape (N, 2) float64.

    ``half_window`` is cornerSubPix's: the weights (1 - r^2/R^2)^2 vanish at
    R = WEIGHT_RADIUS half windows (about as many pixels weigh as in
    cornerSubPix's Gaussian window), so a window of R + 1 pixels holds every
    weighted pixel whatever the estimate's phase. The gradients are Sobel's
    (central differences smoothed across), which pixel noise affects less. Corners too near the image border, or that would
    move more than MAX_SHIFT_PX, keep their input position.
    """
    q0 = np.asarray(corners_px, dtype=np.float64).reshape(-1, 2)
    h = WEIGHT_RADIUS * float(max(half_window, 2))
    r = int(np.ceil(h)) + 1
    H, W = grey.shape[:2]
    inside = ((q0[:, 0] >= r + 2) & (q0[:, 0] <= W - r - 3) & (q0[:, 1] >= r + 2) & (q0[:, 1] <= H - r - 3)
              & np.all(np.isfinite(q0), axis=1))
    out = q0.copy()
    if not inside.any():
        return out
    img = np.asarray(grey, dtype=np.float64)
    q = q0[inside].copy()
    off = np.arange(-r - 1, r + 2)  # the window plus one pixel each side for the central differences
    for _ in range(ITERATIONS):
        c = np.round(q).astype(np.int64)
        ys = c[:, 1, None, None] + off[None, :, None]
        xs = c[:, 0, None, None] + off[None, None, :]
        patch = img[ys, xs]  # shape (N, 2r + 3, 2r + 3)
        dxp = 0.5 * (patch[:, :, 2:] - patch[:, :, :-2])  # central differences, then [1 2 1]/4 across (Sobel)
        dyp = 0.5 * (patch[:, 2:, :] - patch[:, :-2, :])
        gx = 0.25 * (dxp[:, :-2, :] + 2.0 * dxp[:, 1:-1, :] + dxp[:, 2:, :])
        gy = 0.25 * (dyp[:, :, :-2] + 2.0 * dyp[:, :, 1:-1] + dyp[:, :, 2:])
        px = xs[:, :, 1:-1].astype(np.float64)  # shape (N, 1, 2r + 1): broadcasts over rows
        py = ys[:, 1:-1, :].astype(np.float64)  # shape (N, 2r + 1, 1)
        dx, dy = px - q[:, 0, None, None], py - q[:, 1, None, None]
        w = np.clip(1.0 - (dx * dx + dy * dy) / (h * h), 0.0, None) ** 2
        wxx, wxy, wyy = w * gx * gx, w * gx * gy, w * gy * gy
        a, b, d = wxx.sum((1, 2)), wxy.sum((1, 2)), wyy.sum((1, 2))
        # relative to the window's centre pixel, so the sums do not lose digits to the absolute coordinates
        ox, oy = px - c[:, 0, None, None], py - c[:, 1, None, None]
        b1 = (wxx * ox + wxy * oy).sum((1, 2))
        b2 = (wxy * ox + wyy * oy).sum((1, 2))
        det = a * d - b * b
        ok = det > 1e-12 * np.maximum(a * d, 1e-300)
        new = q.copy()
        new[ok, 0] = c[ok, 0] + (d[ok] * b1[ok] - b[ok] * b2[ok]) / det[ok]
        new[ok, 1] = c[ok, 1] + (a[ok] * b2[ok] - b[ok] * b1[ok]) / det[ok]
        new = np.where(np.abs(new - q0[inside]).max(axis=1, keepdims=True) <= MAX_SHIFT_PX, new, q0[inside])
        step = float(np.max(np.abs(new - q))) if new.size else 0.0
        q = new
        if step < TOLERANCE_PX:
            break
    out[inside] = q
    return out
