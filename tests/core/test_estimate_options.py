"""Robust loss and self-calibration, against simulator truth."""
from dataclasses import replace

import numpy as np

from lps_gui.core.estimator.estimate import EstimateOptions, estimate
from lps_gui.core.truth.simulate import observations_of, simulate_views, small_spec


def rms_error_um(est, views):
    return 1e3 * float(np.sqrt(np.mean((est.state.s - np.asarray(views.truth["positions_mm"])) ** 2)))


def test_huber_loss_resists_gross_corner_errors():
    spec = small_spec(seed=21, views=25, noise_px=0.1)
    views = simulate_views(spec)
    clean = estimate(observations_of(spec, views), EstimateOptions(six_dof=False, detect_outliers=False))
    rng = np.random.default_rng(0)
    bad = views.corners_px.copy()
    hit = rng.random(bad.shape[:2]) < 0.03  # 3 % of corners mislocated by 5-10 px
    bad[hit] += rng.choice([-1, 1], size=(hit.sum(), 2)) * rng.uniform(5, 10, size=(hit.sum(), 2))
    corrupt = replace(views, corners_px=bad)
    plain = estimate(observations_of(spec, corrupt), EstimateOptions(six_dof=False, detect_outliers=False))
    robust = estimate(observations_of(spec, corrupt), EstimateOptions(robust=True, six_dof=False, detect_outliers=False))
    assert rms_error_um(robust, views) < 1.5 * rms_error_um(clean, views)
    assert rms_error_um(plain, views) > 3 * rms_error_um(robust, views)


def test_self_calibration_stays_within_its_prior_and_truth():
    spec = small_spec(seed=22, views=30, noise_px=0.1)
    views = simulate_views(spec)
    true = spec.rig.intrinsics
    std = np.array([1.0, 1.0, 1.0, 1.0, 2e-3, 5e-3, 1e-4, 1e-4, 1e-2])
    given = replace(true.with_vector(true.vector() + std * np.array([1, -1, 0.5, 0.5, 1, 0, 0, 0, 0])),
                    covariance=np.diag(std**2))
    est = estimate(observations_of(spec, views, given), EstimateOptions(self_calibrate=True, six_dof=False))
    sigma = np.asarray(est.parameter_sigmas["intrinsics_sigma"])
    assert np.all(sigma <= std * 1.0001)  # data can only sharpen the prior
    err = (est.state.s - np.asarray(views.truth["positions_mm"]))[1:]
    assert np.sqrt(np.mean((err / est.sigma_s_mm[1:]) ** 2)) < 2.0
