"""From corners to positions with error bars: one estimator for a stage of D = 1 or 2 axes.

:func:`estimate` takes :class:`~lps_gui.core.estimator.observations.Observations` with
targets of shape (K, D) and :class:`EstimateOptions` (whose
:meth:`~EstimateOptions.selections` name the free parameter groups), checks
the method against D and runs the solver family of D (:data:`SOLVERS`): the
line of SPEC 4 (:mod:`lps_gui.core.models.joint_lm`, one unknown per view) and the
plane of SPEC 10 (:mod:`lps_gui.core.models.planar_model`, two), both here. Both
share the outlier rounds (:mod:`lps_gui.core.estimator.outlier_round`), the block
arrowhead (:mod:`lps_gui.core.numerics.arrowhead`) and one result type.

Line methods: ``joint`` (default, SPEC 4.4), ``hybrid`` (the paper, SPEC 4.3),
``pnp`` (per-view baseline, Eq. 3) and ``calibrate`` (Eq. 2, intrinsics and
all poses free: reference only). Every method reports positions relative to
the first usable capture, per-position sigma from noise alone and total sigma
including the intrinsics covariance, outlier views (flagged, excluded from
the solve, their own position still reported), and 6-DOF error motions.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from lps_gui.core.estimator.board_plane_positions import with_board_plane_positions
from lps_gui.core.estimator.estimate_types import (
    METHODS,
    EstimateOptions,
    LpsEstimate,
    planar_fit,
    sigmas_of,
    step_pairs,
)
from lps_gui.core.estimator.methods import BY_NAME
from lps_gui.core.estimator.observations import Observations
from lps_gui.core.estimator.outlier_round import Solution, judge_views, solve_with_outliers
from lps_gui.core.estimator.per_view import estimate_per_view, plane_per_view
from lps_gui.core.estimator.target_estimate import estimate_with_targets
from lps_gui.core.geometry.camera_model import INTRINSIC_NAMES
from lps_gui.core.geometry.pnp import solve_pnp
from lps_gui.core.models.constant_orientation import board_plane_from_model
from lps_gui.core.models.hybrid import initial_line, solve_hybrid, view_costs
from lps_gui.core.models.joint_lm import (
    N_POSE_PARAMS,
    LmOptions,
    LpsState,
    NormalEquations,
    line_inverse,
    linearize,
    linearize_poses,
    solve_joint,
    solve_positions_only,
)
from lps_gui.core.models.planar_model import (
    N_PLANAR_SHARED,
    PlanarState,
    affine_residual_um,
    align_to_x_motion,
    initial_planar_state,
    linearize_planar,
    planar_positions_only,
    planar_residuals,
    plane_inverse,
    solve_planar,
)
from lps_gui.core.models.six_dof import SixDof, refine_view_poses, six_dof_motion
from lps_gui.core.numerics.arrowhead import ArrowheadInverse, intrinsics_sensitivity
from lps_gui.core.numerics.outliers import position_outliers, robust_sigma
from lps_gui.core.numerics.pose_normals import PoseNormals
from lps_gui.core.numerics.uncertainty import noise_variance, propagated_variance
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.errors import DegenerateGeometryError, InputError

__all__ = ["METHODS", "EstimateOptions", "LpsEstimate", "estimate"]

INIT_VIEWS = 24  # per-view PnP on this many spread views initializes the joint LM
N_INTRINSICS = len(INTRINSIC_NAMES)  # 9, after the pose parameters when self-calibrating


def estimate(
    obs: Observations,
    options: EstimateOptions | None = None,
    progress: ProgressFn = no_progress,
    cancel: CancelToken | None = None,
    *,
    warm_start: LpsState | None = None,
) -> LpsEstimate:
    """Estimate the stage model of ``obs.D`` axes and every position from the observed corners.

    One problem for D = 1 (a line, SPEC 4) and D = 2 (a plane, SPEC 10): the
    same options, selections, outlier rounds and covariance of the block
    arrowhead; the solver family is chosen by D (:data:`SOLVERS`).
    ``warm_start``: the state of an estimate of the first views of ``obs``
    (a live capture's last one), the start of the joint LM instead of the
    per-view PnP initialization; the new views start at their targets.
    """
    opt = options or EstimateOptions()
    opt.check_axes(obs.D)
    obs.validate()
    if obs.mounted is not None:  # a row or constellation (SPEC 13): the target poses are one more selection
        if warm_start is not None:
            raise InputError("a warm start continues a joint estimate of one board on one axis; a target session has none")
        return estimate_with_targets(obs, opt, progress, cancel)
    if warm_start is not None:
        if obs.D != 1 or opt.method != "joint":
            raise InputError("a warm start continues a joint estimate of one axis (the running estimate of a live capture)")
        return _estimate_line(obs, opt, progress, cancel, warm_start)
    return SOLVERS[obs.D](obs, opt, progress, cancel)


def _estimate_line(obs: Observations, opt: EstimateOptions, progress: ProgressFn, cancel: CancelToken | None,
                   warm_start: LpsState | None = None) -> LpsEstimate:
    """D = 1: Eq. 5 initialization, the joint LM or the hybrid, the line's covariances and 6-DOF motions."""
    timings: dict[str, float] = {}
    t_start = time.perf_counter()
    X = obs.board.object_points()
    usable = obs.usable_views()
    mask_all = obs.mask() & usable[:, None]
    ref = int(np.flatnonzero(usable)[0])
    progress(0, 4, "initializing")

    if BY_NAME[opt.method].per_view:
        return estimate_per_view(obs, opt, usable, ref, X, progress, cancel, timings, t_start)

    state = (_initial_state(obs, usable, ref, X, full_pnp=opt.method == "hybrid") if warm_start is None
             else _warm_state(obs, warm_start, ref))
    timings["init"] = time.perf_counter() - t_start
    sol = Solution(state, ref, usable, np.zeros(obs.K, dtype=bool), [""] * obs.K)

    def solve(sol: Solution) -> None:
        sol.state, sol.iterations, sol.converged, sol.equations = _solve(
            sol.state, obs, X, mask_all & sol.used[:, None], sol.used, sol.ref, opt, progress, cancel)

    solve_with_outliers(sol, solve, lambda sol, round_no: _outlier_round(sol, obs, X, mask_all, opt.outlier_k, round_no),
                        opt, timings, cancel)

    others = usable & ~sol.used
    if others.any():
        sol.state.s[others] = _positions_alone(sol.state, X, obs.corners_px, mask_all, others)
    sol.state = sol.state.regauged(sol.ref)
    progress(3, 4, "uncertainty")
    est = _finish(obs, opt, sol, X, mask_all, timings)
    timings["total"] = time.perf_counter() - t_start
    progress(4, 4, "done")
    return est


# ----------------------------------------------------------------------------- steps

def _spread_views(usable: np.ndarray, target_mm: np.ndarray, n: int) -> np.ndarray:
    """Up to n usable views spread evenly over the targets (always both ends)."""
    idx = np.flatnonzero(usable)
    if idx.size <= n:
        return idx
    order = idx[np.argsort(target_mm[idx], kind="stable")]
    return np.unique(order[np.linspace(0, order.size - 1, n).round().astype(int)])


def _initial_state(obs: Observations, usable: np.ndarray, ref: int, X: np.ndarray, full_pnp: bool) -> LpsState:
    """Eq. 5 initialization: per-view PnP (on all views for hybrid, on a spread subset for joint)."""
    views = np.flatnonzero(usable) if full_pnp else _spread_views(usable, obs.target_mm, INIT_VIEWS)
    R, t, ok = solve_pnp(X, obs.corners_px[views], obs.intrinsics)
    views, R, t = views[ok], R[ok], t[ok]
    if views.size < 2 or np.ptp(obs.target_mm[views]) <= 0:
        raise DegenerateGeometryError(
            f"{obs.source}: the board's pose could be found in {views.size} views only; check intrinsics and board size"
        )
    init = initial_line(R, t, obs.target_mm[views], obs.intrinsics)
    s_all = obs.target_mm - obs.target_mm[ref]
    l0 = np.mean(t - s_all[views, None] * init.n[None, :], axis=0)
    return LpsState(init.R, l0, init.n, s_all.astype(float), obs.intrinsics)


def _warm_state(obs: Observations, warm: LpsState, ref: int) -> LpsState:
    """The previous solution of the first views, regauged to ``ref``; the views added since at their targets."""
    s_all = (obs.target_mm - obs.target_mm[ref]).astype(float)
    known = min(len(warm.s), obs.K)
    shift = float(warm.s[ref]) if ref < known else 0.0
    s_all[:known] = warm.s[:known] - shift
    return LpsState(warm.R, warm.l0 + shift * warm.n, warm.n, s_all, obs.intrinsics)


def _solve(
    state: LpsState,
    obs: Observations,
    X: np.ndarray,
    mask: np.ndarray,
    used: np.ndarray,
    ref: int,
    opt: EstimateOptions,
    progress: ProgressFn,
    cancel: CancelToken | None,
) -> tuple[LpsState, int, bool, NormalEquations | None]:
    free = used.copy()
    free[ref] = False
    if opt.method == "hybrid":
        res = solve_hybrid(state, X, obs.corners_px, mask, used, opt.hybrid, progress, cancel)
        return res.state.regauged(ref), res.rounds, res.converged, None
    prior = opt.intrinsics_prior(obs.intrinsics)
    lm = solve_joint(
        state,
        X,
        obs.corners_px,
        mask,
        free,
        LmOptions(robust=opt.robust, estimate_intrinsics=opt.self_calibrate),
        cancel,
        intrinsics_prior=prior,
    )
    progress(2, 4, f"joint LM: {lm.iterations} iterations")
    plain = not opt.robust and not opt.self_calibrate  # then lm.equations are the plain pose blocks the outlier round needs
    return lm.state, lm.iterations, lm.converged, lm.equations if plain else None


def _positions_alone(state: LpsState, X: np.ndarray, corners: np.ndarray, mask: np.ndarray, views: np.ndarray) -> np.ndarray:
    """Each selected view's own best position with the shared parameters fixed."""
    idx = np.flatnonzero(views)
    return solve_positions_only(_views_of(state, idx), X, corners[idx], mask[idx])


def views_against(state: LpsState, obs: Observations, views: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(position s, reprojection RMS px) of each of ``views`` (indices into ``obs``) with the line and rotation of
    ``state`` held: O(views), a live capture's test of its new frames against the solution so far."""
    idx = np.asarray(views, int)
    X = obs.board.object_points()
    mask = obs.mask()
    sel = np.zeros(obs.K, bool)
    sel[idx] = True
    sel &= mask.any(axis=1)
    s = np.full(obs.K, np.nan)
    s[idx] = (obs.target_mm[idx] - obs.target_mm[0]).astype(float)
    if sel.any():
        start = LpsState(state.R, state.l0, state.n, np.nan_to_num(s), state.intrinsics)
        s[sel] = _positions_alone(start, X, obs.corners_px, mask, sel)
    rms = _view_rms(LpsState(state.R, state.l0, state.n, np.nan_to_num(s), state.intrinsics), X, obs.corners_px,
                    mask & sel[:, None], np.zeros(obs.K), np.zeros(obs.K, bool))
    return s[idx], rms[idx]


def _views_of(state: LpsState, idx: np.ndarray) -> LpsState:
    """The same line and rotation with only the positions of views ``idx``."""
    return LpsState(state.R, state.l0, state.n, state.s[idx].copy(), state.intrinsics)


def _view_rms(state: LpsState, X: np.ndarray, corners: np.ndarray, mask: np.ndarray, known_ssr: np.ndarray,
              known: np.ndarray) -> np.ndarray:
    """Each view's reprojection RMS (px): ``known_ssr`` of the ``known`` views comes from a pass already made,
    the other views with corners are projected here."""
    n = mask.sum(axis=1)
    cost = np.where(known, known_ssr, 0.0)
    rest = np.flatnonzero(~known & (n > 0))
    if rest.size:
        cost[rest] = view_costs(_views_of(state, rest), X, corners[rest], mask[rest])
    return np.where(n > 0, np.sqrt(cost / np.maximum(2 * n, 1)), np.nan)


def _outlier_round(sol: Solution, obs: Observations, X: np.ndarray, mask_all: np.ndarray, k: float, round_no: int) -> bool:
    """One judgement of the used views (:func:`~lps_gui.core.estimator.outlier_round.judge_views`) with the line's
    position test: a position off its run's local trend, judged against each position's own sigma."""
    used = sol.used
    mask = mask_all & used[:, None]
    eq = sol.equations  # the LM's last pass, when it was the plain one at this state
    if eq is None:
        eq, _ = linearize(sol.state, X, obs.corners_px, mask, want_residuals=False)
    rms = _view_rms(sol.state, X, obs.corners_px, mask_all, eq.view_ssr, used)
    sigma2 = noise_variance(eq.ssr, eq.n_obs, N_POSE_PARAMS + int(used.sum()) - 1)
    inv = line_inverse(eq.A, eq.B, eq.D, sol.free())
    sigma_um = 1e3 * np.sqrt(sigma2 * inv.variances()[:, 0])
    dev = 1e3 * (sol.state.s - (obs.target_mm - obs.target_mm[sol.ref]))
    groups = obs.run * 2 + (obs.direction > 0)

    def position_test(valid: np.ndarray) -> tuple[np.ndarray, Callable[[int], str]]:
        moved, resid = position_outliers(dev, obs.target_mm, groups, valid, sigma_um, k)
        return moved, lambda i: f"position {resid[i]:+.1f} um off the local trend of its run (image replaced?)"

    return judge_views(sol, rms, position_test, obs.index, k, round_no, obs.source)


@dataclass
class _Uncertainty:
    """Covariances of the solution (SPEC 4, "Uncertainty")."""

    sigma2: float  # a-posteriori noise variance, px^2
    var_s: np.ndarray  # (K,) mm^2, noise only
    var_total: np.ndarray  # (K,) mm^2, with the intrinsics' covariance
    step_sigma: np.ndarray  # (K,) mm, of each step to the previous capture of its run
    parameter_sigmas: dict[str, list[float]]
    inverse: Any  # ArrowheadInverse, one unknown per view
    intrinsics_gradient: np.ndarray | None  # d s / d intrinsics, (K, 9)
    n_obs: int
    n_params: int
    poses: PoseNormals  # every usable view's pose blocks at the solution: the per-view fits start from them


def _uncertainty(obs: Observations, opt: EstimateOptions, sol: Solution, X: np.ndarray, mask_all: np.ndarray) -> _Uncertainty:
    """Cov = sigma^2 H^-1 by the arrowhead inverse; intrinsics propagated; excluded views on their own."""
    used, usable, free = sol.used, sol.usable, sol.free()
    have_cov = obs.intrinsics.covariance is not None
    # one pass over every usable view; only the used ones enter the equations
    eq, poses = linearize_poses(sol.state, X, obs.corners_px, mask_all, with_intrinsics=have_cov or opt.self_calibrate,
                                views=used)
    p = N_POSE_PARAMS
    A, B = eq.A, eq.B
    if opt.self_calibrate:
        A = A.copy()
        A[p:, p:] += np.linalg.inv(opt.intrinsics_prior(obs.intrinsics)[1])
        n_params = p + N_INTRINSICS + int(free.sum())
    else:
        A, B = A[:p, :p], B[:, :p]
        n_params = p + int(free.sum())
    sigma2 = noise_variance(eq.ssr, eq.n_obs, n_params)
    inv = line_inverse(A, B, eq.D, free)
    var_s = sigma2 * inv.variances()[:, 0]
    var_total = var_s.copy()
    G_s = None
    if have_cov and not opt.self_calibrate:
        G_s = intrinsics_sensitivity(inv, eq.A[:p, p:], eq.B[:, None, p:])[:, 0]
        var_total = var_s + propagated_variance(G_s, obs.intrinsics.covariance)
    # positions of views outside the solve: their own 1-D sigma (noise only), n^T H_tt n of their pose blocks
    alone = usable & ~used
    if alone.any():
        n = sol.state.n
        var_o = sigma2 / np.maximum(np.einsum("i,kij,j->k", n, poses.H[alone, 3:, 3:], n), 1e-300)
        var_s[alone] = var_o
        var_total[alone] = var_o
    var_s[~usable] = np.nan
    var_total[~usable] = np.nan
    prev, cur = step_pairs(obs.run, obs.direction)
    step_sigma = np.full(obs.K, np.nan)
    both = used[prev] & used[cur]
    if both.any():
        step_sigma[cur[both]] = np.sqrt(sigma2 * inv.cov_difference(prev[both], cur[both])[:, 0, 0])
    sd = np.sqrt(np.diag(sigma2 * inv.S_inv))
    param_sigmas = {"rvec_sigma_rad": sd[0:3].tolist(), "l0_sigma_mm": sd[3:6].tolist(), "n_sigma_rad": sd[6:p].tolist()}
    if opt.self_calibrate:
        param_sigmas["intrinsics_sigma"] = sd[p : p + N_INTRINSICS].tolist()
    return _Uncertainty(sigma2, var_s, var_total, step_sigma, param_sigmas, inv, G_s, eq.n_obs, n_params, poses)



def _finish(obs: Observations, opt: EstimateOptions, sol: Solution, X: np.ndarray, mask_all: np.ndarray,
            timings: dict[str, float]) -> LpsEstimate:
    """Uncertainty, per-view RMS, 6-DOF motions and board-plane straightness of the solution, as an :class:`LpsEstimate`."""
    t0 = time.perf_counter()
    unc = _uncertainty(obs, opt, sol, X, mask_all)
    timings["uncertainty"] = time.perf_counter() - t0
    six = board_plane = None
    if opt.six_dof:
        t1 = time.perf_counter()
        six = _six_dof(sol.state, obs, X, mask_all, sol.usable, sol.used, unc.poses)
        timings["six_dof"] = time.perf_counter() - t1
        t1 = time.perf_counter()  # straightness at the board plane and image rotation (SPEC 11)
        state = sol.state
        board_plane = board_plane_from_model(state.R, state.line().translations(state.s), state.line().u_board, X,
                                             obs.corners_px, mask_all, state.intrinsics, state.s, sol.usable, sol.used,
                                             start=unc.poses)
        timings["board_plane"] = time.perf_counter() - t1
    est = LpsEstimate(
        method=opt.method,
        options=opt,
        state=sol.state,
        reference_view=sol.ref,
        usable=sol.usable,
        used=sol.used,
        outlier=sol.outlier,
        outlier_reason=sol.reasons,
        sigma_px=float(np.sqrt(unc.sigma2)),
        sigma_s_mm=np.sqrt(unc.var_s),
        sigma_total_mm=np.sqrt(unc.var_total),
        step_sigma_mm=unc.step_sigma,
        rms_px=_view_rms(sol.state, X, obs.corners_px, mask_all, unc.poses.ssr, sol.usable),
        n_corners=mask_all.sum(axis=1),
        parameter_sigmas=unc.parameter_sigmas,
        iterations=sol.iterations,
        converged=sol.converged,
        n_observations=unc.n_obs,
        dof=unc.n_obs - unc.n_params,
        six_dof=six,
        flags=sol.flags,
        timings_s=timings,
        inverse=unc.inverse,
        intrinsics_gradient=unc.intrinsics_gradient,
        board_plane=board_plane,
    )
    if opt.method == "joint":  # the line model's misfit (angles, straightness) is not the corners' noise
        est = with_board_plane_positions(est, X.mean(axis=0), *step_pairs(obs.run, obs.direction))
    return est


def _six_dof(
    state: LpsState, obs: Observations, X: np.ndarray, mask_all: np.ndarray, usable: np.ndarray, used: np.ndarray,
    start: PoseNormals | None = None,
) -> SixDof:
    """Per-view poses started from the common model, then straightness and angles.

    The noise is the pooled residual of the per-view fits, not the joint
    fit's: angular error motions that the common rotation cannot follow
    inflate the latter, never the former.
    """
    K = obs.K
    t_model = state.line().translations(state.s)
    t_model[~usable] = state.l0
    poses = refine_view_poses(np.broadcast_to(state.R, (K, 3, 3)), t_model, X, obs.corners_px, mask_all, state.intrinsics,
                              start=start)
    n_obs = int(2 * mask_all[used].sum())
    sigma2 = noise_variance(float(poses.ssr[used].sum()), n_obs, 6 * int(used.sum()))
    six = six_dof_motion(poses, state.R, used, sigma2)
    for arr in (six.straightness_um, six.straightness_sigma_um, six.angles_urad, six.angles_sigma_urad):
        arr[~usable] = np.nan
    return six


# ----------------------------------------------------------------------------- D = 2: the plane (SPEC 10)


def _estimate_plane(obs: Observations, opt: EstimateOptions, progress: ProgressFn, cancel: CancelToken | None
                    ) -> LpsEstimate:
    """D = 2: per-view PnP -> initial plane -> joint LM on the block arrowhead (b = 2) inside the outlier
    rounds (the position test: the robust affine trend of the grid) -> the frame turned so +x is the fitted
    X motion (SPEC 10) -> covariance with the intrinsics' propagated. ``pnp``: the per-view baseline."""
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
        return plane_per_view(obs, opt, state, R_v, t_v, usable, ref, X, mask_all, timings, t_start)

    sol = Solution(state, ref, usable, np.zeros(obs.K, dtype=bool), [""] * obs.K)
    prior = opt.intrinsics_prior(obs.intrinsics)
    progress(1, 4, "joint planar solve")

    def solve(sol: Solution) -> None:
        res = solve_planar(sol.state, X, obs.corners_px, mask_all & sol.used[:, None], sol.free(), robust=opt.robust,
                           cancel=cancel, intrinsics_prior=prior)
        sol.state, sol.iterations, sol.converged = res.state, res.iterations, res.converged

    solve_with_outliers(sol, solve, lambda sol, round_no: _plane_outlier_round(sol, obs, X, mask_all, opt.outlier_k,
                                                                               round_no), opt, timings, cancel)
    state, used = sol.state, sol.used
    others = usable & ~used
    if others.any():
        sub = state.copy()
        sub.xy = state.xy[others]
        state.xy[others] = planar_positions_only(sub, X, obs.corners_px[others], mask_all[others])
    progress(3, 4, "uncertainty")
    state = align_to_x_motion(state.regauged(sol.ref), obs.target_mm, obs.approach, used)
    t0 = time.perf_counter()
    mask = mask_all & used[:, None]
    inv, sigma2, G_s, n_params = _plane_uncertainty(state, obs, X, mask, sol.free(), prior)
    cov = sigma2 * inv.cov_view()
    cov_total = cov
    if G_s is not None:
        cov_total = cov + np.einsum("kai,ij,kbj->kab", G_s, obs.intrinsics.covariance, G_s)
    timings["uncertainty"] = time.perf_counter() - t0
    n_obs = int(2 * mask.sum())
    est = LpsEstimate(
        method=opt.method, options=opt, state=state, reference_view=sol.ref, usable=usable, used=used,
        outlier=sol.outlier, outlier_reason=sol.reasons, sigma_px=float(np.sqrt(sigma2)), sigma_s_mm=sigmas_of(cov),
        sigma_total_mm=sigmas_of(cov_total), rms_px=_plane_view_rms(state, X, obs.corners_px, mask_all),
        n_corners=mask_all.sum(axis=1), iterations=sol.iterations, converged=sol.converged, n_observations=n_obs,
        dof=n_obs - n_params, flags=sol.flags, timings_s=timings, inverse=inv, intrinsics_gradient=G_s, cov_mm2=cov,
        cov_total_mm2=cov_total,
    )
    est.fit = planar_fit(est, obs.target_mm, obs.approach)
    timings["total"] = time.perf_counter() - t_start
    progress(4, 4, "done")
    return est


def _plane_outlier_round(sol: Solution, obs: Observations, X: np.ndarray, mask_all: np.ndarray, k: float,
                         round_no: int) -> bool:
    """One judgement of the used views (:func:`~lps_gui.core.estimator.outlier_round.judge_views`) with the plane's
    position test: a position off the robust affine trend of the grid, against its own sigma."""
    rms = _plane_view_rms(sol.state, X, obs.corners_px, mask_all)
    eq, _ = linearize_planar(sol.state, X, obs.corners_px, mask_all & sol.used[:, None])
    free = sol.free()
    sigma2 = noise_variance(eq.ssr, eq.n_obs, N_PLANAR_SHARED + 2 * int(free.sum()))
    sig_um = 1e3 * np.sqrt(sigma2 * plane_inverse(eq.A, eq.B, eq.D, free).variances())

    def position_test(valid: np.ndarray) -> tuple[np.ndarray, Callable[[int], str]]:
        resid = affine_residual_um(sol.state.xy, obs.target_mm, obs.approach, valid)
        scale = np.maximum(np.array([robust_sigma(resid[valid, a]) for a in range(2)])[None, :], sig_um)
        moved = valid & np.any(np.abs(resid) > k * np.maximum(scale, 1e-9), axis=1)
        return moved, lambda i: (f"position ({resid[i, 0]:+.1f}, {resid[i, 1]:+.1f}) um off the trend of the grid "
                                 "(image replaced?)")

    ref = sol.ref
    flagged = judge_views(sol, rms, position_test, obs.index, k, round_no, obs.source)
    if sol.ref != ref:
        sol.state.xy = sol.state.xy - sol.state.xy[sol.ref]
    return flagged


def _plane_view_rms(state: PlanarState, X: np.ndarray, corners: np.ndarray, mask: np.ndarray) -> np.ndarray:
    r = planar_residuals(state, X, corners, mask)
    n = mask.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n > 0, np.sqrt(np.sum(r * r, axis=(1, 2)) / np.maximum(n, 1)), np.nan)


def _plane_uncertainty(state: PlanarState, obs: Observations, X: np.ndarray, mask: np.ndarray, free: np.ndarray,
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


SOLVERS = {1: _estimate_line, 2: _estimate_plane}  # the solver family of a stage of D axes
