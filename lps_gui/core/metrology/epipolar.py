"""The epipolar check of a light field (issue 38): what rectification left of vertical disparity, and how
linear the disparity of a plane is in the views' positions.

In a rectified light field along a line, a scene point keeps its image row in every view (vertical
disparity zero) and moves along it by f (s_i - s_j) / Z: the disparity of a plane parallel to the motion
is linear in the positions, one slope per plane. Tracks are a point's image position in every view
((K, N) arrays, NaN where unseen); points seen in fewer than two views do not count.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def _seen(track: np.ndarray) -> np.ndarray:
    return np.isfinite(track).sum(axis=0) >= 2


def vertical_disparity_rms(v: np.ndarray) -> float:
    """RMS (px) of every point's row about its mean row over the views that see it; ``v`` (K, N)."""
    v = np.asarray(v, dtype=float)
    keep = _seen(v)
    if not keep.any():
        return float("nan")
    d = v[:, keep] - np.nanmean(v[:, keep], axis=0)
    return float(np.sqrt(np.nanmean(d**2)))


@dataclass(frozen=True)
class DisparityFit:
    """Disparity of one plane against the views' positions: one slope, one intercept per point."""

    slope_px_per_mm: float
    residual_rms_px: float
    n_points: int

    def depth_mm(self, focal_px: float) -> float:
        """The plane's depth the slope implies, |f / slope|."""
        return float(abs(focal_px / self.slope_px_per_mm)) if self.slope_px_per_mm else float("inf")


def disparity_fit(u: np.ndarray, positions_mm: np.ndarray) -> DisparityFit:
    """Least-squares fit u_in = a_n + b s_i over every seen (i, n); ``u`` (K, N), ``positions_mm`` (K,)."""
    u = np.asarray(u, dtype=float)
    keep = _seen(u)
    u = u[:, keep]
    s = np.broadcast_to(np.asarray(positions_mm, dtype=float)[:, None], u.shape)
    seen = np.isfinite(u)
    s = np.where(seen, s, np.nan)
    uc = u - np.nanmean(u, axis=0)
    sc = s - np.nanmean(s, axis=0)
    denom = float(np.nansum(sc**2))
    if not keep.any() or denom <= 0:
        return DisparityFit(float("nan"), float("nan"), int(keep.sum()))
    b = float(np.nansum(sc * uc)) / denom
    r = uc - b * sc
    dof = max(int(seen.sum()) - int(keep.sum()) - 1, 1)
    return DisparityFit(b, float(np.sqrt(np.nansum(r**2) / dof)), int(keep.sum()))
