"""Planar (XY) estimation checked against the simulator's truth and an independent Jacobian."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from lps_gui.core.estimator.estimate import EstimateOptions, estimate
from lps_gui.core.estimator.observations import Observations
from lps_gui.core.metrology.planar_figures import axis_geometry, planar_figures
from lps_gui.core.models.planar_model import planar_truth_in_stage_frame
from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.simulate import (
    nominal_planar_state,
    paper_planar_spec,
    simulate_views,
    small_planar_spec,
)
from lps_gui.core.truth.stage_errors import PlanarErrorModel, StageErrorModel
from lps_gui.errors import DegenerateGeometryError, InputError


def observations(spec, views) -> Observations:
    st = views.stops
    return Observations(spec.rig.board, spec.rig.intrinsics, views.corners_px, [s.target_mm for s in st],
                        [1 if s.direction == "+" else -1 for s in st], [s.run for s in st], [s.index for s in st],
                        source="simulated planar session", approach=[s.approach for s in st])


def true_stage_xy(est, obs, views) -> np.ndarray:
    return planar_truth_in_stage_frame(views.board_plane_mm, obs.target_mm, obs.approach, est.used,
                                       est.reference_view)


def crb_xy_sigma_mm(spec, views) -> np.ndarray:
    """Cramér-Rao bound of every view's (x, y), from cv2.projectPoints' Jacobian at the truth.

    Independent of the estimator's own linearization: the Fisher information
    of the planar model in (rvec, l0, plane tilt, x_i, y_i) for noise sigma.
    """
    rig = spec.rig
    st = nominal_planar_state(rig, views.board_plane_mm - views.board_plane_mm[0])
    st.l0 = st.l0 + st.basis @ views.board_plane_mm[0]
    X = rig.board.object_points()
    rvec, _ = cv2.Rodrigues(st.R)
    K = st.xy.shape[0]
    p = 8 + 2 * (K - 1)
    F = np.zeros((p, p))
    n_z = st.P[:, 2]
    for i in range(K):
        t = st.l0 + st.basis @ st.xy[i]
        _, jac = cv2.projectPoints(X, rvec, t, rig.intrinsics.camera_matrix, rig.intrinsics.dist)
        d_r, d_t = jac[:, 0:3], jac[:, 3:6]
        cols = np.zeros((jac.shape[0], p))
        cols[:, 0:3] = d_r
        cols[:, 3:6] = d_t
        cols[:, 6] = d_t @ (st.xy[i, 1] * n_z)
        cols[:, 7] = d_t @ (-st.xy[i, 0] * n_z)
        if i > 0:
            cols[:, 8 + 2 * (i - 1): 10 + 2 * (i - 1)] = d_t @ st.basis
        F += cols.T @ cols
    cov = np.linalg.inv(F) * spec.noise_px**2
    var = np.diag(cov)[8:].reshape(K - 1, 2)
    return np.sqrt(np.vstack([np.zeros((1, 2)), var]))


def test_paper_planar_positions_reach_the_cramer_rao_bound_and_recover_squareness_and_scale():
    spec = paper_planar_spec(seed=11)  # 15 x 9 grid at 10 mm, 0.1 px, 150 urad, +80 / -50 ppm
    views = simulate_views(spec)
    obs = observations(spec, views)
    est = estimate(obs)
    assert est.converged and not est.outlier.any()
    truth = true_stage_xy(est, obs, views)
    err_um = 1e3 * (est.state.xy - truth)[est.used]
    rms = np.sqrt(np.mean(err_um**2))
    crb_um = 1e3 * np.sqrt(np.mean(crb_xy_sigma_mm(spec, views)[1:] ** 2))
    assert 0.5 < crb_um < 4.0  # about 2 um per coordinate on this rig
    assert rms < 1.3 * crb_um, (rms, crb_um)
    pnp = estimate(obs, EstimateOptions(method="pnp"))  # the baseline: per-view poses, each with its own depth and tilt noise
    rms_pnp = 1e3 * np.sqrt(np.mean((pnp.state.xy - true_stage_xy(pnp, obs, views))[pnp.used] ** 2))
    assert rms_pnp > 1.5 * rms, (rms_pnp, rms)  # measured: 4.3 um against 2.0 um
    # reported sigmas agree with the bound
    assert np.isclose(np.sqrt(np.mean((1e3 * est.sigma_s_mm[1:]) ** 2)), crb_um, rtol=0.15)
    geo = axis_geometry(est.fit.G, est.fit.cov_G)
    # truth of the figures: the same least-squares fit of the true trajectory (ISO 230-1 reference lines)
    true_est = planar_truth_geometry(est, obs, truth)
    assert geo.squareness_sigma_urad < 20.0
    assert abs(geo.squareness_urad - true_est.squareness_urad) < 3 * geo.squareness_sigma_urad
    assert abs(geo.scale_x_ppm - true_est.scale_x_ppm) < 3 * geo.scale_x_sigma_ppm
    assert abs(geo.scale_y_ppm - true_est.scale_y_ppm) < 3 * geo.scale_y_sigma_ppm
    # and the fitted truth is the error model's squareness and scales, up to the straightness it carries
    assert abs(true_est.squareness_urad - 150.0) < 40.0
    assert abs(true_est.scale_x_ppm - 80.0) < 10.0 and abs(true_est.scale_y_ppm + 50.0) < 15.0


def planar_truth_geometry(est, obs, truth_xy):
    from lps_gui.core.models.planar_model import affine_motion

    G = affine_motion(truth_xy, obs.target_mm, obs.approach, est.used)
    return axis_geometry(G, np.zeros((4, 4)))


def test_square_error_model_without_straightness_gives_its_parameters():
    errors = PlanarErrorModel(StageErrorModel(scale_ppm=80.0), StageErrorModel(scale_ppm=-50.0), squareness_urad=150.0)
    spec = small_planar_spec(seed=2, errors=errors, noise_px=0.02)
    views = simulate_views(spec)
    obs = observations(spec, views)
    est = estimate(obs)
    geo = axis_geometry(est.fit.G, est.fit.cov_G)
    for value, truth, sigma in ((geo.squareness_urad, 150.0, geo.squareness_sigma_urad),
                                (geo.scale_x_ppm, 80.0, geo.scale_x_sigma_ppm),
                                (geo.scale_y_ppm, -50.0, geo.scale_y_sigma_ppm)):
        assert abs(value - truth) < 3.5 * sigma, (value, truth, sigma)


def test_planar_scales_carry_the_intrinsics_they_were_measured_with():
    """fx and fy scale the whole grid: an error of one stated sd of fy (500 ppm) moves scale Y by -400 ppm and
    scale X by +160 ppm (the pose's depth follows the mean focal length), far beyond the corners' noise (38 ppm).
    The scales' U (k = 2) must cover it, as a line's total scale sigma does (issue 35)."""
    from dataclasses import replace

    spec = small_planar_spec(seed=2, noise_px=0.01)
    views = simulate_views(spec)
    obs = observations(spec, views)
    sd = np.r_[0.3, 0.3, 0.3, 0.3, 1e-4, 1e-4, 1e-6, 1e-6, 1e-4]  # px for fx, fy, cx, cy
    true_intrinsics = obs.intrinsics
    obs.intrinsics = replace(true_intrinsics.with_vector(true_intrinsics.vector() + np.r_[0.0, sd[1], np.zeros(7)]),
                             covariance=np.diag(sd**2))
    est = estimate(obs)
    geo = axis_geometry(est.fit.G, est.fit.cov_G)
    truth = planar_truth_geometry(est, obs, true_stage_xy(est, obs, views))
    assert abs(geo.scale_y_ppm - truth.scale_y_ppm) > 200.0  # the intrinsics' error is there, not the noise's
    for value, true, sigma in ((geo.scale_x_ppm, truth.scale_x_ppm, geo.scale_x_sigma_ppm),
                               (geo.scale_y_ppm, truth.scale_y_ppm, geo.scale_y_sigma_ppm)):
        assert abs(value - true) < 2.0 * sigma, (value, true, sigma)


def test_planar_sigmas_are_honest_over_monte_carlo_repetitions():
    z2 = []
    sq = []
    for seed in range(12):
        spec = small_planar_spec(seed=100 + seed)
        views = simulate_views(spec)
        obs = observations(spec, views)
        est = estimate(obs, EstimateOptions(detect_outliers=False))
        truth = true_stage_xy(est, obs, views)
        e = (est.state.xy - truth)[1:]
        z2.append(np.mean((e / est.sigma_s_mm[1:]) ** 2))
        geo = axis_geometry(est.fit.G, est.fit.cov_G)
        tg = planar_truth_geometry(est, obs, truth)
        sq.append(((geo.squareness_urad - tg.squareness_urad) / geo.squareness_sigma_urad) ** 2)
    assert 0.5 < np.mean(z2) < 2.0, np.mean(z2)
    assert np.mean(sq) < 2.5, np.mean(sq)


def test_replaced_and_bumped_views_are_flagged_and_the_rest_unchanged():
    base = small_planar_spec(seed=5)
    spec = type(base)(**{**base.__dict__, "replaced_views": (7,), "bumped_views": (15,), "replaced_offset": 5})
    views = simulate_views(spec)
    est = estimate(observations(spec, views))
    assert set(np.flatnonzero(est.outlier)) == {7, 15}
    kinds = {f["index"]: f["kind"] for f in est.flags}
    assert kinds[7] == "position"  # a bumped camera shows as either, depending on the bump's axis
    assert np.all(np.isfinite(est.state.xy[[7, 15]]))  # flagged views still get their own position


def test_collinear_targets_are_refused_with_a_one_line_message():
    spec = small_planar_spec(plan=Plan.xy(start_mm=(0.0, 0.0), stop_mm=(50.0, 0.0), step_mm=(10.0, 10.0)))
    views = simulate_views(spec)
    with pytest.raises(DegenerateGeometryError, match="one line"):
        estimate(observations(spec, views))


def test_hybrid_is_refused_for_planar_sessions():
    spec = small_planar_spec()
    views = simulate_views(spec)
    with pytest.raises(InputError, match="1-D only"):
        estimate(observations(spec, views), EstimateOptions(method="hybrid"))


def test_planar_figures_lines_and_nodes():
    spec = small_planar_spec(seed=4, plan=Plan.xy(start_mm=(0.0, 0.0), stop_mm=(50.0, 30.0), step_mm=(10.0, 10.0),
                                                  directions="both", runs=2))
    views = simulate_views(spec)
    obs = observations(spec, views)
    est = estimate(obs)
    figs = planar_figures(obs.target_mm, obs.approach, obs.run, obs.direction, est.deviation_um(obs.target_mm),
                          1e3 * est.sigma_s_mm, est.used, est.fit.G, est.fit.cov_G)
    assert {ln.axis for ln in figs.lines} == {"X", "Y"}
    assert len([ln for ln in figs.lines if ln.axis == "X"]) == 4  # one per y level
    assert len(figs.nodes) == 24 and all(n["n"] == 4 for n in figs.nodes)
    assert figs.per_axis["X"]["iso230_2"] is not None
    d = figs.to_dict()
    assert d["geometry"]["squareness_sigma_urad"] > 0


def test_planar_self_calibration_frees_the_intrinsics_under_their_prior():
    """The intrinsics selection for D = 2: the 9 intrinsics join the shared parameters with the calibration's
    covariance as prior; the positions' sigma then carries their uncertainty and stays honest."""
    from dataclasses import replace

    spec = small_planar_spec(seed=5)
    views = simulate_views(spec)
    sd = np.r_[2.0, 2.0, 2.0, 2.0, 0.01, 0.01, 1e-4, 1e-4, 0.01]
    obs = observations(spec, views)
    obs.intrinsics = replace(obs.intrinsics, covariance=np.diag(sd**2))
    held = estimate(obs, EstimateOptions())
    free = estimate(obs, EstimateOptions(self_calibrate=True))
    assert free.converged and free.dof == held.dof - 9
    moved = (free.state.intrinsics.vector() - obs.intrinsics.vector()) / sd
    assert 0 < np.max(np.abs(moved)) < 3.0
    truth = true_stage_xy(free, obs, views)
    rest = free.used & (np.arange(obs.K) != free.reference_view)
    z2 = np.mean(((free.state.xy - truth)[rest] / free.sigma_total_mm[rest]) ** 2)
    assert 0.2 < z2 < 3.0, z2
    # the corners inform the intrinsics too: the positions' total sigma is below the prior's propagation alone
    assert np.median(free.sigma_total_mm[1:]) < np.median(held.sigma_total_mm[1:])
    assert np.all(held.sigma_total_mm[1:] >= held.sigma_s_mm[1:])
