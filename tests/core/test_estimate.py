"""Estimation validated against simulator truth (never against itself).

Tolerances come from the noise: the Cramér-Rao bound computed from the same
Jacobian at the truth, and z-scores over Monte-Carlo repetitions.
"""
from dataclasses import replace

import cv2
import numpy as np
import pytest

from lps_gui.core.estimator.estimate import EstimateOptions, estimate
from lps_gui.core.models.joint_lm import LpsState
from lps_gui.core.truth.simulate import observations_of, paper_rig_spec, simulate_views, small_spec
from lps_gui.core.truth.stage_errors import StageErrorModel

AXIAL_ERRORS = StageErrorModel(scale_ppm=25.0, periodic_um=4.0, pitch_mm=5.0, backlash_um=6.0, repeatability_um=1.0)


def true_s(views):
    return np.asarray(views.truth["positions_mm"])


def crb_positions_mm(spec, views, sigma_px):
    """Cramér-Rao bound of every position: sigma^2 (J^T J)^-1 at the true parameters.

    J is built independently of the estimator: per view from cv2.projectPoints'
    own Jacobian (d uv / d rvec, d uv / d tvec) at t_i = l0 + s_i n, chained to
    the model's parameters (rvec of the common R, l0, the two tangent
    directions of n, and s_i with the gauge s_0 = 0); H is assembled and
    inverted densely. Reparametrizing the rotation does not change the bound
    on s, so the estimator's left-perturbed rotation must give the same numbers.
    """
    rig = spec.rig
    intr = rig.intrinsics
    R = rig.R_cam_board
    rvec = cv2.Rodrigues(R)[0]
    n = -R @ rig.u_board
    s = true_s(views)
    l0 = views.t_cam_board[0]
    helper = np.eye(3)[int(np.argmin(np.abs(n)))]
    b1 = np.cross(n, helper)
    b1 /= np.linalg.norm(b1)
    basis = np.stack([b1, np.cross(n, b1)], axis=1)  # any orthonormal tangent basis of n
    X = rig.board.object_points()
    K, p = len(s), 8
    H = np.zeros((p + K, p + K))
    for k in range(K):
        seen = np.all(np.isfinite(views.corners_px[k]), axis=-1)
        _, jac = cv2.projectPoints(X[seen], rvec, l0 + s[k] * n, intr.camera_matrix, intr.dist)
        d_r, d_t = jac[:, 0:3], jac[:, 3:6]  # rows alternate u, v of each point
        J = np.zeros((jac.shape[0], p + K))
        J[:, 0:3] = d_r
        J[:, 3:6] = d_t
        J[:, 6:8] = s[k] * d_t @ basis
        J[:, p + k] = d_t @ n
        H += J.T @ J
    keep = np.r_[np.ones(p, bool), np.arange(K) != 0]  # the gauge: s_0 is fixed
    var = np.zeros(K)
    var[1:] = np.diag(np.linalg.inv(H[np.ix_(keep, keep)]))[p:]
    return sigma_px * np.sqrt(var)


@pytest.fixture(scope="module")
def paper_case():
    spec = paper_rig_spec(seed=3, noise_px=0.1, errors=AXIAL_ERRORS)
    views = simulate_views(spec)
    return spec, views, crb_positions_mm(spec, views, 0.1)


def rms(x):
    return float(np.sqrt(np.mean(np.square(x))))


def test_joint_lm_reaches_the_cramer_rao_bound_on_the_paper_rig(paper_case):
    spec, views, crb = paper_case
    assert views.corners_px.shape == (400, 540, 2)
    est = estimate(observations_of(spec, views), EstimateOptions(method="joint", six_dof=False))
    err = est.state.s - true_s(views)
    assert rms(err[1:]) <= 1.2 * rms(crb[1:])
    assert abs(est.sigma_px - 0.1) < 0.005  # the a-posteriori noise is the simulated one
    assert est.outlier.sum() == 0


def test_reported_sigmas_equal_the_independent_cramer_rao_bound(paper_case):
    """The estimator's own covariance (its linearize + arrowhead inverse) against the bound from cv2's Jacobian."""
    spec, views, crb = paper_case
    est = estimate(observations_of(spec, views), EstimateOptions(method="joint", six_dof=False))
    # same noise level (the a-posteriori one); linearized at the estimate, not at the truth (1.4e-6 apart when run)
    assert np.allclose(est.sigma_s_mm[1:], crb[1:] * est.sigma_px / 0.1, rtol=1e-4)
    assert est.sigma_s_mm[0] == 0.0


def test_pnp_baseline_is_far_worse_than_the_joint_model(paper_case):
    spec, views, crb = paper_case
    est = estimate(observations_of(spec, views), EstimateOptions(method="pnp", six_dof=False))
    assert rms(est.state.s - true_s(views)) > 10 * rms(crb[1:])


@pytest.mark.slow
def test_hybrid_within_twice_the_bound_on_the_paper_rig(paper_case):
    spec, views, crb = paper_case
    est = estimate(observations_of(spec, views), EstimateOptions(method="hybrid", six_dof=False))
    assert rms((est.state.s - true_s(views))[1:]) <= 2.0 * rms(crb[1:])


def test_hybrid_within_twice_the_bound_on_a_short_paper_run():
    spec = paper_rig_spec(seed=5, noise_px=0.1, errors=AXIAL_ERRORS)
    spec = replace(spec, plan=replace(spec.plan, stop_mm=59.0))
    views = simulate_views(spec)
    crb = crb_positions_mm(spec, views, 0.1)
    est = estimate(observations_of(spec, views), EstimateOptions(method="hybrid", six_dof=False))
    assert rms((est.state.s - true_s(views))[1:]) <= 2.0 * rms(crb[1:])


@pytest.mark.parametrize("resolution_mm", [1e-2, 1e-4])
def test_grid_search_finds_each_position_to_its_resolution(resolution_mm):
    from lps_gui.core.models.hybrid import grid_search_positions

    spec = replace(small_spec(seed=2, views=15), noise_px=0.0)
    views = simulate_views(spec)
    rig = spec.rig
    truth = true_s(views)
    start = truth + np.random.default_rng(0).uniform(-0.3, 0.3, truth.size)
    state = LpsState(rig.R_cam_board, views.t_cam_board[0], -rig.R_cam_board @ rig.u_board, start, rig.intrinsics)
    mask = np.all(np.isfinite(views.corners_px), axis=-1)
    found = grid_search_positions(state, rig.board.object_points(), views.corners_px, mask, np.ones(truth.size, bool),
                                  window_mm=0.5, resolution_mm=resolution_mm, grid_points=21)
    assert np.max(np.abs(found - truth)) <= resolution_mm


def test_reported_sigmas_are_honest_over_monte_carlo():
    z = []
    for seed in range(50):
        spec = small_spec(seed=100 + seed, views=20, noise_px=0.2)
        views = simulate_views(spec)
        est = estimate(observations_of(spec, views), EstimateOptions(six_dof=False, detect_outliers=False))
        err = est.state.s - true_s(views)
        z.extend(err[1:] / est.sigma_s_mm[1:])
    ms = float(np.mean(np.square(z)))
    assert 0.7 <= ms <= 1.4, ms


def test_total_sigma_includes_intrinsics_uncertainty():
    spec = small_spec(seed=4)
    views = simulate_views(spec)
    std = np.array([0.5, 0.5, 0.5, 0.5, 2e-3, 5e-3, 1e-4, 1e-4, 1e-2])
    intr = replace(spec.rig.intrinsics, covariance=np.diag(std**2))
    est = estimate(observations_of(spec, views, intr), EstimateOptions(six_dof=False))
    assert np.all(est.sigma_total_mm[1:] > est.sigma_s_mm[1:])
    # a focal-length error is (almost) a scale error: it dominates far from the reference
    assert est.sigma_total_mm[-1] - est.sigma_s_mm[-1] > est.sigma_total_mm[1] - est.sigma_s_mm[1]


def test_replaced_and_bumped_views_are_flagged_and_others_unaffected():
    spec = replace(small_spec(seed=11, views=40, noise_px=0.1), replaced_views=(7, 22), bumped_views=(15,))
    views = simulate_views(spec)
    obs = observations_of(spec, views)
    est = estimate(obs, EstimateOptions(six_dof=False))
    assert sorted(np.flatnonzero(est.outlier)) == [7, 15, 22]
    kinds = {f["index"]: f["kind"] for f in est.flags}
    assert kinds[15] == "reprojection" and kinds[7] == "position" and kinds[22] == "position"
    # the other positions equal those of a solve that never saw the three views
    clean = obs.corners_px.copy()
    clean[[7, 15, 22]] = np.nan
    ref = estimate(replace(obs, corners_px=clean), EstimateOptions(six_dof=False, detect_outliers=False))
    keep = np.setdiff1d(np.arange(obs.K), [7, 15, 22])
    assert np.allclose(est.state.s[keep], ref.state.s[keep], atol=1e-9)
    # the flagged replaced view is reported where its image says: far from its target
    assert abs(est.deviation_um(obs.target_mm)[7]) > 1000


@pytest.mark.parametrize("scale_ppm", [1e5, -5e4])
def test_a_wrong_steps_per_mm_is_measured_with_every_good_view_kept(scale_ppm):
    """A 5-10 % scale error (a misconfigured steps/mm) is a smooth trend, not replaced images: every good view
    is kept and the scale comes out as simulated; a truly replaced image is still flagged (issue 35)."""
    errors = StageErrorModel(scale_ppm=scale_ppm, periodic_um=5.0, pitch_mm=8.0, repeatability_um=1.0)
    spec = replace(small_spec(seed=4, views=30, noise_px=0.2, directions="both", errors=errors), replaced_views=(40,))
    views = simulate_views(spec)
    obs = observations_of(spec, views)
    est = estimate(obs, EstimateOptions(six_dof=False))
    assert np.flatnonzero(est.outlier).tolist() == [40]
    keep = ~est.outlier
    slope = np.polyfit(obs.target_mm[keep], est.state.s[keep], 1)[0]
    true_slope = np.polyfit(obs.target_mm[keep], true_s(views)[keep], 1)[0]
    assert abs(true_slope - 1.0 - 1e-6 * scale_ppm) < 1e-3
    assert abs(slope - true_slope) < 1e-3  # 1000 ppm of a 100000 ppm error; the estimate's sigma is ~300 ppm


def test_six_dof_recovers_straightness_and_angles_with_honest_sigmas():
    from lps_gui.core.truth.stage_errors import ErrorProfile

    errors = replace(
        AXIAL_ERRORS,
        straightness_um=(ErrorProfile(poly=(0.0, 0.0, -2e5)), ErrorProfile(amplitude=150.0, period_mm=40.0)),
        roll_urad=ErrorProfile(amplitude=300.0, period_mm=50.0),
        pitch_urad=ErrorProfile(poly=(0.0, 5000.0)),
        yaw_urad=ErrorProfile(amplitude=200.0, period_mm=30.0),
    )
    spec = paper_rig_spec(seed=1, noise_px=0.1, errors=errors)
    spec = replace(spec, plan=replace(spec.plan, stop_mm=59.0))
    views = simulate_views(spec)
    six = estimate(observations_of(spec, views)).six_dof
    target = np.array([s.target_mm for s in views.stops])
    A = np.c_[np.ones_like(target), target]
    straight = np.asarray(views.truth["straightness_um"])
    straight = straight - A @ np.linalg.lstsq(A, straight, rcond=None)[0]  # ours is relative to a LS line
    angles = np.asarray(views.truth["angles_urad"])
    err = np.c_[six.straightness_um - straight, (six.angles_urad - six.angles_urad.mean(0)) - (angles - angles.mean(0))]
    sigma = np.c_[six.straightness_sigma_um, six.angles_sigma_urad]
    truth = np.c_[straight, angles]
    z2 = np.mean((err / sigma) ** 2, axis=0)
    assert np.all((z2 > 0.5) & (z2 < 2.0)), z2
    assert np.all(np.sqrt(np.mean(err**2, axis=0)) < 0.5 * np.ptp(truth, axis=0))
