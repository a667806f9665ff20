"""Planar (XY) estimation, the D = 2 solver family of :func:`lps_gui.core.estimate.estimate`.

Steps: per-view PnP -> initial plane (:func:`initial_planar_state`) -> joint
LM (:func:`solve_planar`) inside the shared outlier rounds
(:mod:`lps_gui.core.outlier_round`; the position test here is the robust
affine trend of the grid) -> the frame turned so +x is the fitted X-axis
motion (SPEC 10) -> covariance of every position from the block arrowhead,
with the intrinsics' covariance propagated as for a line. Methods: ``joint``
(this) and ``pnp`` (per-view poses projected on the plane: the baseline).
The paper's hybrid grid search is 1-D by construction.
"""
from __future__ import annotations

import time
from typing import Callable

import numpy as np

from lps_gui.core.arrowhead import ArrowheadInverse, intrinsics_sensitivity
from lps_gui.core.camera_model import project_board
from lps_gui.core.estimate_types import EstimateOptions, LpsEstimate, PlanarFit
from lps_gui.core.observations import Observations
from lps_gui.core.outlier_round import Solution, judge_views, solve_with_outliers
from lps_gui.core.outliers import robust_sigma
from lps_gui.core.planar_model import (
    N_PLANAR_SHARED,
    PlanarEquations,
    PlanarState,
    initial_planar_state,
    linearize_planar,
    planar_positions_only,
    planar_residuals,
    plane_inverse,
    solve_planar,
)
from lps_gui.core.pnp import solve_pnp
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.core.uncertainty import noise_variance
from lps_gui.errors import DegenerateGeometryError


def estimate_plane(obs: Observations, opt: EstimateOptions, progress: ProgressFn = no_progress,
                   cancel: CancelToken | None = None) -> LpsEstimate:
    """D = 2: every (x, y) position and the plane of motion from the observed corners (called by
    :func:`lps_gui.core.estimate.estimate`, which checks the options and the observations)."""
    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    X = obs.board.object_points()
    usable = obs.usable_views()
    mask_all = obs.mask() & usable[:, None]
    progress(0, 4, "per-view poses")
    R_v, t_v, ok = solve_pnp(X, np.where(mask_all[..., None], obs.corners_px, np.nan), obs.intrinsics)
    usable &= ok
    if usable.sum() < 3:
        raise DegenerateGeometryError(f"{obs.source}: only {int(usable.sum())} views give a pose; check the intrinsics")
    ref = int(np.flatnonzero(usable)[0])
    state = initial_planar_state(R_v, t_v, obs.target_mm, usable, ref, obs.intrinsics)
    timings["init"] = time.perf_counter() - t_start
    if opt.method == "pnp":
        return _per_view_result(obs, opt, state, R_v, t_v, usable, ref, X, mask_all, timings, t_start)

    sol = Solution(state, ref, usable, np.zeros(obs.K, dtype=bool), [""] * obs.K)
    prior = opt.intrinsics_prior(obs.intrinsics)
    progress(1, 4, "joint planar solve")

    def solve(sol: Solution) -> None:
        res = solve_planar(sol.state, X, obs.corners_px, mask_all & sol.used[:, None], sol.free(), robust=opt.robust,
                           cancel=cancel, intrinsics_prior=prior)
        sol.state, sol.iterations, sol.converged = res.state, res.iterations, res.converged

    solve_with_outliers(sol, solve, lambda sol, round_no: _outlier_round(sol, obs, X, mask_all, opt.outlier_k, round_no),
                        opt, timings, cancel)
    state, ref, used = sol.state, sol.ref, sol.used
    mask = mask_all & used[:, None]
    free = sol.free()
    others = usable & ~used
    if others.any():
        sub = state.copy()
        sub.xy = state.xy[others]
        state.xy[others] = planar_positions_only(sub, X, obs.corners_px[others], mask_all[others])
    progress(3, 4, "uncertainty")
    state = _regauge(state, ref)
    state, angle = _align_to_x_motion(state, obs.target_mm, obs.approach, used)
    t0 = time.perf_counter()
    inv, sigma2, G_s, n_params = _uncertainty(state, obs, X, mask, free, prior)
    cov = sigma2 * inv.cov_view()
    cov_total = cov
    if G_s is not None:
        cov_total = cov + np.einsum("kai,ij,kbj->kab", G_s, obs.intrinsics.covariance, G_s)
    timings["uncertainty"] = time.perf_counter() - t0
    eq_n_obs = int(2 * mask.sum())
    est = LpsEstimate(
        method=opt.method, options=opt, state=state, reference_view=ref, usable=usable, used=used,
        outlier=sol.outlier, outlier_reason=sol.reasons, sigma_px=float(np.sqrt(sigma2)), sigma_s_mm=_sigmas(cov),
        sigma_total_mm=_sigmas(cov_total), rms_px=_view_rms(state, X, obs.corners_px, mask_all),
        n_corners=mask_all.sum(axis=1), iterations=sol.iterations, converged=sol.converged,
        n_observations=eq_n_obs, dof=eq_n_obs - n_params, flags=sol.flags, timings_s=timings, inverse=inv,
        intrinsics_gradient=G_s, cov_mm2=cov, cov_total_mm2=cov_total,
    )
    est.fit = planar_fit(est, obs.target_mm, obs.approach)
    timings["total"] = time.perf_counter() - t_start
    progress(4, 4, "done")
    return est


def _outlier_round(sol: Solution, obs: Observations, X: np.ndarray, mask_all: np.ndarray, k: float,
                   round_no: int) -> bool:
    """One judgement of the used views (:func:`~lps_gui.core.outlier_round.judge_views`) with the plane's
    position test: a position off the robust affine trend of the grid, against its own sigma."""
    used = sol.used
    mask = mask_all & used[:, None]
    rms = _view_rms(sol.state, X, obs.corners_px, mask_all)
    eq, _ = linearize_planar(sol.state, X, obs.corners_px, mask)
    inv, sigma2 = _inverse(eq, sol.free())
    sig_um = 1e3 * np.sqrt(sigma2 * np.einsum("kii->ki", inv.cov_view()))

    def position_test(valid: np.ndarray) -> tuple[np.ndarray, Callable[[int], str]]:
        resid = _affine_residual_um(sol.state.xy, obs.target_mm, obs.approach, valid)
        scale = np.maximum(np.array([robust_sigma(resid[valid, a]) for a in range(2)])[None, :], sig_um)
        moved = valid & np.any(np.abs(resid) > k * np.maximum(scale, 1e-9), axis=1)
        return moved, lambda i: (f"position ({resid[i, 0]:+.1f}, {resid[i, 1]:+.1f}) um off the trend of the grid "
                                 "(image replaced?)")

    ref = sol.ref
    flagged = judge_views(sol, rms, position_test, obs.index, k, round_no, obs.source)
    if sol.ref != ref:
        sol.state.xy = sol.state.xy - sol.state.xy[sol.ref]
    return flagged


# ----------------------------------------------------------------------------- steps


def _sigmas(cov: np.ndarray) -> np.ndarray:
    """Per-view 1-sigma of x and y (K, 2) from their covariance blocks (K, 2, 2)."""
    return np.sqrt(np.maximum(np.einsum("kii->ki", cov), 0.0))


def _view_rms(state: PlanarState, X: np.ndarray, corners: np.ndarray, mask: np.ndarray) -> np.ndarray:
    r = planar_residuals(state, X, corners, mask)
    n = mask.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n > 0, np.sqrt(np.sum(r * r, axis=(1, 2)) / np.maximum(n, 1)), np.nan)


def _uncertainty(state: PlanarState, obs: Observations, X: np.ndarray, mask: np.ndarray, free: np.ndarray,
                 prior: tuple[np.ndarray, np.ndarray] | None
                 ) -> tuple[ArrowheadInverse, float, np.ndarray | None, int]:
    """H^-1 at the solution, the noise variance, d (x, y) / d intrinsics and the number of unknowns.

    Intrinsics held: their covariance is propagated (when known) through the pose blocks' cross terms;
    intrinsics free (self-calibration): the prior's information joins H and nothing is propagated.
    """
    with_intr = prior is not None or obs.intrinsics.covariance is not None
    eq, _ = linearize_planar(state, X, obs.corners_px, mask, with_intrinsics=with_intr)
    p = N_PLANAR_SHARED
    n_params = p + 2 * int(free.sum())
    if prior is not None:
        A = eq.A.copy()
        A[p:, p:] += np.linalg.inv(prior[1])
        n_params += A.shape[0] - p
        sigma2 = noise_variance(eq.ssr, eq.n_obs, n_params)
        return plane_inverse(A, eq.B, eq.D, free), sigma2, None, n_params
    sigma2 = noise_variance(eq.ssr, eq.n_obs, n_params)
    inv = plane_inverse(eq.A[:p, :p], eq.B[..., :p], eq.D, free)
    G_s = intrinsics_sensitivity(inv, eq.A[:p, p:], eq.B[..., p:]) if with_intr else None
    return inv, sigma2, G_s, n_params


def _inverse(eq: PlanarEquations, free: np.ndarray) -> tuple[ArrowheadInverse, float]:
    """The factored H^-1 of the pose blocks (the intrinsics held) and the a-posteriori noise variance."""
    sigma2 = noise_variance(eq.ssr, eq.n_obs, N_PLANAR_SHARED + 2 * int(free.sum()))
    return plane_inverse(eq.A, eq.B, eq.D, free), sigma2


def _regauge(state: PlanarState, ref: int) -> PlanarState:
    """Zero at the reference view: l0 moves to it, every position shifts."""
    out = state.copy()
    out.l0 = state.l0 + state.basis @ state.xy[ref]
    out.xy = state.xy - state.xy[ref]
    return out


def _design(target_mm: np.ndarray, approach: np.ndarray, used: np.ndarray) -> np.ndarray:
    """Columns: 1, target x, target y, and one backlash offset per axis when both sides occur."""
    cols = [np.ones(target_mm.shape[0]), target_mm[:, 0], target_mm[:, 1]]
    for a in range(2):
        side = approach[:, a] < 0
        if side[used].any() and (~side[used]).any():
            cols.append(side.astype(float))
    return np.column_stack(cols)


def _affine_coefficients(xy: np.ndarray, target_mm: np.ndarray, approach: np.ndarray, used: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares xy = Phi coef; returns (Phi (K, q), coef (q, 2)); one shared design for x and y."""
    Phi = _design(target_mm, approach, used)
    coef, *_ = np.linalg.lstsq(Phi[used], xy[used], rcond=None)
    return Phi, coef


def _affine_residual_um(xy: np.ndarray, target_mm: np.ndarray, approach: np.ndarray, used: np.ndarray) -> np.ndarray:
    Phi, coef = _affine_coefficients(xy, target_mm, approach, used)
    return 1e3 * (xy - Phi @ coef)


def _align_to_x_motion(state: PlanarState, target_mm: np.ndarray, approach: np.ndarray, used: np.ndarray
                       ) -> tuple[PlanarState, float]:
    """Turn the plane coordinates so the fitted +X motion is +x and +Y motion has y > 0 (SPEC 10)."""
    _, coef = _affine_coefficients(state.xy, target_mm, approach, used)
    gx, gy = coef[1], coef[2]  # measured motion per commanded mm of X and of Y
    angle = float(np.arctan2(gx[1], gx[0]))
    out = state.rotated_in_plane(angle)
    if (gx[0] * gy[1] - gx[1] * gy[0]) < 0:  # +Y motion on the -y side: flip y (and n_y) to keep y > 0
        out.P[:, 1] *= -1.0
        out.P[:, 2] *= -1.0
        out.xy[:, 1] *= -1.0
    return out, angle


def planar_fit(est: LpsEstimate, target_mm: np.ndarray, approach: np.ndarray) -> PlanarFit:
    """Affine fit of the measured positions with the covariance of G from the full position covariance."""
    used = est.used
    Phi, coef = _affine_coefficients(est.state.xy, target_mm, approach, used)
    G = coef[1:3].T  # shape (2, 2): G[:, 0] is +X motion, G[:, 1] is +Y motion
    pinv = np.zeros((Phi.shape[1], Phi.shape[0]))
    pinv[:, used] = np.linalg.pinv(Phi[used])
    # coef[j, a] = sum_k pinv[j, k] xy[k, a]; G[a, b] = coef[1 + b, a]
    L = np.zeros((4, est.state.xy.shape[0], 2))
    for a in range(2):
        for b in range(2):
            L[2 * a + b, :, a] = pinv[1 + b]
    cov_G = est.functional_covariance(L)
    resid = 1e3 * (est.state.xy - Phi @ coef)
    resid[~used] = np.nan
    return PlanarFit(G, cov_G, resid)


def _per_view_result(obs: Observations, opt: EstimateOptions, state: PlanarState, R_v: np.ndarray,
                     t_v: np.ndarray, usable: np.ndarray, ref: int, X: np.ndarray, mask_all: np.ndarray,
                     timings: dict[str, float], t_start: float) -> LpsEstimate:
    """The PnP baseline: every view's own translation projected on the initial plane."""
    K = obs.K
    state = _regauge(state, ref)
    state, _ = _align_to_x_motion(state, obs.target_mm, obs.approach, usable)
    xy = (t_v - t_v[ref]) @ state.basis
    state.xy = np.where(usable[:, None], xy, np.nan)
    uv = project_board(R_v, t_v, X, obs.intrinsics)
    r = np.where(mask_all[..., None], uv - np.nan_to_num(obs.corners_px), 0.0)
    n = mask_all.sum(axis=1)
    rms = np.sqrt(np.sum(r * r, axis=(1, 2)) / np.maximum(n, 1))
    ssr = float(np.sum(r * r))
    n_obs = int(2 * mask_all.sum())
    sigma2 = noise_variance(ssr, n_obs, 6 * int(usable.sum()))
    spread = np.nanstd(_affine_residual_um(np.nan_to_num(state.xy), obs.target_mm, obs.approach, usable)[usable],
                       axis=0) * 1e-3
    cov = np.zeros((K, 2, 2))
    cov[:, 0, 0], cov[:, 1, 1] = spread[0] ** 2, spread[1] ** 2  # the baseline's sigma is its own scatter
    timings["total"] = time.perf_counter() - t_start
    est = LpsEstimate(
        method="pnp", options=opt, state=state, reference_view=ref, usable=usable, used=usable.copy(),
        outlier=np.zeros(K, bool), outlier_reason=[""] * K, sigma_px=float(np.sqrt(sigma2)), sigma_s_mm=_sigmas(cov),
        sigma_total_mm=_sigmas(cov), rms_px=rms, n_corners=n, iterations=0, converged=True, n_observations=n_obs,
        dof=n_obs - 6 * int(usable.sum()), flags=[], timings_s=timings, cov_mm2=cov, cov_total_mm2=cov,
    )
    est.fit = planar_fit(est, obs.target_mm, obs.approach)
    return est


def affine_motion(xy: np.ndarray, target_mm: np.ndarray, approach: np.ndarray, used: np.ndarray) -> np.ndarray:
    """G (2x2) of the least-squares fit xy = offset + G target (+ backlash offsets): columns +X, +Y motion."""
    _, coef = _affine_coefficients(xy, target_mm, approach, used)
    return coef[1:3].T


def planar_truth_in_stage_frame(true_xy_mm: np.ndarray, target_mm: np.ndarray, approach: np.ndarray,
                                used: np.ndarray, ref: int) -> np.ndarray:
    """True positions under the estimate's own frame convention (zero at ``ref``, +x along the
    fitted +X motion, +Y motion on the +y side), so they compare with a plane's ``LpsEstimate.positions_mm``."""
    xy = np.asarray(true_xy_mm, dtype=float) - true_xy_mm[ref]
    G = affine_motion(xy, target_mm, approach, used)
    angle = float(np.arctan2(G[1, 0], G[0, 0]))
    c, s = np.cos(angle), np.sin(angle)
    out = xy @ np.array([[c, -s], [s, c]])
    if np.linalg.det(G) < 0:
        out[:, 1] *= -1.0
    return out
