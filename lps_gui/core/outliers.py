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
    for g in np.unique(groups):
        idx = np.flatnonzero((groups == g) & valid)
        if idx.size < 3:
            continue
        idx = idx[np.argsort(target_mm[idx], kind="stable")]
        d = deviation[idx]
        for j, i in enumerate(idx):
            lo, hi = max(0, j - half_window), min(idx.size, j + half_window + 1)
            neighbours = np.concatenate([d[lo:j], d[j + 1 : hi]])
            if neighbours.size >= 2:
                out[i] = d[j] - np.median(neighbours)
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
