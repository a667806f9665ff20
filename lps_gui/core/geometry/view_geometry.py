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
_VIEWS_PER_PASS = 256  # views per numpy pass: temporaries of about 2 MB


def collinear_views(corners_px: np.ndarray) -> list[int]:
    """Indices of views (K, N, 2) whose detected corners lie on one line (or one point).

    Views with fewer than three finite corners are left to the callers'
    own minimum-corner rules. The test is the ratio of the centred corners'
    singular values; all views get it at once from their 2x2 scatter
    matrices, and only a view near the limit (or degenerate) gets the exact
    SVD, so the verdicts are those of the per-view SVD.
    """
    uv = np.asarray(corners_px, dtype=float)  # shape (K, N, 2)
    if not len(uv):
        return []
    K, N = uv.shape[:2]
    n, ratio, big = np.empty(K, int), np.empty(K), np.empty(K)
    for lo in range(0, K, _VIEWS_PER_PASS):  # small temporaries, reused
        part = uv[lo : lo + _VIEWS_PER_PASS]
        seen = np.isfinite(part[..., 0]) & np.isfinite(part[..., 1])  # shape (k, N)
        count = seen.sum(axis=1)
        masked = int(count.min(initial=N)) < N
        if masked:
            part = np.where(seen[..., None], part, 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = np.matmul(part.transpose(0, 2, 1), np.ones(N)) / count[:, None]  # shape (k, 2)
        d = part - mean[:, None]
        if masked:
            d *= seen[..., None]
        scatter = np.matmul(d.transpose(0, 2, 1), d)  # shape (k, 2, 2)
        sxx, syy, sxy = scatter[:, 0, 0], scatter[:, 1, 1], scatter[:, 0, 1]
        top = (sxx + syy) / 2 + np.hypot((sxx - syy) / 2, sxy)  # eigenvalues of the scatter matrix: squared singular values
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio[lo : lo + len(part)] = np.sqrt(np.maximum(sxx * syy - sxy**2, 0.0) / top) / np.sqrt(top)  # smallest / largest
        n[lo : lo + len(part)], big[lo : lo + len(part)] = count, top
    near = ~((ratio > 10 * LINE_RATIO) | (ratio < 0.1 * LINE_RATIO)) | ~(big > 0)  # NaN lands here too
    out = []
    for k in np.flatnonzero(n >= 3):
        if near[k]:
            pts = uv[k][np.all(np.isfinite(uv[k]), axis=-1)]
            sv = np.linalg.svd(pts - pts.mean(axis=0), compute_uv=False)
            if sv[0] == 0 or sv[-1] / sv[0] < LINE_RATIO:
                out.append(int(k))
        elif ratio[k] < LINE_RATIO:
            out.append(int(k))
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
