"""Outlier views (SPEC 4, paper Fig. 9): flag, never drop silently.

Two kinds: a *bumped* camera does not fit the common rotation, so its RMS
reprojection error stands out; a *replaced* image (another position's image,
a wrong file) reprojects fine but its position leaves the local (linear) trend
of its run; a smooth deviation, a scale error above all, is no outlier. Both are judged against robust scales (median and MAD), k sigmas.
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


def reprojection_outliers(rms_px: np.ndarray, valid: np.ndarray, k: float, half_window: int = 3) -> np.ndarray:
    """Views whose RMS reprojection error exceeds median + k robust sigmas, shape (K,) bool.

    A bumped camera is a spike: it also stands k scales above the median RMS of
    the ``2 half_window`` views nearest in capture order (self excluded, the
    window sliding inward at the ends). A stage whose motion the model does not
    quite express raises the RMS smoothly towards the ends of what was seen so
    far, and the newest view of a live estimate sits at the end of that slope:
    above the median of all views, but not above its neighbours.
    """
    ok = valid & np.isfinite(rms_px)
    if ok.sum() < 3:
        return np.zeros_like(valid)
    med = float(np.median(rms_px[ok]))
    scale = max(robust_sigma(rms_px[ok]), 0.02 * med, 1e-12)
    idx = np.flatnonzero(ok)
    r = rms_px[idx]
    m = r.size
    width = min(2 * half_window + 1, m)
    rows = np.arange(m)
    start = np.clip(rows - half_window, 0, m - width)
    window = start[:, None] + np.arange(width)[None, :]
    nb = np.sort(np.where(window == rows[:, None], m, window), axis=1)[:, :-1]  # self moved last and dropped
    local = np.full(rms_px.shape, np.inf)
    local[idx] = np.median(r[nb], axis=1)
    return valid & (rms_px > med + k * scale) & (rms_px > local + k * scale)


def local_trend_residuals(
    deviation: np.ndarray, target_mm: np.ndarray, groups: np.ndarray, valid: np.ndarray, half_window: int = 3
) -> np.ndarray:
    """Deviation minus the robust line through its neighbours in the same run and direction (self excluded).

    The neighbours are the ``2 half_window`` views nearest in target order (the
    window slides inward at a run's ends, so an end view has as many). The
    trend is *linear*, not constant: a stage with a wrong steps/mm deviates
    along a line, and a median of one-sided neighbours would call its end
    views (then, round after round, the next ones) replaced images. The line
    is Theil-Sen (median of the pairwise slopes, median intercept), which
    one replaced image among the neighbours does not move.
    Returns shape (K,), NaN where a view has fewer than 2 valid neighbours.
    """
    out = np.full(deviation.shape, np.nan)
    for g in np.unique(groups):
        idx = np.flatnonzero((groups == g) & valid)
        if idx.size < 3:
            continue
        idx = idx[np.argsort(target_mm[idx], kind="stable")]
        out[idx] = _robust_line_residuals(deviation[idx], target_mm[idx], half_window)
    return out


def _robust_line_residuals(d: np.ndarray, t: np.ndarray, half_window: int) -> np.ndarray:
    """For views sorted by target, each one's deviation minus its neighbours' Theil-Sen line at its target."""
    m = d.size
    width = min(2 * half_window + 1, m)
    rows = np.arange(m)
    start = np.clip(rows - half_window, 0, m - width)
    window = start[:, None] + np.arange(width)[None, :]  # shape (m, width), self included
    nb = np.sort(np.where(window == rows[:, None], m, window), axis=1)[:, :-1]  # self moved last and dropped
    dn, tn = d[nb], t[nb] - t[:, None]  # neighbours relative to the view's own target
    a, b = np.triu_indices(width - 1, 1)
    dt = tn[:, b] - tn[:, a]
    tied = np.abs(dt) <= 1e-9 * np.maximum(np.abs(tn[:, a]) + np.abs(tn[:, b]), 1e-12)
    with np.errstate(invalid="ignore", divide="ignore"):
        slopes = np.where(tied, np.nan, (dn[:, b] - dn[:, a]) / dt)
    slope = np.zeros(m)
    some = ~np.all(tied, axis=1)  # neighbours all at one target (repeated frames): a constant trend
    slope[some] = np.nanmedian(slopes[some], axis=1)
    return d - np.median(dn - slope[:, None] * tn, axis=1)


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
