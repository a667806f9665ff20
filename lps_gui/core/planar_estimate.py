"""Planar (XY) estimation: the joint planar model, outlier views, the stage frame, covariances.

Steps: per-view PnP -> initial plane (:func:`initial_planar_state`) -> joint
LM (:func:`solve_planar`) -> outlier views flagged as in 1-D (reprojection
RMS, or a position off the robust affine trend) and re-solved without them
-> the frame turned so +x is the fitted X-axis motion (SPEC 10) -> covariance
of every position from the block arrowhead. The method names mirror the 1-D
ones: ``joint`` (this), ``pnp`` (per-view poses projected on the plane: the
baseline). The paper's hybrid grid search is 1-D by construction and not
offered for planar sessions.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lps_gui.core.block_arrowhead import BlockArrowheadInverse, block_arrowhead_inverse
from lps_gui.core.board import Board
from lps_gui.core.camera_model import CameraIntrinsics
from lps_gui.core.observations import CornerViews
from lps_gui.core.outliers import reprojection_outliers, robust_sigma
from lps_gui.core.planar_model import (
    N_PLANAR_SHARED,
    PlanarState,
    initial_planar_state,
    linearize_planar,
    planar_positions_only,
    planar_residuals,
    solve_planar,
)
from lps_gui.core.pnp import solve_pnp
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.core.uncertainty import noise_variance
from lps_gui.errors import DegenerateGeometryError, InputError

PLANAR_METHODS = ("joint", "pnp")


@dataclass
class PlanarObservations(CornerViews):
    """Corners of K views of one board taken on an XY stage."""

    board: Board
    intrinsics: CameraIntrinsics
    corners_px: np.ndarray  # shape (K, N, 2)
    target_mm: np.ndarray  # shape (K, 2)
    approach: np.ndarray  # shape (K, 2): +1/-1 per axis
    direction: np.ndarray  # shape (K,): +1 forward pass, -1 backward pass
    run: np.ndarray  # shape (K,)
    index: np.ndarray  # shape (K,)
    names: list[str] = field(default_factory=list)
    source: str = "planar observations"
    source_sha256: str | None = None  # of the corner file's bytes as they were read (results.json inputs)

    def __post_init__(self) -> None:
        self.corners_px = np.asarray(self.corners_px, dtype=float)
        K = self.corners_px.shape[0]
        self.target_mm = np.asarray(self.target_mm, dtype=float).reshape(K, 2)
        self.approach = np.asarray(self.approach, dtype=float).reshape(K, 2)
        self.direction = np.asarray(self.direction, dtype=float).reshape(K)
        self.run = np.asarray(self.run, dtype=int).reshape(K)
        self.index = np.asarray(self.index, dtype=int).reshape(K)
        if not self.names:
            self.names = [f"view{i}" for i in self.index]

    def validate(self) -> None:
        """One-line errors for input that cannot determine a plane of motion."""
        if self.corners_px.ndim != 3 or self.corners_px.shape[2] != 2:
            raise InputError(f"{self.source}: corners must have shape (views, corners, 2)")
        if self.corners_px.shape[1] != self.board.n_corners:
            raise InputError(f"{self.source}: views have {self.corners_px.shape[1]} corners but the board has "
                             f"{self.board.n_corners}; check inner_corners in board.json")
        usable = self.usable_views()
        if usable.sum() < 3:
            raise DegenerateGeometryError(f"{self.source}: only {int(usable.sum())} views show the board; "
                                          "need at least 3 at targets not on one line")
        t = self.target_mm[usable]
        centred = t - t.mean(axis=0)
        sv = np.linalg.svd(centred, compute_uv=False)
        if sv.size < 2 or sv[1] <= 1e-9 * max(sv[0], 1e-300):
            raise DegenerateGeometryError(f"{self.source}: the usable targets lie on one line; a planar "
                                          "session needs targets spread over both axes (or estimate it as 1-D)")


@dataclass
class PlanarFit:
    """Affine fit measured = offset + G target (+ backlash offsets), stage frame."""

    G: np.ndarray  # shape (2, 2): columns are the measured +X and +Y motion per commanded mm
    cov_G: np.ndarray  # shape (4, 4): covariance of G.ravel() (row-major), from noise
    residual_um: np.ndarray  # shape (K, 2): measured - fit (NaN for unused views)


@dataclass
class PlanarEstimate:
    """Everything the planar estimator found; positions in the stage frame (SPEC 10)."""

    method: str
    state: PlanarState  # xy in the stage frame, zero at the reference view
    reference_view: int
    usable: np.ndarray  # shape (K,) bool
    used: np.ndarray  # shape (K,) bool
    outlier: np.ndarray  # shape (K,) bool
    outlier_reason: list[str]
    sigma_px: float
    cov_xy_mm2: np.ndarray  # shape (K, 2, 2): each view's position covariance, from noise
    rms_px: np.ndarray  # shape (K,)
    n_corners: np.ndarray  # shape (K,)
    iterations: int
    converged: bool
    n_observations: int
    dof: int
    flags: list[dict[str, Any]]
    timings_s: dict[str, float]
    inverse: BlockArrowheadInverse | None  # in units of sigma_px^2, stage frame
    fit: PlanarFit | None = None

    @property
    def sigma_xy_mm(self) -> np.ndarray:
        """Per-view 1-sigma of x and y, shape (K, 2) mm."""
        return np.sqrt(np.maximum(np.einsum("kii->ki", self.cov_xy_mm2), 0.0))

    def deviation_um(self, target_mm: np.ndarray) -> np.ndarray:
        """measured - (target - target of the reference), um, shape (K, 2)."""
        t = np.asarray(target_mm, dtype=float)
        return 1e3 * (self.state.xy - (t - t[self.reference_view]))

    def functional_covariance(self, L: np.ndarray) -> np.ndarray:
        """Covariance (mm^2) of linear functionals of the positions, L shape (m, K, 2)."""
        L = np.where(self.used[None, :, None], L, 0.0)
        if self.inverse is None:
            return np.einsum("mka,kab,nkb->mn", L, self.cov_xy_mm2, L)
        return self.sigma_px**2 * self.inverse.functional_covariance(L)


def estimate_planar(
    obs: PlanarObservations,
    method: str = "joint",
    outlier_k: float = 5.0,
    max_outlier_rounds: int = 3,
    detect_outliers: bool = True,
    robust: bool = False,
    progress: ProgressFn = no_progress,
    cancel: CancelToken | None = None,
) -> PlanarEstimate:
    """Estimate the planar model and every (x, y) position from the observed corners."""
    if method not in PLANAR_METHODS:
        raise InputError(f"planar estimation: method {method!r} is not available for planar sessions; "
                         f"use one of {', '.join(PLANAR_METHODS)} (the hybrid grid search is 1-D only)")
    obs.validate()
    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    X = obs.board.object_points()
    usable = obs.usable_views()
    mask_all = obs.mask() & usable[:, None]
    ref = int(np.flatnonzero(usable)[0])
    progress(0, 4, "per-view poses")
    R_v, t_v, ok = solve_pnp(X, np.where(mask_all[..., None], obs.corners_px, np.nan), obs.intrinsics)
    usable &= ok
    if usable.sum() < 3:
        raise DegenerateGeometryError(f"{obs.source}: only {int(usable.sum())} views give a pose; check the intrinsics")
    ref = int(np.flatnonzero(usable)[0])
    state = initial_planar_state(R_v, t_v, obs.target_mm, usable, ref, obs.intrinsics)
    timings["init"] = time.perf_counter() - t_start
    if method == "pnp":
        return _per_view_result(obs, state, R_v, t_v, usable, ref, X, mask_all, timings, t_start)

    outlier = np.zeros(obs.K, dtype=bool)
    reasons = [""] * obs.K
    flags: list[dict[str, Any]] = []
    new = np.zeros(obs.K, dtype=bool)
    progress(1, 4, "joint planar solve")
    for round_no in range(max_outlier_rounds + 1):
        used = usable & ~outlier
        mask = mask_all & used[:, None]
        free = used & (np.arange(obs.K) != ref)
        t0 = time.perf_counter()
        res = solve_planar(state, X, obs.corners_px, mask, free, robust=robust, cancel=cancel)
        timings["solve"] = timings.get("solve", 0.0) + time.perf_counter() - t0
        state = res.state
        if not detect_outliers:
            break
        rms = _view_rms(state, X, obs.corners_px, mask_all)
        inv, sigma2 = _inverse(state, X, obs.corners_px, mask, free, used)
        sig_um = 1e3 * np.sqrt(sigma2 * np.einsum("kii->ki", inv.cov_view()))
        bumped = reprojection_outliers(rms, used, outlier_k)
        resid = _affine_residual_um(state.xy, obs.target_mm, obs.approach, used & ~bumped)
        scale = np.maximum(np.array([robust_sigma(resid[used & ~bumped, a]) for a in range(2)])[None, :], sig_um)
        moved = used & ~bumped & np.any(np.abs(resid) > outlier_k * np.maximum(scale, 1e-9), axis=1)
        new = (bumped | moved) & ~outlier
        if not new.any():
            break
        for i in np.flatnonzero(new):
            if bumped[i]:
                reasons[i] = (f"reprojection RMS {rms[i]:.3f} px against a median of "
                              f"{np.median(rms[used]):.3f} px (camera bumped?)")
                kind = "reprojection"
            else:
                reasons[i] = (f"position ({resid[i, 0]:+.1f}, {resid[i, 1]:+.1f}) um off the trend of the grid "
                              "(image replaced?)")
                kind = "position"
            flags.append({"index": int(obs.index[i]), "kind": kind, "message": reasons[i], "round": round_no + 1})
        outlier |= new
        if outlier[ref]:
            ref = int(np.flatnonzero(usable & ~outlier)[0])
            state.xy = state.xy - state.xy[ref]
        if (usable & ~outlier).sum() < 3:
            raise DegenerateGeometryError(f"{obs.source}: fewer than 3 views are left after removing outliers")

    used = usable & ~outlier
    mask = mask_all & used[:, None]
    free = used & (np.arange(obs.K) != ref)
    if detect_outliers and new.any():  # the last round flagged views: solve once more without them
        res = solve_planar(state, X, obs.corners_px, mask, free, robust=robust, cancel=cancel)
        state = res.state
    others = usable & ~used
    if others.any():
        sub = state.copy()
        sub.xy = state.xy[others]
        state.xy[others] = planar_positions_only(sub, X, obs.corners_px[others], mask_all[others])
    progress(3, 4, "uncertainty")
    state = _regauge(state, ref)
    state, angle = _align_to_x_motion(state, obs.target_mm, obs.approach, used)
    inv, sigma2 = _inverse(state, X, obs.corners_px, mask, free, used)
    eq, _ = linearize_planar(state, X, obs.corners_px, mask)
    n_params = N_PLANAR_SHARED + 2 * int(free.sum())
    est = PlanarEstimate(
        method=method, state=state, reference_view=ref, usable=usable, used=used, outlier=outlier,
        outlier_reason=reasons, sigma_px=float(np.sqrt(sigma2)), cov_xy_mm2=sigma2 * inv.cov_view(),
        rms_px=_view_rms(state, X, obs.corners_px, mask_all), n_corners=mask_all.sum(axis=1),
        iterations=res.iterations, converged=res.converged, n_observations=eq.n_obs, dof=eq.n_obs - n_params,
        flags=flags, timings_s=timings, inverse=inv,
    )
    est.fit = planar_fit(est, obs.target_mm, obs.approach)
    timings["total"] = time.perf_counter() - t_start
    progress(4, 4, "done")
    return est


# ----------------------------------------------------------------------------- steps


def _view_rms(state: PlanarState, X: np.ndarray, corners: np.ndarray, mask: np.ndarray) -> np.ndarray:
    r = planar_residuals(state, X, corners, mask)
    n = mask.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n > 0, np.sqrt(np.sum(r * r, axis=(1, 2)) / np.maximum(n, 1)), np.nan)


def _inverse(state: PlanarState, X: np.ndarray, corners: np.ndarray, mask: np.ndarray, free: np.ndarray,
             used: np.ndarray) -> tuple[BlockArrowheadInverse, float]:
    eq, _ = linearize_planar(state, X, corners, mask)
    sigma2 = noise_variance(eq.ssr, eq.n_obs, N_PLANAR_SHARED + 2 * int(free.sum()))
    return block_arrowhead_inverse(eq.A, eq.B, eq.D, free), sigma2


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


def planar_fit(est: PlanarEstimate, target_mm: np.ndarray, approach: np.ndarray) -> PlanarFit:
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


def _per_view_result(obs: PlanarObservations, state: PlanarState, R_v: np.ndarray, t_v: np.ndarray,
                     usable: np.ndarray, ref: int, X: np.ndarray, mask_all: np.ndarray,
                     timings: dict[str, float], t_start: float) -> PlanarEstimate:
    """The PnP baseline: every view's own translation projected on the initial plane."""
    from lps_gui.core.camera_model import project_board

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
    est = PlanarEstimate("pnp", state, ref, usable, usable.copy(), np.zeros(K, bool), [""] * K,
                         float(np.sqrt(sigma2)), cov, rms, n, 0, True, n_obs, n_obs - 6 * int(usable.sum()), [],
                         timings, None)
    est.fit = planar_fit(est, obs.target_mm, obs.approach)
    return est


def affine_motion(xy: np.ndarray, target_mm: np.ndarray, approach: np.ndarray, used: np.ndarray) -> np.ndarray:
    """G (2x2) of the least-squares fit xy = offset + G target (+ backlash offsets): columns +X, +Y motion."""
    _, coef = _affine_coefficients(xy, target_mm, approach, used)
    return coef[1:3].T


def planar_truth_in_stage_frame(true_xy_mm: np.ndarray, target_mm: np.ndarray, approach: np.ndarray,
                                used: np.ndarray, ref: int) -> np.ndarray:
    """True positions under the estimate's own frame convention (zero at ``ref``, +x along the
    fitted +X motion, +Y motion on the +y side), so they compare with ``PlanarEstimate.state.xy``."""
    xy = np.asarray(true_xy_mm, dtype=float) - true_xy_mm[ref]
    G = affine_motion(xy, target_mm, approach, used)
    angle = float(np.arctan2(G[1, 0], G[0, 0]))
    c, s = np.cos(angle), np.sin(angle)
    out = xy @ np.array([[c, -s], [s, c]])
    if np.linalg.det(G) < 0:
        out[:, 1] *= -1.0
    return out
