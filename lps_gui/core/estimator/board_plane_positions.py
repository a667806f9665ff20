"""Positions at the board plane when the line model cannot follow the carriage (issue 35).

The LPS model (SPEC 3) gives each view one unknown, its position s_i on a line, under one orientation. A
carriage that rolls or runs off the line moves the board's image across the motion (roll x board distance:
~1 mm on the honesty campaign's ``motions`` stage), and a yaw about the viewing direction turns it; one
unknown per view follows neither. The joint fit's a-posteriori sigma is then that misfit (0.34 px where the
corners have 0.016 px), every position's sigma ~20 x too large, and each position couples to the misfit.

Each view's own pose (SPEC 4.5, :mod:`lps_gui.core.models.six_dof`, fixed intrinsics) has no misfit: its
residuals are the corners' noise. A tilt and a sideways shift are hard to tell apart in one view, but the
board centre's place in the camera frame, b_i = R_i X0 + t_i, is not: D_i = X0 - R^T b_i, where a camera of
the common orientation R sees the board centre (the Abbe convention of the positions, exact for any angle),
is as well determined as the line model's s_i. The positions are D_i along the least-squares line of the used
D_i (ISO 230-1's reference line), each with its own sigma. (The 4-unknown fit of SPEC 11 leaves a camera tilt's
perspective in its b_i: 290 ppm of scale on that stage.) They replace the line model's positions when a
variance-ratio test says the line model leaves more than noise; on a stage the line model fits (ratio ~1.00)
nothing changes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.special import fdtrc  # the F distribution's survival function (scipy.stats stays out of `lps estimate`)

from lps_gui.core.estimator.estimate_types import LpsEstimate
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.models.constant_orientation import board_plane_displacements, path_direction
from lps_gui.core.models.pose_model import solve_poses
from lps_gui.core.models.target_model import TargetObservations, TargetSolution, with_bows
from lps_gui.core.numerics.arrowhead import ArrowheadInverse
from lps_gui.core.numerics.target_arrowhead import PositionCovariance
from lps_gui.core.numerics.uncertainty import propagated_variance

MISFIT_Z = 3.09  # one-sided 0.1 % of the normal (the Hausman scale test, line_scale_bias)
MISFIT_ALPHA = 1e-3  # the misfit switch's false-switch rate on a stage the line model fits (one-sided F-test)
MISFIT_MATERIAL = 1.5  # ... and the line model's residual variance at least this x the per-view fit's (see below)
HAUSMAN_FLOOR = 0.1  # var(poses) - var(line) is at least this share of var(poses) (see line_scale_biased)
POSITION_MODEL_BOARD_PLANE = "board plane"  # each view's board-centre line of sight from its own pose (else "line")
POSITION_MODEL_POSE_SCALE = "line, scale of the board plane"  # the line model's positions, the poses' scale


def line_model_rejected(sigma2_line: float, dof_line: int, sigma2_views: float, dof_views: int,
                        alpha: float = MISFIT_ALPHA, material: float = MISFIT_MATERIAL) -> bool:
    """True when the line model leaves more than the corners' noise: the extra-sum-of-squares F-test of the line
    model (one orientation, one unknown per view) nested in the per-view fit (six unknowns per view) on the same
    corners, rejecting at false-switch rate ``alpha`` where the line model holds, for a misfit that is material.

    Why this test: the two residual variances share every corner's noise, so their ratio barely scatters where the
    line model holds (0.98-1.02 on the campaign's flat sessions, 5129 against 4896 dof), far less than two
    independent variances would (ln F sd 0.028): a misfit shows in the sum of squares the per-view fit removes,
    RSS_line - RSS_views, on dof_line - dof_views (five a view), against the per-view noise.
    Why ``material`` (a variance ratio, 1.5): with 10^5 residuals a misfit of 0.4 % of the noise's variance is
    significant (the paper close-up's small angles: 0.1005 px against 0.1001 px), and there each stop's own pose is less precise
    than the line model across a short step (its 2 um ASME steps: sigma 1.13 um against the must-show's 1 um).
    The campaign has no session between 1.07 (min-step, settling: motions, realism on) and 1.92 (the same, realism
    off, which the former constant 2 switched by coin flip); 1.5 sits between.
    No redundancy, or fits that are not nested (dof_line <= dof_views): no judgement.
    """
    if not (dof_views > 0 and dof_line > dof_views and sigma2_views > 0 and math.isfinite(sigma2_line)):
        return False
    if sigma2_line < material * sigma2_views:
        return False
    dfn = dof_line - dof_views
    f = (dof_line * sigma2_line - dof_views * sigma2_views) / (dfn * sigma2_views)
    return bool(fdtrc(dfn, dof_views, f) < alpha)


def gauge_inverse(var_unit: np.ndarray, ref: int, free: np.ndarray) -> ArrowheadInverse:
    """The covariance of s_i = p_i - p_ref for independent p_i (unit variances ``var_unit``) as an arrowhead:
    the reference's own p is the one shared unknown, so every functional and step keeps its correlation."""
    K = var_unit.size
    D_inv = np.where(free, var_unit, 0.0).reshape(K, 1, 1)
    W = np.where(free, -1.0, 0.0).reshape(K, 1, 1)
    return ArrowheadInverse(np.array([[float(var_unit[ref])]]), W, D_inv)


def positions_from_poses(R_views: np.ndarray, t_views: np.ndarray, R: np.ndarray, X0: np.ndarray, used: np.ndarray,
                         towards: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(D_i . a (K,), its gradient (K, 6) in each pose's (rotation, translation)): a the least-squares line's direction.

    With the left perturbation of the poses (R_i <- exp(dw) R_i, t_i <- t_i + dt), d b_i = dw x c_i + dt
    (c_i = R_i X0), so d (D_i . a) = -(c_i x m) . dw - m . dt with m = R a.
    """
    D = board_plane_displacements(R_views, t_views, X0, R)
    a = path_direction(D, used, towards)
    m = R @ a
    c = np.einsum("kij,j->ki", R_views, X0)
    return D @ a, np.concatenate([-np.cross(c, m[None, :]), -np.broadcast_to(m, c.shape)], axis=1)


def line_scale_bias(est: LpsEstimate, pose_positions: np.ndarray, sigma2_pose: float, inv: ArrowheadInverse,
                    seen: np.ndarray) -> tuple[float, float] | None:
    """(slope of line minus pose positions against the line's, its variance) when the per-view poses'
    board-plane positions reject the line model's scale, else None.

    Why: a misfit too small for :func:`line_model_rejected` passes, yet its share of every position can be a
    trend the per-stop sigma hides and a scale (or E, M) shows: the ASME min-step test on the ``motions`` stage
    (pitch 1320 urad over 22 mm, the board 0.1 rad off the optical axis) leaves 0.016 px of misfit under
    0.02 px of noise, and the line model reads the pitch's Abbe shift 0.5 % short of the board centre's line of
    sight: +157 ppm of scale on noise-free views, 3.5 sigma of the scale (the paper close-up's small angles:
    +2 ppm, 2 sigma). Both sets estimate the same displacement where the line model holds, the line model the
    more precisely, so their slopes' difference has the variance var(poses) - var(line) (Hausman's test);
    floored at ``HAUSMAN_FLOOR`` of the poses' own, the test cannot fire on a difference of two nearly equal
    sigmas. One-sided 0.1 % as the variance test.
    """
    both = est.used & seen & np.isfinite(est.state.s)
    if both.sum() < 3 or est.inverse is None:
        return None
    x = np.where(both, est.state.s, 0.0)
    dx = np.where(both, x - x[both].mean(), 0.0)
    sxx = float(dx @ dx)
    if sxx <= 0.0:
        return None
    L = (dx / sxx)[None, :, None]  # the least-squares slope of the positions against themselves
    var_line = float(est.sigma_px**2 * est.inverse.functional_covariance(L)[0, 0])
    var_pose = float(sigma2_pose * inv.functional_covariance(L)[0, 0])
    diff = float(L[0, :, 0] @ np.where(both, est.state.s - pose_positions, 0.0))
    var = max(var_pose - var_line, HAUSMAN_FLOOR * var_pose)
    return (diff, var) if var > 0.0 and abs(diff) > MISFIT_Z * math.sqrt(var) else None


def with_pose_scale(est: LpsEstimate, bias: float, var: float) -> LpsEstimate:
    """The line model's positions with the per-view poses' scale: s (1 - bias), the correction's variance
    var s^2 added to each position's. Why not the poses' positions themselves: a view's 6-DOF pose is less
    precise across a short step than the line model (the paper close-up's 2 um ASME steps: sigma 1.13 um
    against 0.9), and the bias the test sees is a scale (a pitch ramp's Abbe shift, read short)."""
    state = est.state.copy()
    s = est.state.s
    state.s = s * (1.0 - bias)
    extra = var * s**2
    return replace(est, state=state, sigma_s_mm=np.sqrt((1.0 - bias) ** 2 * est.sigma_s_mm**2 + extra),
                   sigma_total_mm=np.sqrt((1.0 - bias) ** 2 * est.sigma_total_mm**2 + extra),
                   step_sigma_mm=abs(1.0 - bias) * est.step_sigma_mm, position_model=POSITION_MODEL_POSE_SCALE)


def with_noise_of_the_views(est: LpsEstimate, sigma2_views: float) -> LpsEstimate:
    """The kept line model's position sigmas scaled from its own a-posteriori sigma to the per-view fit's.

    Why (issue 35): a line model kept (a misfit :func:`line_model_rejected` does not see) has an a-posteriori
    sigma that is noise plus that misfit; the misfit is the residual the model cannot follow (orthogonal to the positions' columns), not scatter of the positions. Sized with it, each position's sigma
    and every figure drawn from it were too wide by sqrt(ratio): the honesty campaign's min-step motions cell
    (ratio ~1.9) had per-stop (error/sigma)^2 0.52, E 0.38, M 0.16. The per-view fit's residuals are the
    corners' noise (module docstring): its variance sizes the noise (``sigma_px``, the corners' a-posteriori noise,
    is then the per-view fit's). Never raises a sigma (ratio under 1: as is).
    """
    if not (sigma2_views > 0.0 and math.isfinite(sigma2_views)) or sigma2_views >= est.sigma_px**2:
        return est
    r = math.sqrt(sigma2_views) / est.sigma_px
    other2 = np.clip(est.sigma_total_mm**2 - est.sigma_s_mm**2, 0.0, None)  # intrinsics: not the corners' noise
    return replace(est, sigma_px=float(math.sqrt(sigma2_views)), sigma_s_mm=r * est.sigma_s_mm,
                   sigma_total_mm=np.sqrt(r * r * est.sigma_s_mm**2 + other2),
                   step_sigma_mm=None if est.step_sigma_mm is None else r * est.step_sigma_mm)


def with_board_plane_positions(est: LpsEstimate, X0: np.ndarray, prev: np.ndarray, cur: np.ndarray) -> LpsEstimate:
    """``est`` with the board-plane positions of the per-view poses when the line model is rejected, else ``est``.

    ``X0``: the board centre (board frame); ``prev``, ``cur``: the step pairs of
    :func:`~lps_gui.core.estimator.estimate_types.step_pairs`. The intrinsics' share of each position is the
    line model's (both measure the same displacement to first order); views outside the solve get their own
    position and sigma from their pose.
    """
    six = est.six_dof
    if six is None or six.poses is None or est.state.s.ndim != 1:
        return est
    used, usable, ref = est.used, est.usable, est.reference_view
    n_used = int(used.sum())
    dof_views = int(2 * est.n_corners[used].sum()) - 6 * n_used
    rejected = line_model_rejected(est.sigma_px**2, est.dof, six.sigma2_px, dof_views)
    if not rejected and est.inverse is None:
        return est
    position, J = positions_from_poses(six.poses.R, six.poses.t, est.state.R, X0, used, est.state.line().u_board)
    var_unit = np.einsum("ka,kab,kb->k", J, six.poses.cov_unit, J)
    seen = usable & np.isfinite(position) & np.isfinite(var_unit)
    if not seen[ref]:
        return est
    sigma2 = six.sigma2_px
    free = seen.copy()
    free[ref] = False
    inv = gauge_inverse(np.where(seen, var_unit, 0.0), ref, free)
    if not rejected:
        bias = line_scale_bias(est, position - position[ref], sigma2, inv, seen)
        kept = with_noise_of_the_views(est, sigma2)
        return kept if bias is None else with_pose_scale(kept, *bias)
    var_s = np.where(seen, sigma2 * inv.variances()[:, 0], np.nan)
    intr = np.nan_to_num(est.sigma_total_mm**2 - est.sigma_s_mm**2)
    if est.intrinsics_gradient is not None and est.state.intrinsics.covariance is not None:
        intr = propagated_variance(est.intrinsics_gradient, est.state.intrinsics.covariance)
    state = est.state.copy()
    state.s = np.where(seen, position - position[ref], est.state.s)
    step = np.full(state.s.size, np.nan)
    both = seen[prev] & seen[cur]
    if both.any():
        step[cur[both]] = np.sqrt(sigma2 * inv.cov_difference(prev[both], cur[both])[:, 0, 0])
    return replace(est, state=state, sigma_px=float(np.sqrt(sigma2)), sigma_s_mm=np.sqrt(var_s),
                   sigma_total_mm=np.sqrt(var_s + np.where(seen, intr, np.nan)), step_sigma_mm=step, inverse=inv,
                   dof=dof_views, position_model=POSITION_MODEL_BOARD_PLANE, line_model_sigma_px=est.sigma_px)


@dataclass(frozen=True)
class PosePositionCovariance:
    """The covariance of positions s_k = g_k . v_k - g_ref . v_ref, linear in the pose model's view 6-vectors v_k
    (their covariance correlated through the targets' poses): the interface of the row model's position
    covariance (:class:`~lps_gui.core.numerics.target_arrowhead.PositionCovariance`, D = 1) for the estimate's
    functionals (scale, steps)."""

    poses: PositionCovariance  # of the views' 6-vectors
    g: np.ndarray  # (K, 6): d s_k / d v_k
    ref: int
    sigma2: float
    row: PositionCovariance  # the row model's: its shared parameters' block (``S_inv``) gives their sigmas

    @property
    def S_inv(self) -> np.ndarray:
        return self.row.S_inv

    def _weights(self, L: np.ndarray) -> np.ndarray:
        L = np.array(L[..., 0], dtype=float)  # (Q, K) on the positions
        L[:, self.ref] = 0.0  # s_ref is 0
        g6 = L[:, :, None] * self.g[None, :, :]
        g6[:, self.ref, :] = -L.sum(axis=1)[:, None] * self.g[self.ref][None, :]
        return g6

    def covariance(self, L: np.ndarray) -> np.ndarray:
        """(Q, Q) covariance of Q functionals with weights L (Q, K, 1) on the positions."""
        return self.poses.covariance(self._weights(L))

    def variances(self, L: np.ndarray) -> np.ndarray:
        """Variances of Q functionals with weights L (Q, K, 1) on the positions."""
        return self.poses.variances(self._weights(L))


def row_with_board_plane_positions(tobs: TargetObservations, sol: TargetSolution, intrinsics: CameraIntrinsics,
                                   dof_row: int) -> TargetSolution:
    """A row's solution (SPEC 13, D = 1) with every stop's position from its full pose when the row model is rejected.

    The row model holds one orientation and one unknown per view, jointly with the targets' poses; a carriage
    that rolls or yaws leaves a misfit that the targets' poses absorb (520 um of max |deviation| on the
    campaign's row with angles). The pose model (:func:`~lps_gui.core.models.pose_model.solve_poses`, every
    stop's six unknowns with the targets', started from the row's solution) has none. The positions are the
    first target's centre's line of sight (D_i, as one board's) along its least-squares line; the targets'
    poses and their sigmas are the pose model's.
    """
    if sol.bows_mm is not None:  # the row's bows, refined with the poses (their uncertainty in the poses' sigmas)
        tobs = TargetObservations(with_bows(tobs.targets, sol.bows_mm), tobs.corners_px, tobs.targets_mm, tobs.names)
    poses = solve_poses(tobs, intrinsics, start=sol, bows=sol.bows_mm is not None)
    used = sol.used & poses.used
    n_corners = int((np.isfinite(tobs.corners_px[..., 0]) & used[:, None]).sum())
    n_bows = 0 if poses.bows_mm is None else poses.bows_mm.size
    dof_poses = 2 * n_corners - n_bows - 6 * (len(tobs.targets) - 1) - 6 * int(used.sum())
    if not line_model_rejected(sol.sigma_px**2, dof_row, poses.sigma_px**2, dof_poses):
        return sol
    ref = sol.reference
    X0 = tobs.targets[0].board.object_points().mean(axis=0)
    position, g = positions_from_poses(poses.R, poses.t, sol.R, X0, used, -sol.R.T @ sol.N[:, 0])
    cov = PosePositionCovariance(poses.covariance, np.where(used[:, None], g, 0.0), ref, poses.sigma_px**2,
                                 sol.covariance)
    K = len(used)
    unit = np.zeros((K, K, 1))
    unit[np.arange(K), np.arange(K), 0] = 1.0
    sigma = np.sqrt(np.maximum(cov.variances(unit), 0.0))
    s = np.where(used, position - position[ref], np.nan)[:, None]
    sigma = np.where(used, sigma, np.nan)[:, None]
    centred = np.where(used, np.sqrt(np.maximum(np.einsum("ka,kab,kb->k", g, poses.single_view, g), 0.0)), np.nan)
    gradient = sol.intrinsics_gradient
    if poses.intrinsics_gradient is not None:  # the positions' own sensitivity, through every stop's pose
        dpos = np.einsum("ka,kai->ki", np.where(used[:, None], g, 0.0), poses.intrinsics_gradient)
        gradient = np.where(used[:, None], dpos - dpos[ref], 0.0)[:, None, :]
    return replace(sol, s=s, sigma_s=sigma, sigma_centred=centred[:, None], Q=poses.Q, p=poses.p,
                   intrinsics_gradient=gradient,
                   target_sigma=poses.target_sigma, sigma_px=poses.sigma_px, covariance=cov, used=used,
                   bows_mm=None if sol.bows_mm is None else sol.bows_mm + poses.bows_mm)
