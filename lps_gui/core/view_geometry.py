"""Checks that a set of board views can determine what is asked of it.

Two views of the same image add no information but shrink the reported
uncertainty as if they did (four copies of one image calibrate to a
confident, wrong focal length); a view whose corners lie on one line (a
corrupted corner file, a board seen edge-on) fixes no pose. Both are
caught here, before any solver runs, with the reason named.
"""
from __future__ import annotations

import numpy as np

DUPLICATE_PX = 0.5  # views whose corners all agree to within this are the same view
LINE_RATIO = 1e-3  # smallest/largest spread of a view's corners below this: all on one line


def collinear_views(corners_px: np.ndarray) -> list[int]:
    """Indices of views (K, N, 2) whose detected corners lie on one line (or one point).

    Views with fewer than three finite corners are left to the callers'
    own minimum-corner rules.
    """
    out = []
    for k, uv in enumerate(np.asarray(corners_px, dtype=float)):
        pts = uv[np.all(np.isfinite(uv), axis=-1)]
        if len(pts) < 3:
            continue
        sv = np.linalg.svd(pts - pts.mean(axis=0), compute_uv=False)
        if sv[0] == 0 or sv[-1] / sv[0] < LINE_RATIO:
            out.append(k)
    return out


def duplicate_views(corners_px: np.ndarray, tol_px: float = DUPLICATE_PX) -> list[tuple[int, int]]:
    """Pairs (first, later) of views whose common corners all agree within ``tol_px``."""
    c = np.asarray(corners_px, dtype=float)
    pairs = []
    for j in range(1, len(c)):
        diff = np.abs(c[:j] - c[j])  # (j, N, 2), NaN where either misses a corner
        both = np.all(np.isfinite(diff), axis=-1)
        with np.errstate(invalid="ignore"):
            worst = np.where(both, diff.max(axis=-1), 0.0).max(axis=-1)
        same = (both.sum(axis=-1) >= 3) & (worst <= tol_px)
        if same.any():
            pairs.append((int(np.argmax(same)), j))
    return pairs
