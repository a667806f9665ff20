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


def _theil_sen_residual(d: np.ndarray, t: np.ndarray, i: int, nb: np.ndarray) -> float:
    """The definition, one view at a time: d minus the Theil-Sen line of its neighbours at its target."""
    slopes = [(d[b] - d[a]) / (t[b] - t[a]) for k, a in enumerate(nb) for b in nb[k + 1:] if t[b] != t[a]]
    slope = float(np.median(slopes)) if slopes else 0.0
    return float(d[i] - np.median(d[nb] - slope * (t[nb] - t[i])))


def test_local_trend_is_the_theil_sen_line_of_each_views_own_neighbours():
    """The vectorized windows against the definition, view by view, on ragged groups with gaps: the 6 views
    nearest in target order (the window slides inward at a run's ends), self excluded."""
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
            width = min(7, same.size)
            lo = min(max(j - 3, 0), same.size - width)
            nb = np.array([v for v in same[lo:lo + width] if v != i])
            assert got[i] == pytest.approx(_theil_sen_residual(dev, target, i, nb), abs=1e-12)


@pytest.mark.parametrize("scale", [0.05, -0.07, 0.10])
def test_a_wrong_steps_per_mm_is_a_trend_not_outliers(scale):
    """A stage with a 5-10 % scale error (wrong steps/mm) deviates along a line: no view leaves the local trend,
    not even at a run's ends (the old median of one-sided neighbours flagged them, round after round)."""
    rng = np.random.default_rng(3)
    target = np.tile(np.arange(60.0) * 2.0, 2)
    groups = np.repeat([0, 1], 60)
    dev = 1e3 * scale * target + 2.0 * np.sin(target / 4.0) + rng.normal(0, 0.5, target.size)
    valid = np.ones(target.size, bool)
    flags, resid = position_outliers(dev, target, groups, valid, np.full(target.size, 0.5), k=5.0)
    assert not flags.any(), np.abs(resid).max()
    dev[70] += 1e3 * scale * 6.0  # but another position's image (3 targets away) is still caught
    flags, _ = position_outliers(dev, target, groups, valid, np.full(target.size, 0.5), k=5.0)
    assert np.flatnonzero(flags).tolist() == [70]


def test_repeated_frames_at_one_target_take_a_constant_trend():
    """Neighbours all at one target (frames_per_stop > 1) have no slope: their median is the trend."""
    target = np.repeat([0.0, 1.0], 8)
    dev = np.r_[np.zeros(8), np.full(8, 5.0)]
    dev[3] = 40.0
    resid = local_trend_residuals(dev, target, np.zeros(16, int), np.ones(16, bool))
    assert resid[3] == pytest.approx(40.0) and np.isfinite(resid).all()


def test_an_rms_at_the_end_of_a_smooth_slope_is_not_a_bumped_camera():
    """The live estimate's newest view once read as bumped: 0.047 px at the end of a slope of RMS (the stage's motion
    the constant-orientation model does not quite express), against a median of 0.031 px over all 14 views."""
    from lps_gui.core.numerics.outliers import reprojection_outliers

    rms = np.array([0.0283, 0.0282, 0.0297, 0.0303, 0.0298, 0.0308, 0.0312, 0.0316, 0.0325, 0.0333, 0.1852, 0.0404,
                    0.0395, 0.0466])
    valid = np.ones(rms.size, bool)
    assert np.flatnonzero(reprojection_outliers(rms, valid, 5.0)).tolist() == [10]  # the jolted view, and only it
    spike = rms.copy()
    spike[13] = 0.09  # a camera bumped at the newest view is still caught
    assert np.flatnonzero(reprojection_outliers(spike, valid, 5.0)).tolist() == [10, 13]
