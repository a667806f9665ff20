"""collinear_views, vectorized over views (issue 15), gives the verdicts of the per-view SVD it replaced."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.geometry.view_geometry import LINE_RATIO, collinear_views


def _per_view_svd(corners_px):
    """The previous implementation: one SVD per view."""
    out = []
    for k, uv in enumerate(np.asarray(corners_px, dtype=float)):
        pts = uv[np.all(np.isfinite(uv), axis=-1)]
        if len(pts) < 3:
            continue
        sv = np.linalg.svd(pts - pts.mean(axis=0), compute_uv=False)
        if sv[0] == 0 or sv[-1] / sv[0] < LINE_RATIO:
            out.append(k)
    return out


@pytest.mark.parametrize("seed", range(4))
def test_verdicts_match_the_per_view_svd(seed):
    rng = np.random.default_rng(seed)
    K, N = 600, 30
    c = rng.uniform(0, 2000, (K, N, 2))
    for k in range(0, K, 5):  # lines with noise from far below to far above the limit, at every angle
        t = rng.uniform(-1, 1, N)
        angle = rng.uniform(0, np.pi)
        line = np.stack([np.cos(angle) * t, np.sin(angle) * t], 1) * rng.uniform(1, 500)
        c[k] = 1000 + line + rng.normal(0, 10 ** rng.uniform(-8, 1), (N, 2))
    for k in range(1, K, 9):
        c[k] = c[k, 0]  # one point
    for k in range(2, K, 7):
        c[k, rng.integers(0, N, rng.integers(1, N))] = np.nan  # missing corners
    c[3] = np.nan
    c[4, :-2] = np.nan  # two corners left
    c[6] = 0.1  # identical points whose mean is not exactly 0.1
    c[8, 0, 1] = np.inf
    c[11, :3] = [[1.0, 1.0], [2.0, 2.0], [3.0, 3.0]]
    c[11, 3:] = np.nan
    want = _per_view_svd(c)
    assert len(want) > 50
    assert collinear_views(c) == want


def test_no_views():
    assert collinear_views(np.zeros((0, 5, 2))) == []
