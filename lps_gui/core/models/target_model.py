"""Positions along the whole travel against a row or constellation of targets (SPEC 13).

x_cam = R (Q_j X + p_j) + l0 + N s_i: one camera orientation R, the motion frame
N (3 x D; D = 1 line, 2 plane), each stop's coordinates s_i (D,), and the
mounting pose (Q_j, p_j) of every target but the first (the world frame).
Known intrinsics. Gauss-Newton (Levenberg-Marquardt damped) on the block
arrowhead: 8 shared columns (R 3, l0 3, the tilt of N 2) plus 6 per target,
and D per view; the per-view D x D blocks are eliminated by a Schur complement,
so a step costs O(corners) plus one (8 + 6 (T - 1))^2 solve.

Gauges: s of the reference view is 0 (SPEC 5: positions relative to the
reference capture); N turns only out of its own span (D = 1: the two tilts of n;
D = 2: the tilts of the plane), the rotation within the plane is fixed
afterwards so that x runs along the fitted X motion (SPEC 10).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics, intrinsics_rows, project_parts
from lps_gui.core.geometry.pnp import solve_pnp
from lps_gui.core.geometry.rotation import chordal_mean, exp_so3
from lps_gui.core.geometry.target_chain import chain_targets
from lps_gui.core.geometry.target_rig import TargetLayout
from lps_gui.core.geometry.targets import Target
from lps_gui.core.numerics.target_arrowhead import (
    Linearization,
    PositionCovariance,
    levenberg_marquardt,
    project_residuals,
    retract_targets,
    view_covariances,
    view_rms,
)
from lps_gui.errors import DegenerateGeometryError

N_COMMON = 8  # R (3), l0 (3), tilt of the motion frame (2)
N_INTRINSICS = 9  # after them when self-calibrating (SPEC 4.6)
MIN_CORNERS = 6


def row_parameter_count(n_targets: int, bows: bool, n_used_views: int, D: int = 1) -> int:
    """Unknowns of the row model: the common frame (N_COMMON), each target's bow (2) when estimated, every
    target's pose but the first's (6), each used view's position but the reference's (D): its dof's count."""
    return N_COMMON + (2 * n_targets if bows else 0) + 6 * (n_targets - 1) + D * (n_used_views - 1)


@dataclass
class TargetObservations:
    """Corners of K views of T targets, laid end to end (see io/corners/target_vnl)."""

    targets: list[Target]
    corners_px: np.ndarray  # (K, N, 2), NaN where not seen
    targets_mm: np.ndarray  # (K, D) commanded stage coordinates
    names: list[str]

    @property
    def own_points(self) -> np.ndarray:
        return np.concatenate([t.board.object_points() for t in self.targets])

    @property
    def which(self) -> np.ndarray:
        return np.repeat(np.arange(len(self.targets)), [t.board.n_corners for t in self.targets])

    @property
    def bow_basis(self) -> np.ndarray:
        """(N, 2): d z / d (bow_x, bow_y) of every corner in its own target's frame (Board.warp_basis)."""
        return np.concatenate([t.board.warp_basis(t.board.flat_points()) for t in self.targets])


def with_bows(targets: list[Target], bows: np.ndarray | None) -> list[Target]:
    """The targets with their estimated bows (T, 2) added to their boards' warp (None: as they are)."""
    if bows is None:
        return list(targets)
    return [replace(t, board=replace(t.board, warp_mm=tuple((np.asarray(t.board.warp_mm or (0.0, 0.0)) + b).tolist())))
            for t, b in zip(targets, np.asarray(bows, float))]


def bowed(X: np.ndarray, basis: np.ndarray, bows: np.ndarray, tj: np.ndarray) -> np.ndarray:
    """Corners ``X`` (M, 3) in their targets' frames, moved along the target normal by the targets' bows (T, 2)."""
    out = X.copy()
    out[:, 2] += np.einsum("mb,mb->m", basis, bows[tj])
    return out


def bow_columns(dP: np.ndarray, R_normal: np.ndarray, basis: np.ndarray, tj: np.ndarray, T: int) -> np.ndarray:
    """d uv / d (every target's bow_x, bow_y), (M, 2, 2 T): ``R_normal`` (M, 3) each corner's target normal in
    the camera frame. Why estimated: a print bowed 0.1 mm (as real prints are) shifts a near target's pose by
    3-10 sigma, and no other parameter can take it (issue 35)."""
    J = np.zeros((len(dP), 2, 2 * T))
    d = np.einsum("mai,mi->ma", dP, R_normal)
    rows = np.arange(len(dP))
    for b in range(2):
        J[rows, :, 2 * tj + b] = d * basis[:, b:b + 1]
    return J


@dataclass
class TargetSolution:
    R: np.ndarray  # (3, 3) camera from world
    l0: np.ndarray  # (3,) mm
    N: np.ndarray  # (3, D) motion directions in the camera frame
    s: np.ndarray  # (K, D) mm, NaN for views without a target; 0 at the reference view
    Q: np.ndarray  # (T, 3, 3)
    p: np.ndarray  # (T, 3) mm
    sigma_s: np.ndarray  # (K, D) mm, corner noise at sigma_px, relative to the reference view
    sigma_centred: np.ndarray  # (K, D) mm: of s_i minus the mean over the used views (no reference noise)
    target_sigma: np.ndarray  # (T, 6): rotation (rad, left perturbation) and p (mm); zero for target 0
    sigma_px: float  # a-posteriori corner noise
    rms_px: np.ndarray  # (K,)
    used: np.ndarray  # (K,) bool
    reference: int
    ties: np.ndarray  # (T, T) views seeing both
    iterations: int
    converged: bool
    covariance: "PositionCovariance"
    intrinsics_gradient: np.ndarray | None = None  # (K, D, 9): d s / d intrinsics (reported coordinates), when
    # the intrinsics have a covariance to propagate
    intrinsics_estimated: CameraIntrinsics | None = None  # self-calibration: the intrinsics at the solution
    bows_mm: np.ndarray | None = None  # (T, 2): each target's estimated bow (bow_x, bow_y), when free

    def planar_axes(self, targets_mm: np.ndarray) -> dict[str, float]:
        """Scales of X and Y (ppm) and the squareness of Y to X (urad), with sigmas (SPEC 10 names).

        From the least-squares fit s_i ~ c + (targets_i) A over the used views; squareness is the
        angle between the +X and +Y motion directions minus 90 degrees. Linear in the positions to
        first order, so each sigma is that functional's variance under the full covariance.
        """
        used = self.used
        X = targets_mm[used] - targets_mm[used].mean(axis=0)
        L = np.linalg.solve(X.T @ X, X.T)  # (2, n): A = L s
        A = L @ self.s[used]
        (a, e), (b, c) = A
        g = np.zeros((4, len(self.s), 2))
        rows = np.flatnonzero(used)
        g[0, rows, 0] = L[0] * a / np.hypot(a, e)  # |A0|
        g[0, rows, 1] = L[0] * e / np.hypot(a, e)
        g[1, rows, 0] = L[1] * b / np.hypot(b, c)  # |A1|
        g[1, rows, 1] = L[1] * c / np.hypot(b, c)
        # squareness = atan2(c, b) - atan2(e, a) - pi/2
        g[2, rows, 0] = L[1] * (-c / (b * b + c * c)) - L[0] * (-e / (a * a + e * e))
        g[2, rows, 1] = L[1] * (b / (b * b + c * c)) - L[0] * (a / (a * a + e * e))
        sig = [np.sqrt(self.covariance.variance(g[k])) for k in range(3)]
        squareness = np.arctan2(c, b) - np.arctan2(e, a) - np.pi / 2
        return {"scale_x_ppm": (np.hypot(a, e) - 1) * 1e6, "scale_x_sigma_ppm": sig[0] * 1e6,
                "scale_y_ppm": (np.hypot(b, c) - 1) * 1e6, "scale_y_sigma_ppm": sig[1] * 1e6,
                "squareness_urad": squareness * 1e6, "squareness_sigma_urad": sig[2] * 1e6}


# ----------------------------------------------------------------------------- initialization


def _frame(A: np.ndarray) -> np.ndarray:
    """A rotation whose first D columns span the columns of A (3, D) in order (Gram-Schmidt), det +1."""
    D = A.shape[1]
    c0 = A[:, 0] / np.linalg.norm(A[:, 0])
    if D == 1:
        helper = np.eye(3)[int(np.argmin(np.abs(c0)))]
        c1 = np.cross(c0, helper)
        c1 /= np.linalg.norm(c1)
    else:
        c1 = A[:, 1] - (A[:, 1] @ c0) * c0
        c1 /= np.linalg.norm(c1)
    return np.stack([c0, c1, np.cross(c0, c1)], axis=1)


def target_views(obs: TargetObservations, intrinsics: CameraIntrinsics) -> dict:
    """Each view's PnP pose of each target it sees, and the targets chained from target 0 (Q, p, ties)."""
    own, which = obs.own_points, obs.which
    K, T = len(obs.names), len(obs.targets)
    Rv = np.tile(np.eye(3), (K, T, 1, 1))
    tv = np.zeros((K, T, 3))
    ok = np.zeros((K, T), bool)
    for j in range(T):
        sel = which == j
        R_j, t_j, ok_j = solve_pnp(own[sel], obs.corners_px[:, sel], intrinsics, refine=False)
        Rv[:, j], tv[:, j], ok[:, j] = R_j, t_j, ok_j
    Q, p, ties = chain_targets(Rv, tv, ok, [t.id for t in obs.targets], obs.names)
    used = ok.any(axis=1)
    if used.sum() < 3:
        raise DegenerateGeometryError(f"only {used.sum()} views see a target; the motion needs at least 3")
    R_world = np.einsum("ktij,tlj->ktil", Rv, Q)  # R_cam_j Q_j^T: camera from world, per target
    return {"Rv": Rv, "tv": tv, "ok": ok, "Q": Q, "p": p, "ties": ties, "used": used, "R_world": R_world}


def origin_in_camera(tv: np.ndarray, ok: np.ndarray, p: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Each view's translation (K, 3) under orientations R (K, 3, 3): the mean over its seen targets of t_cj - R p_j."""
    t = np.zeros((len(tv), 3))
    for i in np.flatnonzero(ok.any(axis=1)):
        t[i] = np.mean(tv[i, ok[i]] - p[ok[i]] @ R[i].T, axis=0)
    return t


def initial_solution(obs: TargetObservations, intrinsics: CameraIntrinsics) -> dict:
    """R, l0, frame F, s, Q, p from per-view PnP of every seen target, chained from target 0."""
    views = target_views(obs, intrinsics)
    K = len(obs.names)
    tv, ok, Q, p, ties, used = (views[k] for k in ("tv", "ok", "Q", "p", "ties", "used"))
    R = chordal_mean(views["R_world"][ok])
    t = origin_in_camera(tv, ok, p, np.broadcast_to(R, (K, 3, 3)))
    ref = int(np.flatnonzero(used)[0])
    dt = t[used] - t[ref]
    dx = obs.targets_mm[used] - obs.targets_mm[ref]
    A, *_ = np.linalg.lstsq(dx, dt, rcond=None)  # dt ~ dx A: A (D, 3)
    if np.linalg.matrix_rank(dx) < dx.shape[1]:
        raise DegenerateGeometryError("the stops do not span the plan's axes; the motion directions are undetermined")
    F = _frame(A.T)
    D = obs.targets_mm.shape[1]
    s = np.full((K, D), np.nan)
    s[used] = (t[used] - t[ref]) @ F[:, :D]
    return {"R": R, "l0": t[ref].copy(), "F": F, "s": s, "Q": Q, "p": p, "ties": ties, "used": used, "ref": ref}


# ----------------------------------------------------------------------------- linearization


def _camera_points(state: dict, X: np.ndarray, tj: np.ndarray, view: np.ndarray, D: int):
    """Every corner in the camera frame P (M, 3), with the parts its Jacobian needs (Q X, R X_w, N s)."""
    R, l0, F, s, Q, p = state["R"], state["l0"], state["F"], state["s"], state["Q"], state["p"]
    QX = np.einsum("mij,mj->mi", Q[tj], X)
    ts = s[view] @ F[:, :D].T  # (M, 3)
    RXw = (QX + p[tj]) @ R.T
    return RXw + l0 + ts, QX, RXw, ts


def _linearize(state: dict, X: np.ndarray, tj: np.ndarray, view: np.ndarray, uv: np.ndarray,
               intrinsics: CameraIntrinsics, D: int, want_jacobian: bool = True,
               bow_basis: np.ndarray | None = None) -> Linearization:
    R, F = state["R"], state["F"]
    N = F[:, :D]
    free_intrinsics = "I" in state  # self-calibration: the 9 intrinsics are shared columns after the 8
    if free_intrinsics:
        intrinsics = intrinsics.with_vector(state["I"])
    if bow_basis is not None:  # the targets' bows: 2 shared columns per target after the intrinsics
        X = bowed(X, bow_basis, state["w"], tj)
    P, QX, RXw, ts = _camera_points(state, X, tj, view, D)
    cost, r, dP = project_residuals(P, uv, intrinsics, want_jacobian)
    if dP is None:
        return Linearization(cost, r, None, None, None)  # type: ignore[arg-type]
    B = F[:, 1:3] if D == 1 else F[:, 0:2]  # axes N may turn about
    Jc = np.empty((len(P), 2, N_COMMON))
    # a row a times -[v]x is -(a x v): the rotation columns as cross products
    Jc[:, :, 0:3] = -np.cross(dP, RXw[:, None, :])
    Jc[:, :, 3:6] = dP
    Jc[:, :, 6:8] = -np.cross(dP, ts[:, None, :]) @ B
    dPR = dP @ R  # d uv / d X_w
    Jt = np.empty((len(P), 2, 6))
    Jt[:, :, 0:3] = -np.cross(dPR, QX[:, None, :])
    Jt[:, :, 3:6] = dPR
    Jt[tj == 0] = 0.0
    Jv = dP @ N
    if free_intrinsics:
        du, dv = intrinsics_rows(project_parts(P[:, 0], P[:, 1], P[:, 2], intrinsics), intrinsics)
        Jc = np.concatenate([Jc, np.stack([du.T, dv.T], axis=1)], axis=2)
    if bow_basis is not None:
        normal = np.einsum("ij,mj->mi", R, state["Q"][tj][:, :, 2])  # each corner's target normal, camera frame
        Jc = np.concatenate([Jc, bow_columns(dP, normal, bow_basis, tj, len(state["Q"]))], axis=2)
    return Linearization(cost, r, Jc, Jt, Jv)


def _retract(state: dict, dg: np.ndarray, dv: np.ndarray, D: int, T: int) -> dict:
    F = state["F"]
    B = F[:, 1:3] if D == 1 else F[:, 0:2]
    new = dict(state)
    new["R"] = exp_so3(dg[0:3]) @ state["R"]
    new["l0"] = state["l0"] + dg[3:6]
    new["F"] = exp_so3(B @ dg[6:8]) @ F
    new["s"] = state["s"] + dv
    C = N_COMMON
    if "I" in state:
        new["I"] = state["I"] + dg[C: C + N_INTRINSICS]
        C += N_INTRINSICS
    if "w" in state:
        new["w"] = state["w"] + dg[C: C + 2 * T].reshape(T, 2)
        C += 2 * T
    new["Q"], new["p"] = retract_targets(state["Q"], state["p"], dg[C:])
    return new


# ----------------------------------------------------------------------------- solve


def solve_targets(
    obs: TargetObservations, intrinsics: CameraIntrinsics, max_iterations: int = 50, tolerance: float = 1e-10,
    progress=None, noise_px: float | None = None, intrinsics_prior: tuple[np.ndarray, np.ndarray] | None = None,
    bows: bool = False,
) -> TargetSolution:
    """Positions of every stop and the targets' poses, jointly; sigmas from (J^T J)^-1 at the solution.

    ``bows``: every target's bow (Board.warp_mm's two terms) is free too, from the targets' nominal
    warp (:func:`bow_columns`).

    ``noise_px``: the corner noise to scale the sigmas with (a planner's noise-free views); None takes
    the a-posteriori noise of the fit. ``intrinsics_prior`` (I0, Sigma_I): the intrinsics are free with
    their calibration as a Gaussian prior (SPEC 4.6), nine shared columns; the prior enters as nine
    residuals L^T (I - I0) (L L^T = Sigma_I^-1) on the reference view, so the sigmas include it.
    """
    state = initial_solution(obs, intrinsics)
    K, T, D = len(obs.names), len(obs.targets), obs.targets_mm.shape[1]
    used, ref = state["used"], state["ref"]
    state["s"] = np.where(used[:, None], state["s"], 0.0)
    seen = np.isfinite(obs.corners_px[..., 0]) & used[:, None]
    view, corner = np.nonzero(seen)
    X, tj, uv = obs.own_points[corner], obs.which[corner], obs.corners_px[view, corner]
    free_view = used.copy()
    free_view[ref] = False
    M = len(view)
    basis = obs.bow_basis[corner] if bows else None
    n_bows = 2 * T if bows else 0
    if bows:
        state["w"] = np.zeros((T, 2))
    linearize = lambda st, jac=True: _linearize(st, X, tj, view, uv, intrinsics, D, jac, basis)  # noqa: E731
    tj_all, view_all = tj, view
    if intrinsics_prior is not None:
        # the prior weighs against corners of the fit's noise (MAP: |r|^2 + sigma^2 dI' Sigma^-1 dI), so the fit
        # with the intrinsics held comes first and gives sigma; the covariance is then the posterior's
        held = levenberg_marquardt(state, linearize, lambda st, dg, dv: _retract(st, dg, dv, D, T), tj, view, K, T,
                                   free_view, max_iterations, tolerance, progress, "target model")
        dof_held = max(2 * M - (N_COMMON + n_bows + 6 * (T - 1) + D * int(free_view.sum())), 1)
        state = dict(held.state, I=np.asarray(intrinsics_prior[0], float).copy())
        linearize = _with_prior(linearize, intrinsics_prior, D, np.sqrt(held.lin.cost / dof_held))
        tj_all, view_all = np.r_[tj, np.zeros(PRIOR_ROWS, int)], np.r_[view, np.full(PRIOR_ROWS, ref)]
    fit = levenberg_marquardt(state, linearize, lambda st, dg, dv: _retract(st, dg, dv, D, T), tj_all, view_all, K, T,
                              free_view, max_iterations, tolerance, progress, "target model")
    state, lin, it, converged = fit.state, fit.lin, fit.iterations, fit.converged
    C = N_COMMON + (N_INTRINSICS if "I" in state else 0) + n_bows
    n_params = N_COMMON + n_bows + 6 * (T - 1) + D * int(free_view.sum())
    dof = max(2 * M - n_params, 1)
    sigma2 = float(np.sum(lin.r[:M] ** 2)) / dof if noise_px is None else float(noise_px) ** 2
    S_inv, W, Avv_inv = fit.S_inv, fit.W, fit.Avv_inv
    cov_s, cov_c = view_covariances(Avv_inv, W, S_inv, free_view, used)
    cov_s, cov_c = cov_s * sigma2, cov_c * sigma2
    target_sigma = np.zeros((T, 6))
    if T > 1:
        target_sigma[1:] = np.sqrt(np.maximum(np.diag(S_inv)[C:], 0.0) * sigma2).reshape(T - 1, 6)
    rms = view_rms(lin.r[:M], view, K)
    s_solver = s = np.where(used[:, None], state["s"], np.nan)
    F = state["F"]
    N = F[:, :D]
    turn = np.eye(D)
    if D == 2:
        G = turn = _x_along_motion(s, obs.targets_mm, used, ref)
        N, s = N @ G, s @ G
        cov_s, cov_c = (np.einsum("dx,kde,ey->kxy", G, c, G) for c in (cov_s, cov_c))
    sigma_s, sigma_c = (np.sqrt(np.maximum(np.einsum("kdd->kd", c), 0.0)) for c in (cov_s, cov_c))
    sigma_s[~used] = sigma_c[~used] = np.nan
    gradient = None
    if intrinsics.covariance is not None and "I" not in state:  # free intrinsics are in the covariance already
        Xb = bowed(X, basis, state["w"], tj) if bows else X
        grad, target_grad = _intrinsics_gradient(state, fit, Xb, tj, view, intrinsics, D, free_view, C)
        target_sigma = with_intrinsics_term(target_sigma, target_grad, intrinsics.covariance)
        gradient = np.einsum("de,kdi->kei", turn, grad)  # reported coordinates: v turn
        if D == 2:  # the turn follows the positions: its change enters every position
            gradient += _turn_change(s_solver, obs.targets_mm, used, ref, turn, grad)
    return TargetSolution(state["R"], state["l0"], N, s, state["Q"], state["p"], sigma_s, sigma_c, target_sigma,
                          float(np.sqrt(sigma2)), rms, used, ref, state["ties"], it, converged,
                          PositionCovariance(Avv_inv * free_view[:, None, None], W * free_view[:, None, None],
                                             S_inv, sigma2, turn), gradient,
                          intrinsics.with_vector(state["I"]) if "I" in state else None, state.get("w"))


def _intrinsics_gradient(state: dict, fit, X: np.ndarray, tj: np.ndarray, view: np.ndarray,
                         intrinsics: CameraIntrinsics, D: int, free_view: np.ndarray, C: int = N_COMMON
                         ) -> tuple[np.ndarray, np.ndarray]:
    """d s / d intrinsics (K, D, 9) in the solver's coordinates and d (target poses) / d intrinsics
    (6 (T - 1), 9), from :func:`intrinsics_sensitivity`."""
    P, *_ = _camera_points(state, X, tj, view, D)
    du, dv = intrinsics_rows(project_parts(P[:, 0], P[:, 1], P[:, 2], intrinsics), intrinsics)
    shared, per_view = intrinsics_sensitivity(fit, np.stack([du.T, dv.T], axis=1), tj, view, free_view)
    return per_view, shared[C:]


def intrinsics_sensitivity(fit, JI: np.ndarray, tj: np.ndarray, view: np.ndarray,
                           free_view: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """d (shared columns) / d intrinsics (G, 9) and d (view columns) / d intrinsics (K, D, 9): -H^-1 J^T J_I
    by the fit's Schur complement, ``JI`` (M, 2, 9) the corners' d uv / d intrinsics.

    With W_k = A_gv,k A_vv,k^-1: y_g = S^-1 (C_g - sum_k W_k C_v,k), y_v,k = A_vv,k^-1 C_v,k - W_k^T y_g.
    Why the shared part too: a target's pose at another depth or scale moves with the focal length and
    the principal point (SPEC 14's two depths), which the corners' noise alone does not show.
    """
    lin = fit.lin
    K, C = len(free_view), lin.Jc.shape[2]
    T = (fit.S_inv.shape[0] - C) // 6 + 1  # the shared columns: C common, then 6 per target but the first
    C_g = np.zeros((C + 6 * (T - 1), JI.shape[2]))
    C_g[:C] = np.einsum("mac,mai->ci", lin.Jc, JI)
    for j in range(1, T):
        on = tj == j
        C_g[C + 6 * (j - 1): C + 6 * j] = np.einsum("mac,mai->ci", lin.Jt[on], JI[on])
    C_v = np.zeros((K, lin.Jv.shape[2], JI.shape[2]))
    np.add.at(C_v, view, np.einsum("map,mai->mpi", lin.Jv * free_view[view][:, None, None], JI))
    y_g = fit.S_inv @ (C_g - np.einsum("kgp,kpi->gi", fit.W, C_v))
    y_v = np.einsum("kpq,kqi->kpi", fit.Avv_inv, C_v) - np.einsum("kgp,gi->kpi", fit.W, y_g)
    return -y_g, -y_v * free_view[:, None, None]


def with_intrinsics_term(target_sigma: np.ndarray, gradient: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """(T, 6) target sigmas with the held intrinsics' covariance propagated through ``gradient``
    (6 (T - 1), 9): the term is common to every stop, so it does not average out (issue 35)."""
    out = np.asarray(target_sigma, float).copy()
    if len(out) > 1:
        var = np.einsum("gi,ij,gj->g", gradient, covariance, gradient).reshape(len(out) - 1, 6)
        out[1:] = np.sqrt(out[1:] ** 2 + np.maximum(var, 0.0))
    return out


PRIOR_ROWS = 5  # pseudo-corners carrying the nine prior residuals (and one zero)


def _with_prior(linearize, prior: tuple[np.ndarray, np.ndarray], D: int, sigma_px: float):
    """The linearization with the intrinsics' prior appended as PRIOR_ROWS pseudo-corners of target 0, in
    units of the corners' noise ``sigma_px``."""
    I0, cov = np.asarray(prior[0], float), np.asarray(prior[1], float)
    Lt = sigma_px * np.linalg.cholesky(np.linalg.inv(cov)).T  # |L^T d|^2 = sigma^2 d^T Sigma^-1 d
    J_prior = np.zeros((2 * PRIOR_ROWS, N_COMMON + N_INTRINSICS))
    J_prior[:N_INTRINSICS, N_COMMON:] = Lt

    def augmented(state: dict, jac: bool = True) -> Linearization:
        lin = linearize(state, jac)
        rp = np.zeros(2 * PRIOR_ROWS)
        rp[:N_INTRINSICS] = Lt @ (state["I"] - I0)
        r = np.concatenate([lin.r, rp.reshape(PRIOR_ROWS, 2)])
        cost = lin.cost + float(rp @ rp)
        if lin.Jc is None:
            return Linearization(cost, r, None, None, None)  # type: ignore[arg-type]
        pad = np.zeros((2 * PRIOR_ROWS, lin.Jc.shape[2] - J_prior.shape[1]))  # the bows' columns after them
        Jc = np.concatenate([lin.Jc, np.concatenate([J_prior, pad], axis=1).reshape(PRIOR_ROWS, 2, -1)])
        Jt = np.concatenate([lin.Jt, np.zeros((PRIOR_ROWS, 2, 6))])
        Jv = np.concatenate([lin.Jv, np.zeros((PRIOR_ROWS, 2, D))])
        return Linearization(cost, r, Jc, Jt, Jv)

    return augmented


def _turn_change(s: np.ndarray, targets_mm: np.ndarray, used: np.ndarray, ref: int, turn: np.ndarray,
                 ds: np.ndarray) -> np.ndarray:
    """s dG/dtheta dtheta of :func:`_x_along_motion`'s turn G for position changes ``ds`` (K, 2, m), (K, 2, m)."""
    dx = targets_mm[used] - targets_mm[ref]
    L = np.linalg.pinv(dx)[0]  # row 0 of A = pinv(dx) (s_used - s_ref): where +X moves
    a = L @ (s[used] - s[ref])
    da = np.einsum("n,ndm->dm", L, ds[used] - ds[ref])  # (2, m)
    dtheta = (a[0] * da[1] - a[1] * da[0]) / (a @ a)
    c, sn = turn[0, 0], turn[1, 0]
    dG = np.array([[-sn, -c], [c, -sn]])
    return np.where(used[:, None], np.nan_to_num(s) @ dG, 0.0)[:, :, None] * dtheta[None, None, :]


def _x_along_motion(s: np.ndarray, targets_mm: np.ndarray, used: np.ndarray, ref: int) -> np.ndarray:
    """The 2 x 2 rotation whose columns are the new x (along the fitted X motion, SPEC 10) and y."""
    dx = targets_mm[used] - targets_mm[ref]
    A, *_ = np.linalg.lstsq(dx, s[used] - s[ref], rcond=None)  # s ~ dx A: row 0 is where +X moves
    a = A[0] / np.linalg.norm(A[0])
    return np.array([[a[0], -a[1]], [a[1], a[0]]])
