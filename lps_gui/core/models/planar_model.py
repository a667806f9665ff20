"""The planar (XY) LPS model of SPEC section 10, solved jointly.

A camera on an XY gantry keeps a constant orientation R and moves in a plane:
``t_i = l0 + x_i n_x + y_i n_y`` (camera frame; n_x, n_y orthonormal, the
first two columns of a rotation P). Unknowns: R (3), l0 (3), the plane's
orientation (2: tilts of P about n_x and n_y; a rotation about the plane
normal only relabels x and y and is fixed afterwards by the X motion
direction), and (x_i, y_i) of every view but the gauge view. Every view's
residuals depend on the 8 shared parameters and its own two coordinates: a
block arrowhead (b = 2), eliminated by :mod:`lps_gui.core.numerics.arrowhead`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics, intrinsics_rows, project_parts
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.models.joint_lm import camera_points, huber_threshold, huber_weights, pose_residuals, robust_cost
from lps_gui.core.numerics.arrowhead import ArrowheadInverse, arrowhead_inverse, schur_step
from lps_gui.core.progress import CancelToken

N_PLANAR_SHARED = 8  # rotation 3, l0 3, plane tilt 2
N_PLANAR_PER_VIEW = 2


@dataclass
class PlanarState:
    """Current estimate; xy relative to the gauge view (mm, plane coordinates)."""

    R: np.ndarray  # shape (3, 3) R_cam_board
    l0: np.ndarray  # shape (3,) mm: t at (x, y) = 0
    P: np.ndarray  # shape (3, 3) rotation: columns n_x, n_y, n_z (camera frame)
    xy: np.ndarray  # shape (K, 2) mm
    intrinsics: CameraIntrinsics

    @property
    def positions(self) -> np.ndarray:
        """The views' positions as an estimate reports them, shape (K, 2)."""
        return self.xy

    @property
    def basis(self) -> np.ndarray:
        """(n_x, n_y) as columns, shape (3, 2)."""
        return self.P[:, :2]

    def translations(self) -> np.ndarray:
        """t_i, shape (K, 3)."""
        return self.l0[None, :] + self.xy @ self.basis.T

    def copy(self) -> "PlanarState":
        return PlanarState(self.R.copy(), self.l0.copy(), self.P.copy(), self.xy.copy(), self.intrinsics)

    def regauged(self, ref: int) -> "PlanarState":
        """Zero at view ``ref``: l0 moves to it, every position shifts (the translations stay)."""
        out = self.copy()
        out.l0 = self.l0 + self.basis @ self.xy[ref]
        out.xy = self.xy - self.xy[ref]
        return out

    def motion_axes_board(self) -> np.ndarray:
        """Camera-centre motion directions of +x and +y in the board frame, shape (3, 2).

        C_i = -R^T t_i, so moving by +x_i moves the camera centre by -R^T n_x.
        """
        return -self.R.T @ self.basis

    def rotated_in_plane(self, angle_rad: float) -> "PlanarState":
        """The same geometry with x, y relabelled by a rotation of ``angle_rad`` in the plane.

        New basis columns are the old ones turned by the angle, and xy turned
        back, so every t_i is unchanged.
        """
        c, s = np.cos(angle_rad), np.sin(angle_rad)
        rot = np.array([[c, -s], [s, c]])
        P = self.P.copy()
        P[:, :2] = self.basis @ rot
        return PlanarState(self.R.copy(), self.l0.copy(), P, self.xy @ rot, self.intrinsics)


def _camera_points(state: PlanarState, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return camera_points(state.R, state.translations(), X)


def planar_residuals(state: PlanarState, X: np.ndarray, corners: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Reprojection residuals uv - measured, shape (K, N, 2); zero where not used."""
    return pose_residuals(state.R, state.translations(), X, state.intrinsics, corners, mask)


@dataclass
class PlanarEquations:
    """Blocks of J^T W J and J^T W r at one linearization point."""

    A: np.ndarray  # shape (p, p): p = 8, or 17 with the intrinsics after the 8 shared parameters
    B: np.ndarray  # shape (K, 2, p)
    D: np.ndarray  # shape (K, 2, 2)
    g_theta: np.ndarray  # shape (p,)
    g_s: np.ndarray  # shape (K, 2)
    cost: float
    ssr: float
    n_obs: int
    weights: np.ndarray  # shape (K, N)


def planar_jacobians(state: PlanarState, X: np.ndarray, with_intrinsics: bool = False
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """Projection and Jacobians of the planar model at ``state``.

    Returns uv shape (2, K, N), J_theta shape (8, 2, K, N) (left-perturbed
    rotation, l0, plane tilts about n_x and n_y), J_s shape (2, 2, K, N)
    (d uv / d x_i and d uv / d y_i) and, when asked, J_I shape (9, 2, K, N)
    (d uv / d intrinsics, :data:`~lps_gui.core.geometry.camera_model.INTRINSIC_NAMES`).
    """
    x, y, z = _camera_points(state, X)
    parts = project_parts(x, y, z, state.intrinsics, want_jacobian=True)
    J_I = np.stack(intrinsics_rows(parts, state.intrinsics), axis=1) if with_intrinsics else None
    Px = np.stack([parts.du[0], parts.dv[0]])  # shape (2, K, N)
    Py = np.stack([parts.du[1], parts.dv[1]])
    Pz = np.stack([parts.du[2], parts.dv[2]])

    def P_dot(v: np.ndarray) -> np.ndarray:
        return Px * v[0] + Py * v[1] + Pz * v[2]

    RX = X @ state.R.T
    K, N = state.xy.shape[0], X.shape[0]
    J = np.empty((N_PLANAR_SHARED, 2, K, N))
    a, b, c = RX[None, None, :, 0], RX[None, None, :, 1], RX[None, None, :, 2]
    J[0] = b * Pz - c * Py
    J[1] = c * Px - a * Pz
    J[2] = a * Py - b * Px
    J[3], J[4], J[5] = Px, Py, Pz
    # P <- exp(alpha n_x + beta n_y) P: n_x moves by -beta n_z, n_y by +alpha n_z
    Pn_z = P_dot(state.P[:, 2])
    J[6] = state.xy[None, :, 1, None] * Pn_z
    J[7] = -state.xy[None, :, 0, None] * Pn_z
    Js = np.stack([P_dot(state.P[:, 0]), P_dot(state.P[:, 1])])
    uv = np.stack([parts.u, parts.v])
    return uv, J, Js, J_I


def linearize_planar(
    state: PlanarState, X: np.ndarray, corners: np.ndarray, mask: np.ndarray, huber_c: float | None = None,
    with_intrinsics: bool = False,
) -> tuple[PlanarEquations, np.ndarray]:
    """Normal-equation blocks at ``state`` and the residuals (K, N, 2); ``with_intrinsics`` puts the 9
    intrinsics after the 8 shared parameters (self-calibration, or propagating their covariance)."""
    uv, J, Js, J_I = planar_jacobians(state, X, with_intrinsics)
    if J_I is not None:
        J = np.concatenate([J, J_I])
    m = np.nan_to_num(corners)
    r = np.empty_like(uv)  # shape (2, K, N)
    r[0] = np.where(mask, uv[0] - m[..., 0], 0.0)
    r[1] = np.where(mask, uv[1] - m[..., 1], 0.0)
    r_kn2 = np.moveaxis(r, 0, -1)
    weights = huber_weights(r_kn2, mask, huber_c)
    w = weights[None]  # shape (1, K, N)
    p = J.shape[0]
    Jf = J.reshape(p, -1)
    A = (Jf * np.broadcast_to(w, r.shape).reshape(1, -1)) @ Jf.T
    wJs = w[None] * Js  # shape (2, 2, K, N)
    B = np.einsum("ackn,pckn->kap", wJs, J)
    D = np.einsum("ackn,bckn->kab", wJs, Js)
    g_s = np.einsum("ackn,ckn->ka", wJs, r)
    g_theta = Jf @ (w * r).reshape(-1)
    e2 = np.sum(r_kn2 * r_kn2, axis=-1)
    eq = PlanarEquations(A, B, D, g_theta, g_s, robust_cost(r_kn2, mask, huber_c), float(np.sum(e2[mask])),
                         int(2 * mask.sum()), weights)
    return eq, r_kn2


def planar_positions_only(state: PlanarState, X: np.ndarray, corners: np.ndarray, mask: np.ndarray,
                          iterations: int = 10) -> np.ndarray:
    """Each view's best (x, y) with R, l0 and the plane held (2x2 Gauss-Newton per view), shape (K, 2)."""
    sub = state.copy()
    for _ in range(iterations):
        eq, _ = linearize_planar(sub, X, corners, mask)
        ok = np.linalg.det(eq.D) > 0
        step = np.zeros_like(sub.xy)
        step[ok] = -np.linalg.solve(eq.D[ok], eq.g_s[ok][..., None])[..., 0]
        sub.xy = sub.xy + step
        if np.max(np.abs(step)) < 1e-10:
            break
    return sub.xy


def plane_inverse(A: np.ndarray, B: np.ndarray, D: np.ndarray, free_s: np.ndarray) -> ArrowheadInverse:
    """H^-1 of the plane's blocks (B (K, 2, p), D (K, 2, 2)) at the solution, factored."""
    return arrowhead_inverse(A, B, D, free_s, "the plane of motion", "capture a grid that spans both axes")


def apply_planar_step(state: PlanarState, d_theta: np.ndarray, d_s: np.ndarray) -> PlanarState:
    """Move the state by a step of :func:`~lps_gui.core.numerics.arrowhead.schur_step` (9 intrinsics after the 8 shared, when given)."""
    R = exp_so3(d_theta[0:3]) @ state.R
    l0 = state.l0 + d_theta[3:6]
    w = d_theta[6] * state.P[:, 0] + d_theta[7] * state.P[:, 1]
    P = exp_so3(w) @ state.P
    intr = state.intrinsics
    if d_theta.size > N_PLANAR_SHARED:
        intr = intr.with_vector(intr.vector() + d_theta[N_PLANAR_SHARED:])
    return PlanarState(R, l0, P, state.xy + d_s, intr)


@dataclass
class PlanarLmResult:
    state: PlanarState
    equations: PlanarEquations
    iterations: int
    converged: bool
    cost_history: list[float]


def solve_planar(
    state: PlanarState,
    X: np.ndarray,
    corners: np.ndarray,
    mask: np.ndarray,
    free_s: np.ndarray,
    max_iterations: int = 50,
    robust: bool = False,
    huber_scale: float = 3.0,
    relative_tolerance: float = 1e-10,
    cancel: CancelToken | None = None,
    intrinsics_prior: tuple[np.ndarray, np.ndarray] | None = None,
) -> PlanarLmResult:
    """Minimize the reprojection error of the planar model by LM (Schur on the 2x2 blocks).

    Parameters
    ----------
    state : initial estimate
    X : board points, shape (N, 3) mm
    corners : measured corners, shape (K, N, 2) px (NaN where missing)
    mask : corners to use, shape (K, N) bool
    free_s : views whose (x, y) are estimated, shape (K,) bool (gauge view False)
    intrinsics_prior : (I0 (9,), Sigma_I (9, 9)): the intrinsics are free too, with this prior (SPEC 4.6)
    """
    huber_c = (huber_threshold(planar_residuals(state, X, corners, mask), mask, huber_scale)
               if robust else None)
    with_intr = intrinsics_prior is not None
    info = np.linalg.inv(intrinsics_prior[1]) if with_intr else None
    p = N_PLANAR_SHARED

    def prior(st: PlanarState) -> tuple[float, np.ndarray]:
        """The prior's cost and gradient (zero without self-calibration)."""
        if info is None:
            return 0.0, 0.0
        dI = st.intrinsics.vector() - intrinsics_prior[0]
        return float(dI @ info @ dI), np.r_[np.zeros(p), info @ dI]

    prior_A = 0.0
    if info is not None:
        prior_A = np.zeros((p + 9, p + 9))
        prior_A[p:, p:] = info
    eq, _ = linearize_planar(state, X, corners, mask, huber_c, with_intr)
    prior_cost, prior_g = prior(state)
    cost = eq.cost + prior_cost
    history = [cost]
    lam = 1e-4
    converged = False
    it = 0
    for it in range(1, max_iterations + 1):
        if cancel is not None:
            cancel.check("planar estimation")
        d_theta, d_s = schur_step(eq.A + prior_A, eq.B, eq.D, eq.g_theta + prior_g, eq.g_s, free_s, lam)
        trial = apply_planar_step(state, d_theta, d_s)
        trial_prior, trial_prior_g = prior(trial)
        trial_cost = robust_cost(planar_residuals(trial, X, corners, mask), mask, huber_c) + trial_prior
        if trial_cost <= cost:
            improvement = (cost - trial_cost) / max(cost, 1e-300)
            state, prior_g = trial, trial_prior_g
            eq, _ = linearize_planar(state, X, corners, mask, huber_c, with_intr)
            cost = eq.cost + trial_prior
            history.append(cost)
            lam = max(lam / 10.0, 1e-12)
            if improvement < relative_tolerance:
                converged = True
                break
        else:
            lam *= 10.0
            if lam > 1e10:
                converged = True
                break
    return PlanarLmResult(state, eq, it, converged, history)


def initial_planar_state(
    R_views: np.ndarray,
    t_views: np.ndarray,
    target_xy_mm: np.ndarray,
    use: np.ndarray,
    ref: int,
    intrinsics: CameraIntrinsics,
) -> PlanarState:
    """Start from per-view poses (SPEC 4.3 step 2, in two dimensions).

    R is the chordal mean of the per-view rotations; the plane and its axes
    come from an affine fit t_i = c + M target_i (M: 3x2), n_x along M's first
    column, n_y the Gram-Schmidt rest of the second; positions are the
    per-view translations projected on the plane, relative to the reference.
    """
    from lps_gui.core.geometry.rotation import chordal_mean

    R = chordal_mean(R_views[use])
    T = np.asarray(target_xy_mm, dtype=float)
    G = np.column_stack([np.ones(int(use.sum())), T[use]])  # shape (k, 3)
    coef, *_ = np.linalg.lstsq(G, t_views[use], rcond=None)  # shape (3, 3): rows c, M_x, M_y
    mx, my = coef[1], coef[2]
    n_x = mx / np.linalg.norm(mx)
    n_y = my - (my @ n_x) * n_x
    n_y /= np.linalg.norm(n_y)
    P = np.column_stack([n_x, n_y, np.cross(n_x, n_y)])
    t_ref = t_views[ref]
    xy = (t_views - t_ref) @ P[:, :2]
    xy[~use] = (T[~use] - T[ref]) if (~use).any() else xy[~use]
    return PlanarState(R, t_ref.copy(), P, xy, intrinsics)


# ----------------------------------------------------------------------------- the grid's affine frame (SPEC 10)


def grid_design(target_mm: np.ndarray, approach: np.ndarray, used: np.ndarray) -> np.ndarray:
    """Columns: 1, target x, target y, and one backlash offset per axis when both sides occur."""
    cols = [np.ones(target_mm.shape[0]), target_mm[:, 0], target_mm[:, 1]]
    for a in range(2):
        side = approach[:, a] < 0
        if side[used].any() and (~side[used]).any():
            cols.append(side.astype(float))
    return np.column_stack(cols)


def affine_coefficients(xy: np.ndarray, target_mm: np.ndarray, approach: np.ndarray, used: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares xy = Phi coef; returns (Phi (K, q), coef (q, 2)); one shared design for x and y."""
    Phi = grid_design(target_mm, approach, used)
    coef, *_ = np.linalg.lstsq(Phi[used], xy[used], rcond=None)
    return Phi, coef


def affine_residual_um(xy: np.ndarray, target_mm: np.ndarray, approach: np.ndarray, used: np.ndarray) -> np.ndarray:
    """Positions off the affine trend of the grid, um (K, 2)."""
    Phi, coef = affine_coefficients(xy, target_mm, approach, used)
    return 1e3 * (xy - Phi @ coef)


def affine_motion(xy: np.ndarray, target_mm: np.ndarray, approach: np.ndarray, used: np.ndarray) -> np.ndarray:
    """G (2x2) of the least-squares fit xy = offset + G target (+ backlash offsets): columns +X, +Y motion."""
    _, coef = affine_coefficients(xy, target_mm, approach, used)
    return coef[1:3].T


def align_to_x_motion(state: PlanarState, target_mm: np.ndarray, approach: np.ndarray, used: np.ndarray
                      ) -> PlanarState:
    """Turn the plane coordinates so the fitted +X motion is +x and +Y motion has y > 0 (SPEC 10)."""
    gx, gy = affine_motion(state.xy, target_mm, approach, used).T  # measured motion per commanded mm of X, of Y
    out = state.rotated_in_plane(float(np.arctan2(gx[1], gx[0])))
    if (gx[0] * gy[1] - gx[1] * gy[0]) < 0:  # +Y motion on the -y side: flip y (and n_y) to keep y > 0
        out.P[:, 1] *= -1.0
        out.P[:, 2] *= -1.0
        out.xy[:, 1] *= -1.0
    return out


def planar_truth_in_stage_frame(true_xy_mm: np.ndarray, target_mm: np.ndarray, approach: np.ndarray,
                                used: np.ndarray, ref: int) -> np.ndarray:
    """True positions under the estimate's own frame convention (zero at ``ref``, +x along the
    fitted +X motion, +Y motion on the +y side), so they compare with a plane's ``LpsEstimate.positions_mm``."""
    xy = np.asarray(true_xy_mm, dtype=float) - true_xy_mm[ref]
    G = affine_motion(xy, target_mm, approach, used)
    angle = float(np.arctan2(G[1, 0], G[0, 0]))
    c, s = np.cos(angle), np.sin(angle)
    out = xy @ np.array([[c, -s], [s, c]])
    if np.linalg.det(G) < 0:
        out[:, 1] *= -1.0
    return out
