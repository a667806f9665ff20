"""Independent per-view poses as position estimates: Eq. 3 (``pnp``) and Eq. 2 (``calibrate``), D = 1 or 2.

The baselines the LPS model is measured against: every view's pose on its
own; on a line, positions along the PCA line of the camera centres with
sigmas from each view's 6x6 covariance (the reference view's noise
included); on a plane, the translations projected on the initial plane, with
their scatter about the grid's affine trend as sigma.
"""
from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from lps_gui.core.estimator.estimate_types import EstimateOptions, LpsEstimate, planar_fit, sigmas_of, step_pairs
from lps_gui.core.estimator.observations import Observations
from lps_gui.core.geometry.camera_model import CameraIntrinsics, project_board
from lps_gui.core.geometry.pnp import solve_pnp
from lps_gui.core.geometry.rotation import chordal_mean, skew
from lps_gui.core.models.joint_lm import LpsState
from lps_gui.core.models.planar_model import PlanarState, affine_residual_um, align_to_x_motion
from lps_gui.core.models.six_dof import refine_view_poses, six_dof_motion
from lps_gui.core.numerics.uncertainty import noise_variance
from lps_gui.core.progress import CancelToken, ProgressFn


def estimate_per_view(
    obs: Observations,
    opt: EstimateOptions,
    usable: np.ndarray,
    ref: int,
    X: np.ndarray,
    progress: ProgressFn,
    cancel: CancelToken | None,
    timings: dict[str, float],
    t_start: float,
) -> LpsEstimate:
    """Eq. 3 (``pnp``) or Eq. 2 (``calibrate``): independent poses, positions along their PCA line."""
    intr = obs.intrinsics
    idx = np.flatnonzero(usable)
    if opt.method == "calibrate":
        intr = calibrate_all(obs, idx, X)
    R, t, ok = solve_pnp(X, obs.corners_px, intr)
    usable = usable & ok
    mask_all = obs.mask() & usable[:, None]
    if cancel is not None:
        cancel.check("estimation")
    poses = refine_view_poses(R, t, X, obs.corners_px, mask_all, intr)
    C = -np.einsum("kji,kj->ki", poses.R, poses.t)
    Cv = C[usable]
    centre = Cv.mean(axis=0)
    u = np.linalg.svd(Cv - centre, full_matrices=False)[2][0]
    if np.dot((Cv - centre) @ u, obs.target_mm[usable] - obs.target_mm[usable].mean()) < 0:
        u = -u
    s = (C - C[ref]) @ u
    n_obs = int(2 * mask_all.sum())
    n_params = 6 * int(usable.sum())
    sigma2 = noise_variance(float(poses.ssr[usable].sum()), n_obs, n_params)
    Rt = np.transpose(poses.R, (0, 2, 1))
    dC = np.concatenate([-Rt @ skew(poses.t), -Rt], axis=2)  # shape (K, 3, 6)
    ju = np.einsum("i,kib->kb", u, dC)
    var_c = sigma2 * np.einsum("ka,kab,kb->k", ju, poses.cov_unit, ju)
    var_s = var_c + var_c[ref]
    var_s[ref] = 0.0
    var_s[~usable] = np.nan
    R_common = chordal_mean(poses.R[usable])
    l0 = -R_common @ C[ref]
    n = -R_common @ u
    state = LpsState(R_common, l0, n, np.where(usable, s, np.nan), intr)
    rms = np.where(usable, np.sqrt(poses.ssr / np.maximum(2 * mask_all.sum(axis=1), 1)), np.nan)
    six = six_dof_motion(poses, R_common, usable, sigma2) if opt.six_dof else None
    prev, cur = step_pairs(obs.run, obs.direction)
    step_sigma = np.full(obs.K, np.nan)
    step_sigma[cur] = np.sqrt(var_c[prev] + var_c[cur])
    timings["total"] = time.perf_counter() - t_start
    progress(4, 4, "done")
    return LpsEstimate(
        method=opt.method,
        options=opt,
        state=state,
        reference_view=ref,
        usable=usable,
        used=usable.copy(),
        outlier=np.zeros(obs.K, dtype=bool),
        outlier_reason=[""] * obs.K,
        sigma_px=float(np.sqrt(sigma2)),
        sigma_s_mm=np.sqrt(var_s),
        sigma_total_mm=np.sqrt(var_s),
        step_sigma_mm=step_sigma,
        rms_px=rms,
        n_corners=mask_all.sum(axis=1),
        parameter_sigmas={},
        iterations=1,
        converged=True,
        n_observations=n_obs,
        dof=n_obs - n_params,
        six_dof=six,
        flags=[],
        timings_s=timings,
    )


def calibrate_all(obs: Observations, idx: np.ndarray, X: np.ndarray) -> CameraIntrinsics:
    """Eq. 2: cv2.calibrateCamera on every view, started from the given intrinsics."""
    import cv2

    objs, imgs = [], []
    for i in idx:
        seen = np.all(np.isfinite(obs.corners_px[i]), axis=-1)
        objs.append(X[seen].astype(np.float32))
        imgs.append(obs.corners_px[i, seen].astype(np.float32))
    intr = obs.intrinsics
    flags = cv2.CALIB_USE_INTRINSIC_GUESS
    if intr.has_higher:  # the calibrated lens's rational and thin-prism terms stay as calibrated
        flags |= (cv2.CALIB_RATIONAL_MODEL | cv2.CALIB_THIN_PRISM_MODEL | cv2.CALIB_FIX_K4 | cv2.CALIB_FIX_K5
                  | cv2.CALIB_FIX_K6 | cv2.CALIB_FIX_S1_S2_S3_S4)
    _, K, dist, _, _ = cv2.calibrateCamera(
        objs, imgs, intr.image_size, intr.camera_matrix.copy(), intr.cv_dist.copy(), flags=flags
    )
    return replace(intr, camera_matrix=K, dist=dist.ravel()[:5])


def plane_per_view(obs: Observations, opt: EstimateOptions, state: PlanarState, R_v: np.ndarray, t_v: np.ndarray,
                   usable: np.ndarray, ref: int, X: np.ndarray, mask_all: np.ndarray, timings: dict[str, float],
                   t_start: float) -> LpsEstimate:
    """The PnP baseline: every view's own translation projected on the initial plane."""
    K = obs.K
    state = align_to_x_motion(state.regauged(ref), obs.target_mm, obs.approach, usable)
    xy = (t_v - t_v[ref]) @ state.basis
    state.xy = np.where(usable[:, None], xy, np.nan)
    uv = project_board(R_v, t_v, X, obs.intrinsics)
    r = np.where(mask_all[..., None], uv - np.nan_to_num(obs.corners_px), 0.0)
    n = mask_all.sum(axis=1)
    rms = np.sqrt(np.sum(r * r, axis=(1, 2)) / np.maximum(n, 1))
    ssr = float(np.sum(r * r))
    n_obs = int(2 * mask_all.sum())
    sigma2 = noise_variance(ssr, n_obs, 6 * int(usable.sum()))
    spread = np.nanstd(affine_residual_um(np.nan_to_num(state.xy), obs.target_mm, obs.approach, usable)[usable],
                       axis=0) * 1e-3
    cov = np.zeros((K, 2, 2))
    cov[:, 0, 0], cov[:, 1, 1] = spread[0] ** 2, spread[1] ** 2  # the baseline's sigma is its own scatter
    timings["total"] = time.perf_counter() - t_start
    est = LpsEstimate(
        method="pnp", options=opt, state=state, reference_view=ref, usable=usable, used=usable.copy(),
        outlier=np.zeros(K, bool), outlier_reason=[""] * K, sigma_px=float(np.sqrt(sigma2)), sigma_s_mm=sigmas_of(cov),
        sigma_total_mm=sigmas_of(cov), rms_px=rms, n_corners=n, iterations=0, converged=True, n_observations=n_obs,
        dof=n_obs - 6 * int(usable.sum()), flags=[], timings_s=timings, cov_mm2=cov, cov_total_mm2=cov,
    )
    est.fit = planar_fit(est, obs.target_mm, obs.approach)
    return est
