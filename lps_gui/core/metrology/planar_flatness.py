"""Out-of-plane motion of an XY gantry at the board plane (SPEC 10 with SPEC 11's rule).

The planar model puts every view in the fitted plane. What the board can
still tell, view by view under the common orientation, is how far the
line of sight at the board moved off that plane (along the plane normal,
which for a camera-array rig is the viewing direction, seen only through the
board's image scale). :func:`core.constant_orientation.solve_views` gives each
view's board centre ``b_i`` (3 DOF) and image rotation with its covariance;
the component of ``b_i - b_model_i`` along the plane normal, off its
least-squares plane over the targets, is the out-of-plane deviation. Per
line of the plan it is the out-of-plane straightness of that axis, judged
resolved or not by :func:`core.resolution.profile_span` like every other
straightness.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.core.models.constant_orientation import solve_views, start_from_line
from lps_gui.core.models.planar_model import PlanarState


@dataclass(frozen=True)
class OutOfPlane:
    """Per-view displacement along the plane normal at the board plane, off the least-squares plane."""

    normal_um: np.ndarray  # shape (K,): along e_x x e_y (stage x, y, normal right-handed); NaN without a board
    sigma_um: np.ndarray  # shape (K,): 1-sigma from corner noise
    sigma_px: float  # a-posteriori corner noise of this fit


def out_of_plane(state: PlanarState, X: np.ndarray, corners: np.ndarray, mask: np.ndarray, target_mm: np.ndarray,
                 used: np.ndarray) -> OutOfPlane:
    """Each view's out-of-plane displacement (um) with its sigma, relative to the plane fitted over ``used``."""
    X0 = np.asarray(X, float).mean(axis=0)
    b_model = start_from_line(state.R, state.translations(), X0)  # shape (K, 3)
    seen = mask.any(axis=1)
    views = solve_views(state.R, b_model, X, X0, corners, mask & seen[:, None], state.intrinsics)
    n = state.P[:, 2]  # n_x x n_y, camera frame: the board-frame normal e_x x e_y is R^T n
    # a camera displacement delta along e_n moves t (and b) by -delta n
    d_mm = -(views.b - b_model) @ n  # shape (K,)
    dof = max(int(views.n_obs[used].sum()) - 4 * int(used.sum()), 1)
    sigma2 = float(views.ssr[used].sum()) / dof
    var = np.einsum("i,kij,j->k", n, views.cov_unit[:, :3, :3], n) * sigma2
    T = np.asarray(target_mm, float)
    design = np.column_stack([np.ones(T.shape[0]), T])  # shape (K, 3): a plane in the targets
    coef = np.linalg.lstsq(design[used], d_mm[used], rcond=None)[0]
    resid_um = 1e3 * (d_mm - design @ coef)
    resid_um[~seen] = np.nan
    return OutOfPlane(resid_um, 1e3 * np.sqrt(np.maximum(var, 0.0)), float(np.sqrt(sigma2)))
