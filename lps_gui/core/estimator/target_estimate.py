"""Sessions with targets (SPEC 13) in the one estimator: the target poses are one more selection.

:func:`lps_gui.core.estimator.estimate.estimate` hands observations that name their
targets (``Observations.mounted``) here. The row / constellation model of
:mod:`lps_gui.core.models.target_model` solves the line (D = 1) or the plane (D = 2)
jointly with the mounting poses of every target but the first, and the
solution is returned as the one estimate type (:class:`TargetEstimate`, an
:class:`~lps_gui.core.estimator.estimate_types.LpsEstimate` of D axes), so the results,
figures, budget and report of a single-board session take it as they are. The position covariance stays the
factored block-arrowhead one (:class:`~lps_gui.core.numerics.target_arrowhead.PositionCovariance`):
every linear functional of the positions (scale, steps, the plane's motion
matrix) gets its variance from it with the correlations through the targets.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from lps_gui.core.estimator.board_plane_positions import (
    POSITION_MODEL_BOARD_PLANE,
    PosePositionCovariance,
    row_with_board_plane_positions,
)
from lps_gui.core.estimator.estimate_types import (
    EstimateOptions,
    LpsEstimate,
    Selections,
    planar_fit,
    sigmas_of,
    step_pairs,
)
from lps_gui.core.estimator.observations import Observations
from lps_gui.core.estimator.outlier_round import Solution, judge_views, solve_with_outliers
from lps_gui.core.models.joint_lm import LpsState
from lps_gui.core.models.planar_model import PlanarState
from lps_gui.core.models.target_model import (
    N_COMMON,
    TargetObservations,
    TargetSolution,
    row_parameter_count,
    solve_targets,
)
from lps_gui.core.numerics.outliers import position_outliers
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.errors import InputError


def target_selections(opt: EstimateOptions) -> Selections:
    """What a session with targets frees: the target poses, and the intrinsics when self-calibrating."""
    return Selections(intrinsics=opt.selections().intrinsics, target_poses=True)


@dataclass
class TargetEstimate(LpsEstimate):
    """An estimate against targets (D = 1 or 2): an :class:`LpsEstimate` with the targets' solution beside it,
    whose functionals of the positions take the full covariance through the targets' poses."""

    fit_targets: TargetSolution | None = None

    def functional_covariance(self, L: np.ndarray, with_intrinsics: bool = False) -> np.ndarray:
        """Covariance (mm^2) of m linear functionals of the positions, L shape (m, K) or (m, K, D) -> (m, m)."""
        c = self.fit_targets.covariance
        L = np.asarray(L, dtype=float)
        L = np.where(self.used[None, :, None], L.reshape(L.shape[0], self.used.size, -1), 0.0)
        out = c.covariance(L)
        cov_I = self.state.intrinsics.covariance
        if with_intrinsics and self.intrinsics_gradient is not None and cov_I is not None:
            GL = np.einsum("mka,kai->mi", L, self.intrinsics_gradient.reshape(L.shape[1], L.shape[2], -1))
            out = out + GL @ cov_I @ GL.T
        return out


def check_target_options(opt: EstimateOptions) -> None:
    """InputError for the options a session with targets does not take (yet)."""
    if opt.method != "joint":
        raise InputError(f"method {opt.method!r} is not available for a session with targets (SPEC 13); use joint")
    if opt.robust:
        raise InputError("a session with targets is estimated with the plain loss; drop --robust")


def estimate_with_targets(obs: Observations, opt: EstimateOptions, progress: ProgressFn = no_progress,
                          cancel: CancelToken | None = None) -> TargetEstimate:
    """Positions of every stop and the targets' poses (SPEC 13), as the estimate type of ``obs.D``."""
    check_target_options(opt)
    t0 = time.perf_counter()
    timings: dict[str, float] = {}
    rounds = Solution(None, 0, obs.usable_views(), np.zeros(obs.K, bool), [""] * obs.K)
    prior = opt.intrinsics_prior(obs.intrinsics) if target_selections(opt).intrinsics else None
    if obs.segment is not None and prior is not None:
        raise InputError("--self-calibrate: a stitched capture (one board moved between segments) holds the "
                         "intrinsics; calibrate them first (lps intrinsics) and drop --self-calibrate")

    def solve(r: Solution) -> None:
        corners = np.where(r.used[:, None, None], obs.corners_px, np.nan)  # flagged views leave the solve
        tobs = TargetObservations(list(obs.mounted), corners, obs.targets, list(obs.names))
        if obs.segment is not None:  # one board moved between segments, tied by the overlap (core/estimator/stitching)
            from lps_gui.core.estimator.stitching import stitched_target_solution

            r.state, _ = stitched_target_solution(tobs, obs.segment, obs.intrinsics, obs.repeatability_mm or 0.0,
                                                  progress)
        else:
            r.state = solve_targets(tobs, obs.intrinsics, progress=progress, intrinsics_prior=prior, bows=True)
        r.ref, r.iterations, r.converged = r.state.reference, r.state.iterations, r.state.converged
        if not r.flags:  # the first solve says which views see a target at all
            r.usable = r.state.used.copy()

    solve_with_outliers(rounds, solve, lambda r, round_no: _outlier_round(r, obs, opt.outlier_k, round_no), opt,
                        timings, cancel)
    sol = rounds.state
    common = _common_fields(obs, opt, sol, timings)
    if obs.D == 1 and obs.segment is None and prior is None:  # a row's misfit (angles) is not the corners' noise
        corners = np.where(sol.used[:, None, None], obs.corners_px, np.nan)
        poses = row_with_board_plane_positions(TargetObservations(list(obs.mounted), corners, obs.targets,
                                                                  list(obs.names)), sol, obs.intrinsics, common["dof"])
        if poses is not sol:
            n_obs = common["n_observations"]
            common.update(sigma_px=poses.sigma_px, used=poses.used.copy(), position_model=POSITION_MODEL_BOARD_PLANE,
                          line_model_sigma_px=sol.sigma_px,
                          dof=n_obs - (0 if poses.bows_mm is None else 2 * len(obs.mounted))
                          - 6 * (len(obs.mounted) - 1) - 6 * int(poses.used.sum()))
            sol = poses
    merged = getattr(sol.covariance, "merged", None)  # a stitched solution: its merged views' covariance
    if isinstance(merged, PosePositionCovariance):  # ... of every stop's own pose (core/estimator/stitching.py)
        n_poses = np.unique(sol.covariance.view_of[sol.used]).size
        common.update(position_model=POSITION_MODEL_BOARD_PLANE,
                      dof=common["n_observations"] - 6 * (len(obs.mounted) - 1) - 6 * n_poses)
    common.update(usable=rounds.usable.copy(), outlier=rounds.outlier.copy(), outlier_reason=list(rounds.reasons),
                  flags=rounds.flags)
    est = _line_estimate(obs, sol, common) if obs.D == 1 else _plane_estimate(obs, sol, common)
    timings["total"] = time.perf_counter() - t0
    return est


def _outlier_round(r: Solution, obs: Observations, k: float, round_no: int) -> bool:
    """The one judgement of the used views (:func:`~lps_gui.core.estimator.outlier_round.judge_views`): a bumped camera by
    its RMS; on a line also a replaced image by its position off its run's local trend (the plane's affine
    trend test is its estimator's)."""
    sol = r.state
    rms = sol.rms_px / np.sqrt(2.0)
    groups = obs.run * 2 + (obs.direction > 0)

    def position_test(valid: np.ndarray):
        if obs.D != 1:
            return np.zeros(obs.K, bool), lambda i: ""
        dev = 1e3 * (np.nan_to_num(sol.s[:, 0]) - (obs.target_mm - obs.target_mm[sol.reference]))
        moved, resid = position_outliers(dev, obs.target_mm, groups, valid & sol.used,
                                         1e3 * np.nan_to_num(sol.sigma_s[:, 0]), k)
        return moved, lambda i: f"position {resid[i]:+.1f} um off the local trend of its run (image replaced?)"

    r.usable &= sol.used | r.outlier  # a view that lost its tie when others left is not usable, not an outlier
    return judge_views(r, rms, position_test, obs.index, k, round_no, obs.source)


def _common_fields(obs: Observations, opt: EstimateOptions, sol: TargetSolution, timings: dict) -> dict:
    seen = np.isfinite(obs.corners_px[..., 0]) & sol.used[:, None]
    n_obs = int(2 * seen.sum())
    T = len(obs.mounted)
    n_params = row_parameter_count(T, sol.bows_mm is not None, int(sol.used.sum()), obs.D)
    K = obs.K
    return dict(method=opt.method, reference_view=sol.reference, usable=sol.used.copy(), used=sol.used.copy(),
                outlier=np.zeros(K, bool), outlier_reason=[""] * K, sigma_px=sol.sigma_px,
                rms_px=sol.rms_px / np.sqrt(2.0),  # per coordinate, as every estimate reports it (the fit's is per corner)
                n_corners=seen.sum(axis=1), iterations=sol.iterations, converged=sol.converged,
                n_observations=n_obs, dof=n_obs - n_params, flags=[], timings_s=timings, options=opt)


def _line_estimate(obs: Observations, sol: TargetSolution, common: dict) -> TargetEstimate:
    s = np.where(sol.used, sol.s[:, 0], np.nan)
    sigma = sol.sigma_s[:, 0]
    gradient = None if sol.intrinsics_gradient is None else np.where(sol.used[:, None], sol.intrinsics_gradient[:, 0], 0.0)
    total = sigma if gradient is None else np.sqrt(sigma ** 2 + np.einsum("ki,ij,kj->k", gradient,
                                                                           obs.intrinsics.covariance, gradient))
    sd = np.sqrt(np.maximum(np.diag(sol.covariance.S_inv)[:N_COMMON], 0.0) * sol.covariance.sigma2)
    sigmas = {"rvec_sigma_rad": sd[0:3].tolist(), "l0_sigma_mm": sd[3:6].tolist(), "n_sigma_rad": sd[6:8].tolist()}
    if sol.intrinsics_estimated is not None:  # self-calibrated: their sigmas after the prior and the corners
        sigmas["intrinsics_sigma"] = np.sqrt(np.maximum(
            np.diag(sol.covariance.S_inv)[N_COMMON: N_COMMON + 9], 0.0) * sol.covariance.sigma2).tolist()
    est = TargetEstimate(
        state=LpsState(sol.R, sol.l0, sol.N[:, 0].copy(), s, _intrinsics_of(sol, obs)),
        sigma_s_mm=sigma, sigma_total_mm=total, step_sigma_mm=_step_sigma(obs, sol), intrinsics_gradient=gradient,
        parameter_sigmas=sigmas,
        six_dof=None, fit_targets=sol, **common)
    return est


def _step_sigma(obs: Observations, sol: TargetSolution) -> np.ndarray:
    """Sigma (mm) of each step to the previous capture of its run and direction, from the full covariance."""
    prev, cur = step_pairs(obs.run, obs.direction)
    out = np.full(obs.K, np.nan)
    both = sol.used[prev] & sol.used[cur]
    if both.any():
        g = np.zeros((int(both.sum()), obs.K, 1))
        rows = np.arange(len(g))
        g[rows, prev[both], 0] = -1.0
        g[rows, cur[both], 0] = 1.0
        out[cur[both]] = np.sqrt(np.maximum(sol.covariance.variances(g), 0.0))
    return out


def _plane_estimate(obs: Observations, sol: TargetSolution, common: dict) -> TargetEstimate:
    N = sol.N
    P = np.stack([N[:, 0], N[:, 1], np.cross(N[:, 0], N[:, 1])], axis=1)
    xy = np.where(sol.used[:, None], sol.s, np.nan)
    cov = np.zeros((obs.K, 2, 2))
    for i in np.flatnonzero(sol.used):
        cov[i] = sol.covariance.turn.T @ sol.covariance.cross(i, i) @ sol.covariance.turn
    gradient = sol.intrinsics_gradient
    total = None
    if gradient is not None:
        gradient = np.where(sol.used[:, None, None], gradient, 0.0)
        total = cov + np.einsum("kai,ij,kbj->kab", gradient, obs.intrinsics.covariance, gradient)
    sigma = sigmas_of(cov)
    est = TargetEstimate(state=PlanarState(sol.R, sol.l0, P, xy, _intrinsics_of(sol, obs)), cov_mm2=cov,
                         sigma_s_mm=sigma, sigma_total_mm=sigma if total is None else sigmas_of(total), inverse=None,
                         fit_targets=sol, cov_total_mm2=total, intrinsics_gradient=gradient, **common)
    est.fit = planar_fit(est, obs.target_mm, obs.approach)
    return est


def _intrinsics_of(sol: TargetSolution, obs: Observations):
    """The intrinsics at the solution: self-calibrated, or the given ones."""
    return obs.intrinsics if sol.intrinsics_estimated is None else sol.intrinsics_estimated
