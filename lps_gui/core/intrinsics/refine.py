"""Joint refinement of intrinsics, per-view poses and the board's bow, with per-corner outliers.

OpenCV's calibration assumes a flat board. A real board is bowed by a
millimetre or so, and the bow trades against the focal length: mrcal models
it with two parabolic factors (``calobject_warp``, see :class:`Board`) and
estimates them with everything else. Here scipy's least_squares refines the
OpenCV solution with the analytic Jacobian of :mod:`camera_model` (poses in
cv2's Rodrigues parametrization), the two warp columns being d uv / d z times
the parabolas. The covariance is ``sigma^2 (J^T J)^-1`` over the free
parameters. Corners whose residual is far beyond the robust noise level are
dropped, the worst of each view per round, and listed (view, corner, residual).

The warp is refused (:class:`WarpNotSeparableError`) when the views cannot
tell it from the other parameters: its multiple correlation with them is
then so close to 1 that its sigma is meaningless. That happens with
near-identical orientations, as in a line-only LPS session.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from lps_gui.core.geometry.board import parabolic_warp_basis
from lps_gui.core.geometry.camera_model import CameraIntrinsics, pose_jacobian_rodrigues
from lps_gui.errors import DegenerateGeometryError

# a corner is an outlier when |residual| exceeds this many robust per-axis sigmas
# (|r|^2 / sigma^2 is chi-square with 2 dof: P(> 4.8^2) = 1e-5, ~0.01 false rejections per 1000 corners)
OUTLIER_K = 4.8
MAX_OUTLIER_ROUNDS = 30
MIN_CORNERS_PER_VIEW = 6
# the warp is refused when 1 - R^2 of it against all other parameters falls below this (multiple correlation > 0.99);
# a line-only LPS session gives ~0.004, varied views tilted by only 3 deg ~0.03, 20-35 deg ~0.15
MIN_WARP_INDEPENDENCE = 0.02


class WarpNotSeparableError(DegenerateGeometryError):
    """The views cannot separate the board's bow from the focal length and poses."""


@dataclass(frozen=True)
class RejectedCorner:
    view: int  # index into the views as given to the calibration
    corner: int  # SPEC 2 corner index
    residual_px: float  # length of the reprojection error when it was rejected


@dataclass
class RefineResult:
    intrinsics_vector: np.ndarray  # shape (9,)
    covariance: np.ndarray  # shape (9, 9), zero rows/cols for fixed parameters
    warp_mm: np.ndarray | None  # shape (2,), None when not estimated
    warp_cov: np.ndarray | None  # shape (2, 2)
    rvecs: list[np.ndarray]
    tvecs: list[np.ndarray]
    residuals_px: list[np.ndarray]  # per view (n_k, 2), observed - projected (rejected corners included)
    kept: list[np.ndarray]  # per view (n_k,) bool, False for rejected corners
    sigma_px: float  # per-axis noise estimate, sqrt(SSR / dof)
    rejected: list[RejectedCorner] = field(default_factory=list)
    warp_independence: float | None = None  # 1 - R^2 of the warp against everything else (min of the two)


def _residuals_and_jacobian(p, X_flat, imgs, free, base, size_mm: tuple[float, float], want_warp, want_jac=True):
    """Stacked residuals (projected - observed) and their Jacobian over [free intrinsics, warp, poses]."""
    m = int(free.sum())
    nw = 2 if want_warp else 0
    intr_vec = _full_vector(p[:m], free, base)
    warp = p[m : m + nw] if want_warp else np.zeros(2)
    intr = CameraIntrinsics.from_values((1, 1), *intr_vec[:4], dist=tuple(intr_vec[4:]))
    res, rows = [], []
    V = len(imgs)
    n_params = m + nw + 6 * V
    for k, (Xk, uv_obs) in enumerate(zip(X_flat, imgs)):
        X = Xk.copy()
        basis = parabolic_warp_basis(X, size_mm) if want_warp else None
        if want_warp:
            X[:, 2] = basis @ warp
        pose = p[m + nw + 6 * k : m + nw + 6 * k + 6]
        uv, J, dX = pose_jacobian_rodrigues(pose[:3], pose[3:], X, intr)
        res.append((uv - uv_obs).ravel())
        if want_jac:
            Jk = np.zeros((uv.shape[0], 2, n_params))
            Jk[..., :m] = J[..., 6:][..., free[:9]]
            if want_warp:
                Jk[..., m : m + 2] = dX[..., 2:3] * basis[:, None, :]
            Jk[..., m + nw + 6 * k : m + nw + 6 * k + 6] = J[..., :6]
            rows.append(Jk.reshape(-1, n_params))
    r = np.concatenate(res)
    return r, (np.concatenate(rows) if want_jac else None)


def _full_vector(sub: np.ndarray, free: np.ndarray, base: np.ndarray) -> np.ndarray:
    v = base.copy()
    v[free] = sub
    return v


def refine_intrinsics(
    size_mm: tuple[float, float],
    X_views: list[np.ndarray],
    uv_views: list[np.ndarray],
    corner_ids: list[np.ndarray],
    view_ids: list[int],
    intrinsics: CameraIntrinsics,
    rvecs: list[np.ndarray],
    tvecs: list[np.ndarray],
    free: np.ndarray,
    estimate_warp: bool,
    reject_outliers: bool = True,
) -> RefineResult:
    """Refine an OpenCV calibration jointly (optionally with the warp), dropping outlier corners.

    ``X_views`` are the flat board points of each used view (n_k, 3), ``uv_views``
    the observed pixels (n_k, 2), ``corner_ids`` their SPEC corner indices and
    ``view_ids`` the views' indices as given by the caller (for the listing).
    ``size_mm`` is the extent of the corner grid (the warp's [-1, 1] span).
    ``free`` masks the 9 intrinsics (False = held, e.g. k3 with CALIB_FIX_K3); the lens's rational and
    thin-prism terms (``intrinsics.higher``, from OpenCV's calibration) are held as given.
    """
    free = np.concatenate([np.asarray(free, dtype=bool), np.zeros(7, dtype=bool)])
    base = np.concatenate([intrinsics.vector(), intrinsics.higher])  # 16: the 9, then the held higher terms
    keep = [np.ones(len(u), dtype=bool) for u in uv_views]
    rejected: list[RejectedCorner] = []
    head = np.concatenate([base[free], np.zeros(2) if estimate_warp else np.zeros(0)])
    poses = np.array([np.concatenate([np.ravel(r), np.ravel(t)]) for r, t in zip(rvecs, tvecs)])
    for _ in range(MAX_OUTLIER_ROUNDS + 1):
        active = [k for k, kk in enumerate(keep) if kk.sum() >= MIN_CORNERS_PER_VIEW]
        Xs = [X_views[k][keep[k]] for k in active]
        imgs = [uv_views[k][keep[k]] for k in active]
        sol = least_squares(
            lambda q: _residuals_and_jacobian(q, Xs, imgs, free, base, size_mm, estimate_warp, want_jac=False)[0],
            np.concatenate([head, poses[active].ravel()]),
            jac=lambda q: _residuals_and_jacobian(q, Xs, imgs, free, base, size_mm, estimate_warp)[1],
            method="lm",
            x_scale="jac",
            xtol=1e-12,
            ftol=1e-12,
        )
        head, poses[active] = sol.x[: head.size], sol.x[head.size :].reshape(-1, 6)
        if not reject_outliers:
            break
        new = _outliers(head, poses, X_views, uv_views, keep, active, free, base, size_mm, estimate_warp)
        if not new:
            break
        for k, j, r in new:
            keep[k][j] = False
            rejected.append(RejectedCorner(view_ids[k], int(corner_ids[k][j]), r))
        for k in active:  # a view left with too few corners goes altogether
            if 0 < keep[k].sum() < MIN_CORNERS_PER_VIEW:
                rejected += [RejectedCorner(view_ids[k], int(corner_ids[k][j]), float("nan")) for j in np.flatnonzero(keep[k])]
                keep[k][:] = False
    active = [k for k, kk in enumerate(keep) if kk.sum() >= MIN_CORNERS_PER_VIEW]
    if not active:
        raise DegenerateGeometryError("intrinsics: every corner was rejected as an outlier; check the detections")
    return _result(head, poses, X_views, uv_views, keep, active, free, base, size_mm, estimate_warp, rejected)


def _view_residuals(head, poses, X_views, uv_views, free, base, size_mm, estimate_warp) -> list[np.ndarray]:
    """observed - projected for every corner of every view given (poses one row per view)."""
    p = np.concatenate([head, poses.ravel()])
    r, _ = _residuals_and_jacobian(p, X_views, uv_views, free, base, size_mm, estimate_warp, want_jac=False)
    out, i = [], 0
    for u in uv_views:
        out.append(-r[i : i + 2 * len(u)].reshape(-1, 2))
        i += 2 * len(u)
    return out


def _outliers(head, poses, X_views, uv_views, keep, active, free, base, size_mm, estimate_warp) -> list[tuple[int, int, float]]:
    """(view, position, |r|) of the worst kept corner of each view, when beyond OUTLIER_K robust sigmas."""
    res = _view_residuals(head, poses[active], [X_views[k] for k in active], [uv_views[k] for k in active],
                          free, base, size_mm, estimate_warp)
    r2 = np.concatenate([np.sum(r[keep[k]] ** 2, axis=1) for r, k in zip(res, active)])
    sigma = np.sqrt(np.median(r2) / (2.0 * np.log(2.0)))  # |r|^2 / sigma^2 ~ chi2(2), median 2 ln 2
    limit = OUTLIER_K * sigma
    out = []
    for r, k in zip(res, active):
        # only the worst corner of a view goes per round: one bad corner pulls the pose, and with it its neighbours
        norm = np.where(keep[k], np.linalg.norm(r, axis=1), 0.0)
        j = int(np.argmax(norm))
        if norm[j] > limit:
            out.append((k, j, float(norm[j])))
    return out


def _result(head, poses, X_views, uv_views, keep, active, free, base, size_mm, estimate_warp, rejected) -> RefineResult:
    Xs = [X_views[k][keep[k]] for k in active]
    imgs = [uv_views[k][keep[k]] for k in active]
    p = np.concatenate([head, poses[active].ravel()])
    r, J = _residuals_and_jacobian(p, Xs, imgs, free, base, size_mm, estimate_warp)
    m, nw = int(free.sum()), (2 if estimate_warp else 0)
    dof = r.size - p.size
    if dof <= 0:
        raise DegenerateGeometryError("intrinsics: fewer corner observations than parameters; add views")
    sigma2 = float(r @ r) / dof
    info = J.T @ J
    try:
        cov_p = np.linalg.inv(info) * sigma2
    except np.linalg.LinAlgError as exc:
        raise DegenerateGeometryError("intrinsics: the calibration is singular; add views at varied tilts") from exc
    independence = None
    if estimate_warp:
        w = slice(m, m + 2)
        independence = float(np.min(1.0 / (np.diag(cov_p)[w] / sigma2 * np.diag(info)[w])))
        if not independence >= MIN_WARP_INDEPENDENCE:
            raise WarpNotSeparableError(
                f"intrinsics: the views cannot separate the board's bow from the focal length and poses "
                f"(independence {independence:.1e}); tilt the board 20-45 deg in different directions, or use --warp off"
            )
    cov = np.zeros((9, 9))
    idx = np.flatnonzero(free)
    cov[np.ix_(idx, idx)] = cov_p[:m, :m]
    cov = 0.5 * (cov + cov.T)
    res = _view_residuals(head, poses, X_views, uv_views, free, base, size_mm, estimate_warp)
    return RefineResult(
        intrinsics_vector=_full_vector(head[:m], free, base),
        covariance=cov,
        warp_mm=head[m : m + 2].copy() if estimate_warp else None,
        warp_cov=cov_p[m : m + 2, m : m + 2].copy() if estimate_warp else None,
        rvecs=[q[:3].copy() for q in poses],
        tvecs=[q[3:].copy() for q in poses],
        residuals_px=res,
        kept=keep,
        sigma_px=float(np.sqrt(sigma2)),
        rejected=rejected,
        warp_independence=independence,
    )
