"""Every stop's full camera pose against targets at known-shape, unknown-pose mounts (SPEC 13, 14).

x_cam = R_i (Q_j X + p_j) + t_i: no line and no common orientation are
assumed, so each stop keeps all six degrees of freedom and the error motions
of SPEC 14 (positioning, two straightness, roll, pitch, yaw) follow from the
poses. With targets at one depth a tilt and a translation look alike and the
tilts come out poorly determined (SPEC 11); targets at two depths separate
them. Solved on the block arrowhead of :mod:`lps_gui.core.numerics.target_arrowhead`
(6 columns per target but the first, 6 per view), known intrinsics.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics, intrinsics_rows, project_parts
from lps_gui.core.geometry.rotation import chordal_mean, exp_so3
from lps_gui.core.models.target_model import (
    TargetObservations,
    TargetSolution,
    bow_columns,
    bowed,
    intrinsics_sensitivity,
    origin_in_camera,
    target_views,
    with_intrinsics_term,
)
from lps_gui.core.numerics.target_arrowhead import (
    Linearization,
    PositionCovariance,
    levenberg_marquardt,
    project_residuals,
    retract_targets,
    view_rms,
)


@dataclass
class PoseSolution:
    R: np.ndarray  # (K, 3, 3) camera from world (target 0's frame)
    t: np.ndarray  # (K, 3) mm
    Q: np.ndarray  # (T, 3, 3)
    p: np.ndarray  # (T, 3)
    used: np.ndarray  # (K,)
    sigma_px: float
    rms_px: np.ndarray
    covariance: PositionCovariance  # of the views' 6-vectors (rotation, translation; camera frame, left)
    single_view: np.ndarray  # (K, 6, 6): each view's covariance with the targets known (what one view resolves)
    target_sigma: np.ndarray  # (T, 6)
    iterations: int
    converged: bool
    bows_mm: np.ndarray | None = None  # (T, 2): each target's bow beyond its board's warp, when free
    intrinsics_gradient: np.ndarray | None = None  # (K, 6, 9): d (view pose) / d intrinsics, held with a covariance


def _linearize(state: dict, X, tj, view, uv, intrinsics: CameraIntrinsics, want_jacobian: bool = True,
               bow_basis: np.ndarray | None = None) -> Linearization:
    R, t, Q, p = state["R"], state["t"], state["Q"], state["p"]
    if bow_basis is not None:  # the targets' bows: the only shared columns besides the targets' poses
        X = bowed(X, bow_basis, state["w"], tj)
    QX = np.einsum("mij,mj->mi", Q[tj], X)
    Rv = R[view]
    RXw = np.einsum("mij,mj->mi", Rv, QX + p[tj])
    P = RXw + t[view]
    cost, r, dP = project_residuals(P, uv, intrinsics, want_jacobian)
    if dP is None:
        return Linearization(cost, r, None, None, None)  # type: ignore[arg-type]
    Jv = np.empty((len(P), 2, 6))
    Jv[:, :, 0:3] = -np.cross(dP, RXw[:, None, :])  # a row times -[v]x is -(row x v)
    Jv[:, :, 3:6] = dP
    dPR = np.matmul(dP, Rv)
    Jt = np.empty((len(P), 2, 6))
    Jt[:, :, 0:3] = -np.cross(dPR, QX[:, None, :])
    Jt[:, :, 3:6] = dPR
    Jt[tj == 0] = 0.0
    Jc = np.zeros((len(P), 2, 0)) if bow_basis is None else bow_columns(
        dP, np.einsum("mij,mj->mi", Rv, Q[tj][:, :, 2]), bow_basis, tj, len(Q))
    return Linearization(cost, r, Jc, Jt, Jv)


def _retract(state: dict, dg: np.ndarray, dv: np.ndarray) -> dict:
    new = dict(state)
    new["R"] = np.einsum("kij,kjl->kil", exp_so3(dv[:, 0:3]), state["R"])
    new["t"] = state["t"] + dv[:, 3:6]
    n_bows = 0
    if "w" in state:
        n_bows = state["w"].size
        new["w"] = state["w"] + dg[:n_bows].reshape(-1, 2)
    new["Q"], new["p"] = retract_targets(state["Q"], state["p"], dg[n_bows:])
    return new


def solve_poses(obs: TargetObservations, intrinsics: CameraIntrinsics, max_iterations: int = 50,
                tolerance: float = 1e-10, progress=None, noise_px: float | None = None,
                start: TargetSolution | None = None, bows: bool = False) -> PoseSolution:
    """Every view's pose and the targets' poses, jointly; sigmas from (J^T J)^-1 at the solution.

    ``bows``: every target's bow is free too, from the boards' warp (target_model.bow_columns).

    ``start``: the row model's solution of the same views (one orientation, a line), whose target
    poses and per-view translations are a close start: no PnP per view and target, a few iterations.
    """
    K, T = len(obs.names), len(obs.targets)
    if start is None:
        views = target_views(obs, intrinsics)
        ok, used, Q, p = views["ok"], views["used"], views["Q"], views["p"]
        R = np.tile(np.eye(3), (K, 1, 1))
        for i in np.flatnonzero(used):
            R[i] = chordal_mean(views["R_world"][i, ok[i]])
        t = origin_in_camera(views["tv"], ok, p, R)
    else:
        used, Q, p = start.used.copy(), start.Q.copy(), start.p.copy()
        R = np.tile(start.R, (K, 1, 1))
        t = start.l0[None, :] + np.where(used[:, None], start.s, 0.0) @ start.N.T
    state = {"R": R, "t": t, "Q": Q, "p": p}
    seen = np.isfinite(obs.corners_px[..., 0]) & used[:, None]
    view, corner = np.nonzero(seen)
    X, tj, uv = obs.own_points[corner], obs.which[corner], obs.corners_px[view, corner]
    basis, n_bows = (obs.bow_basis[corner], 2 * T) if bows else (None, 0)
    if bows:
        state["w"] = np.zeros((T, 2))
    fit = levenberg_marquardt(
        state, lambda st, jac=True: _linearize(st, X, tj, view, uv, intrinsics, jac, basis), _retract,
        tj, view, K, T, used.copy(), max_iterations, tolerance, progress, "pose model")
    n_params = n_bows + 6 * (T - 1) + 6 * int(used.sum())
    dof = max(2 * len(view) - n_params, 1)
    sigma2 = fit.lin.cost / dof if noise_px is None else float(noise_px) ** 2
    cov = PositionCovariance(fit.Avv_inv * used[:, None, None], fit.W * used[:, None, None], fit.S_inv, sigma2,
                             np.eye(6))
    target_sigma = np.zeros((T, 6))
    view_gradient = None
    if T > 1:
        target_sigma[1:] = np.sqrt(np.maximum(np.diag(fit.S_inv)[n_bows:], 0.0) * sigma2).reshape(T - 1, 6)
    if intrinsics.covariance is not None:  # held intrinsics move the targets at other depths (issue 35)
        Xb = bowed(X, basis, fit.state["w"], tj) if bows else X
        shared, view_gradient = _intrinsics_gradients(fit, Xb, tj, view, used, intrinsics)
        if T > 1:
            target_sigma = with_intrinsics_term(target_sigma, shared[n_bows:], intrinsics.covariance)
    return PoseSolution(fit.state["R"], fit.state["t"], fit.state["Q"], fit.state["p"], used,
                        float(np.sqrt(sigma2)), view_rms(fit.lin.r, view, K), cov, fit.Avv_inv * sigma2,
                        target_sigma, fit.iterations, fit.converged, fit.state.get("w"), view_gradient)


def _intrinsics_gradients(fit, X: np.ndarray, tj: np.ndarray, view: np.ndarray, used: np.ndarray,
                          intrinsics: CameraIntrinsics) -> tuple[np.ndarray, np.ndarray]:
    """d (shared columns: bows, target poses) / d intrinsics (G, 9) and d (view poses) / d intrinsics (K, 6, 9)
    at the pose model's solution."""
    st = fit.state
    P = np.einsum("mij,mj->mi", st["R"][view], np.einsum("mij,mj->mi", st["Q"][tj], X) + st["p"][tj]) + st["t"][view]
    du, dv = intrinsics_rows(project_parts(P[:, 0], P[:, 1], P[:, 2], intrinsics), intrinsics)
    return intrinsics_sensitivity(fit, np.stack([du.T, dv.T], axis=1), tj, view, used)


def pose_solution_from_views(R: np.ndarray, t: np.ndarray, cov_unit: np.ndarray, used: np.ndarray,
                             sigma2_px: float) -> PoseSolution:
    """Per-view poses against one board (the world, known) as a :class:`PoseSolution`: no target columns.

    ``cov_unit`` (K, 6, 6): each view's (rotation, translation) covariance per unit noise variance, the
    left perturbation of :func:`solve_poses`, so :mod:`core.error_motions` reads one board's poses
    (the 6-DOF fit of a single-board session) as it reads a constellation's.
    """
    used = np.asarray(used, bool)
    K = len(used)
    cov = PositionCovariance(cov_unit * used[:, None, None], np.zeros((K, 0, 6)), np.zeros((0, 0)), float(sigma2_px),
                             np.eye(6))
    return PoseSolution(np.asarray(R, float), np.asarray(t, float), np.eye(3)[None], np.zeros((1, 3)), used,
                        float(np.sqrt(sigma2_px)), np.full(K, np.nan), cov, cov_unit * sigma2_px, np.zeros((1, 6)), 0,
                        True)
