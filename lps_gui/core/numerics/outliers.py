"""Outlier views (SPEC 4, paper Fig. 9): flag, never drop silently.

Two kinds: a *bumped* camera does not fit the common rotation, so its RMS
reprojection error stands out; a *replaced* image (another position's image,
a wrong file) reprojects fine but its position leaves the local trend of its
run. Both are judged against robust scales (median and MAD), k sigmas.
"""
from __future__ import annotations

import numpy as np

MAD_TO_SIGMA = 1.4826


def robust_sigma(x: np.ndarray) -> float:
    x = np.asarray(x, dtype=float)
    x = x[np.isfinite(x)]
    if x.size == 0:
        return 0.0
    return MAD_TO_SIGMA * float(np.median(np.abs(x - np.median(x))))


def reprojection_outliers(rms_px: np.ndarray, valid: np.ndarray, k: float) -> np.ndarray:
    """Views whose RMS reprojection error exceeds median + k robust sigmas, shape (K,) bool."""
    ok = valid & np.isfinite(rms_px)
    if ok.sum() < 3:
        return np.zeros_like(valid)
    med = float(np.median(rms_px[ok]))
    scale = max(robust_sigma(rms_px[ok]), 0.02 * med, 1e-12)
    return valid & (rms_px > med + k * scale)


def local_trend_residuals(
    deviation: np.ndarray, target_mm: np.ndarray, groups: np.ndarray, valid: np.ndarray, half_window: int = 3
) -> np.ndarray:
    """Deviation minus the median of its neighbours in the same run and direction (self excluded).

    Returns shape (K,), NaN where a view has fewer than 2 valid neighbours.
    """
    out = np.full(deviation.shape, np.nan)
    offsets = np.r_[np.arange(-half_window, 0), np.arange(1, half_window + 1)]
    for g in np.unique(groups):
        idx = np.flatnonzero((groups == g) & valid)
        if idx.size < 3:
            continue
        idx = idx[np.argsort(target_mm[idx], kind="stable")]
        d = deviation[idx]
        at = np.arange(idx.size)[:, None] + offsets[None, :]  # each view's neighbours, shape (m, 2 half_window)
        inside = (at >= 0) & (at < idx.size)
        window = np.sort(np.where(inside, d[np.clip(at, 0, idx.size - 1)], np.nan), axis=1)  # NaN sort last
        n = inside.sum(axis=1)
        rows = np.arange(idx.size)
        median = 0.5 * (window[rows, (n - 1) // 2] + window[rows, n // 2])
        ok = n >= 2
        out[idx[ok]] = d[ok] - median[ok]
    return out


def position_outliers(
    deviation_um: np.ndarray,
    target_mm: np.ndarray,
    groups: np.ndarray,
    valid: np.ndarray,
    sigma_um: np.ndarray,
    k: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Views whose position departs from the local trend by more than k robust sigmas.

    The scale is the larger of the residuals' robust sigma and each view's own
    position sigma, so a perfect stage with tiny noise does not flag noise.
    Returns (flags (K,) bool, residual_um (K,)).
    """
    resid = local_trend_residuals(deviation_um, target_mm, groups, valid)
    scale = np.maximum(robust_sigma(resid[valid]), np.nan_to_num(sigma_um, nan=0.0))
    flags = valid & np.isfinite(resid) & (np.abs(resid) > k * np.maximum(scale, 1e-9))
    return flags, resid
