"""core/numerics/outliers: robust scales, and flagging a bumped view (reprojection) or a replaced one (position)."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.numerics.outliers import (
    MAD_TO_SIGMA,
    local_trend_residuals,
    position_outliers,
    reprojection_outliers,
    robust_sigma,
)


def test_robust_sigma_of_gaussian_noise_ignores_a_wild_value():
    x = np.random.default_rng(0).normal(0.0, 2.0, 20000)
    assert abs(robust_sigma(x) - 2.0) < 0.05
    x[:50] = 1e6
    x[50] = np.nan
    assert abs(robust_sigma(x) - 2.0) < 0.06
    assert robust_sigma(np.array([])) == 0.0
    assert MAD_TO_SIGMA == 1.4826


def test_reprojection_outlier_is_flagged_and_invalid_views_are_not():
    rms = np.full(30, 0.2) + np.random.default_rng(1).normal(0, 0.005, 30)
    rms[7] = 0.9  # a bumped camera
    rms[12] = 5.0  # not valid (board not found): never flagged
    valid = np.ones(30, bool)
    valid[12] = False
    flags = reprojection_outliers(rms, valid, k=5.0)
    assert np.flatnonzero(flags).tolist() == [7]
    assert not reprojection_outliers(rms[:2], valid[:2], 5.0).any()  # too few views to judge


def test_replaced_view_leaves_its_local_trend():
    target = np.tile(np.arange(20.0) * 2.0, 2)
    groups = np.repeat([0, 1], 20)
    dev = 3.0 * np.sin(target / 5.0) + np.random.default_rng(2).normal(0, 0.3, 40)
    dev[25] += 40.0  # another position's image in the second run
    valid = np.ones(40, bool)
    resid = local_trend_residuals(dev, target, groups, valid)
    assert np.isfinite(resid).all() and abs(resid[25]) > 35
    flags, _ = position_outliers(dev, target, groups, valid, np.full(40, 0.3), k=5.0)
    assert np.flatnonzero(flags).tolist() == [25]
    # the view's own sigma bounds the scale: with 20 um sigmas nothing is flagged
    flags, _ = position_outliers(dev, target, groups, valid, np.full(40, 20.0), k=5.0)
    assert not flags.any()


def test_local_trend_equals_the_median_of_each_views_own_neighbours():
    """The vectorized windows against the definition, view by view, on ragged groups with gaps."""

    rng = np.random.default_rng(0)
    for K in (3, 4, 7, 50, 301):
        dev, target = rng.normal(size=K), rng.permutation(K).astype(float)
        groups, valid = rng.integers(0, 3, K), rng.random(K) > 0.1
        got = local_trend_residuals(dev, target, groups, valid, half_window=3)
        for i in range(K):
            same = np.flatnonzero((groups == groups[i]) & valid)
            same = same[np.argsort(target[same], kind="stable")]
            if not valid[i] or same.size < 3:
                assert np.isnan(got[i])
                continue
            j = int(np.flatnonzero(same == i)[0])
            nb = np.r_[dev[same[max(0, j - 3):j]], dev[same[j + 1:j + 4]]]
            assert got[i] == pytest.approx(dev[i] - np.median(nb), abs=1e-15)
