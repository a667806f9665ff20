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
from dataclasses import replace

import numpy as np

from lps_gui.core.estimator.estimate_types import LpsEstimate
from lps_gui.core.models.constant_orientation import board_plane_displacements, path_direction
from lps_gui.core.models.six_dof import ViewPoses
from lps_gui.core.numerics.arrowhead import ArrowheadInverse
from lps_gui.core.numerics.uncertainty import propagated_variance

MISFIT_Z = 3.09  # one-sided 0.1 % of the normal: ln F beyond this many of its sd rejects the line model
POSITION_MODEL_LINE = "line"  # one unknown per view (SPEC 3)
POSITION_MODEL_BOARD_PLANE = "board plane"  # each view's board-centre displacement (SPEC 11), along its line


def line_model_rejected(sigma2_line: float, dof_line: int, sigma2_views: float, dof_views: int) -> bool:
    """True when the line model's residual variance exceeds the per-view fit's by more than noise allows.

    Both variances estimate the corners' noise when the line model holds; ln of their ratio is then
    normal with variance 2/dof_line + 2/dof_views (large dof, thousands here). One-sided at 0.1 %.
    """
    if not (dof_line > 0 and dof_views > 0 and sigma2_views > 0 and math.isfinite(sigma2_line)):
        return False
    return math.log(sigma2_line / sigma2_views) > MISFIT_Z * math.sqrt(2.0 / dof_line + 2.0 / dof_views)


def gauge_inverse(var_unit: np.ndarray, ref: int, free: np.ndarray) -> ArrowheadInverse:
    """The covariance of s_i = p_i - p_ref for independent p_i (unit variances ``var_unit``) as an arrowhead:
    the reference's own p is the one shared unknown, so every functional and step keeps its correlation."""
    K = var_unit.size
    D_inv = np.where(free, var_unit, 0.0).reshape(K, 1, 1)
    W = np.where(free, -1.0, 0.0).reshape(K, 1, 1)
    return ArrowheadInverse(np.array([[float(var_unit[ref])]]), W, D_inv)


def positions_from_poses(poses: ViewPoses, R: np.ndarray, X0: np.ndarray, used: np.ndarray, towards: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray]:
    """(D_i . a, its variance per unit noise variance), shape (K,) each: a the least-squares line's direction.

    With the left perturbation of the poses (R_i <- exp(dw) R_i, t_i <- t_i + dt), d b_i = dw x c_i + dt
    (c_i = R_i X0), so d (D_i . a) = -(c_i x m) . dw - m . dt with m = R a.
    """
    D = board_plane_displacements(poses.R, poses.t, X0, R)
    a = path_direction(D, used, towards)
    m = R @ a
    c = np.einsum("kij,j->ki", poses.R, X0)
    J = np.concatenate([-np.cross(c, m[None, :]), -np.broadcast_to(m, c.shape)], axis=1)  # shape (K, 6)
    return D @ a, np.einsum("ka,kab,kb->k", J, poses.cov_unit, J)


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
    if not line_model_rejected(est.sigma_px**2, est.dof, six.sigma2_px, dof_views):
        return est
    position, var_unit = positions_from_poses(six.poses, est.state.R, X0, used, est.state.line().u_board)
    seen = usable & np.isfinite(position) & np.isfinite(var_unit)
    if not seen[ref]:
        return est
    sigma2 = six.sigma2_px
    free = seen.copy()
    free[ref] = False
    inv = gauge_inverse(np.where(seen, var_unit, 0.0), ref, free)
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
