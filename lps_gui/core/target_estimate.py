"""Sessions with targets (SPEC 13) in the one estimator: the target poses are one more selection.

:func:`lps_gui.core.estimate.estimate` hands observations that name their
targets (``Observations.mounted``) here. The row / constellation model of
:mod:`lps_gui.core.target_model` solves the line (D = 1) or the plane (D = 2)
jointly with the mounting poses of every target but the first, and the
solution is returned as the estimate type of D (:class:`TargetLineEstimate`,
:class:`TargetPlaneEstimate`), so the results, figures, budget and report of
a single-board session take it as they are. The position covariance stays the
factored block-arrowhead one (:class:`~lps_gui.core.target_arrowhead.PositionCovariance`):
every linear functional of the positions (scale, steps, the plane's motion
matrix) gets its variance from it with the correlations through the targets.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from lps_gui.core.estimate_types import EstimateOptions, LpsEstimate, Selections, step_pairs
from lps_gui.core.joint_lm import LpsState
from lps_gui.core.observations import Observations
from lps_gui.core.planar_estimate import PlanarEstimate, planar_fit
from lps_gui.core.planar_model import PlanarState
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.core.target_model import N_COMMON, TargetObservations, TargetSolution, solve_targets
from lps_gui.errors import InputError

SELECTIONS = Selections(intrinsics=False, target_poses=True)  # what a session with targets frees


@dataclass
class TargetLineEstimate(LpsEstimate):
    """A line against a row of targets: an :class:`LpsEstimate` with the targets' solution beside it."""

    fit: TargetSolution | None = None

    def linear_functional_sigma(self, a: np.ndarray) -> tuple[float, float]:
        """Sigma (mm) of sum_i a_i s_i under the full covariance (the targets' poses included), from
        noise alone and with the intrinsics' covariance."""
        a = np.where(self.used, np.asarray(a, dtype=float), 0.0)
        var = max(self.fit.covariance.variance(a[:, None]), 0.0)
        total = var
        cov_i = self.state.intrinsics.covariance
        if self.intrinsics_gradient is not None and cov_i is not None:
            ga = self.intrinsics_gradient.T @ a
            total += float(ga @ cov_i @ ga)
        return float(np.sqrt(var)), float(np.sqrt(total))


@dataclass
class TargetPlaneEstimate(PlanarEstimate):
    """A plane against a constellation: a :class:`PlanarEstimate` with the targets' solution beside it."""

    fit_targets: TargetSolution | None = None

    def functional_covariance(self, L: np.ndarray) -> np.ndarray:
        """Covariance (mm^2) of linear functionals of the positions, L shape (m, K, 2), targets included."""
        c = self.fit_targets.covariance
        gs = np.where(self.used[None, :, None], L, 0.0) @ c.turn.T
        wg = np.einsum("kgp,mkp->mg", c.W, gs)
        return c.sigma2 * (np.einsum("mkp,kpr,nkr->mn", gs, c.A_inv, gs) + wg @ c.S_inv @ wg.T)


def check_target_options(opt: EstimateOptions) -> None:
    """InputError for the options a session with targets does not take (yet)."""
    if opt.method != "joint":
        raise InputError(f"method {opt.method!r} is not available for a session with targets (SPEC 13); use joint")
    if opt.self_calibrate or opt.robust:
        raise InputError("a session with targets is estimated with known intrinsics and the plain loss; "
                         "drop --self-calibrate / --robust")


def estimate_with_targets(obs: Observations, opt: EstimateOptions, progress: ProgressFn = no_progress,
                          cancel: CancelToken | None = None) -> TargetLineEstimate | TargetPlaneEstimate:
    """Positions of every stop and the targets' poses (SPEC 13), as the estimate type of ``obs.D``."""
    check_target_options(opt)
    t0 = time.perf_counter()
    tobs = TargetObservations(list(obs.mounted), obs.corners_px, obs.targets, list(obs.names))
    sol = solve_targets(tobs, obs.intrinsics, progress=progress)
    if cancel is not None:
        cancel.check("estimation")
    timings = {"solve": time.perf_counter() - t0}
    common = _common_fields(obs, opt, sol, timings)
    est = _line_estimate(obs, sol, common) if obs.D == 1 else _plane_estimate(obs, sol, common)
    timings["total"] = time.perf_counter() - t0
    return est


def _common_fields(obs: Observations, opt: EstimateOptions, sol: TargetSolution, timings: dict) -> dict:
    seen = np.isfinite(obs.corners_px[..., 0]) & sol.used[:, None]
    n_obs = int(2 * seen.sum())
    T = len(obs.mounted)
    n_params = N_COMMON + 6 * (T - 1) + obs.D * (int(sol.used.sum()) - 1)
    K = obs.K
    return dict(method=opt.method, reference_view=sol.reference, usable=sol.used.copy(), used=sol.used.copy(),
                outlier=np.zeros(K, bool), outlier_reason=[""] * K, sigma_px=sol.sigma_px,
                rms_px=sol.rms_px / np.sqrt(2.0),  # per coordinate, as every estimate reports it (the fit's is per corner)
                n_corners=seen.sum(axis=1), iterations=sol.iterations, converged=sol.converged,
                n_observations=n_obs, dof=n_obs - n_params, flags=[], timings_s=timings, options=opt)


def _line_estimate(obs: Observations, sol: TargetSolution, common: dict) -> TargetLineEstimate:
    s = np.where(sol.used, sol.s[:, 0], np.nan)
    sigma = sol.sigma_s[:, 0]
    gradient = None if sol.intrinsics_gradient is None else np.where(sol.used[:, None], sol.intrinsics_gradient[:, 0], 0.0)
    total = sigma if gradient is None else np.sqrt(sigma ** 2 + np.einsum("ki,ij,kj->k", gradient,
                                                                           obs.intrinsics.covariance, gradient))
    sd = np.sqrt(np.maximum(np.diag(sol.covariance.S_inv)[:N_COMMON], 0.0) * sol.covariance.sigma2)
    est = TargetLineEstimate(
        state=LpsState(sol.R, sol.l0, sol.N[:, 0].copy(), s, obs.intrinsics),
        sigma_s_mm=sigma, sigma_total_mm=total, step_sigma_mm=_step_sigma(obs, sol), intrinsics_gradient=gradient,
        parameter_sigmas={"rvec_sigma_rad": sd[0:3].tolist(), "l0_sigma_mm": sd[3:6].tolist(),
                          "n_sigma_rad": sd[6:8].tolist()},
        six_dof=None, fit=sol, **common)
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


def _plane_estimate(obs: Observations, sol: TargetSolution, common: dict) -> TargetPlaneEstimate:
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
    est = TargetPlaneEstimate(state=PlanarState(sol.R, sol.l0, P, xy, obs.intrinsics), cov_xy_mm2=cov,
                              inverse=None, fit_targets=sol, cov_xy_total_mm2=total, intrinsics_gradient=gradient,
                              **common)
    est.fit = planar_fit(est, obs.target_mm, obs.approach)
    return est
