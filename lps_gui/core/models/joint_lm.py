"""Joint Levenberg-Marquardt on the LPS model (SPEC 4.4): R, l0, n and every s_i at once.

Each view's residuals depend on the shared parameters theta (rotation 3, l0 3,
direction 2 on the sphere, and optionally the 9 intrinsics) plus its own
position s_i: the Jacobian is an arrowhead. We never build it as one matrix;
we accumulate the normal equations blockwise

    H = [[A, B^T], [B, diag(D)]],  A: (p, p), B: (K, p), D: (K,)

and eliminate the diagonal s-block by a Schur complement (:mod:`lps_gui.core.numerics.arrowhead`,
b = 1), so one iteration costs O(K N) and the linear solve is p x p. Residual weights come from the
corner mask and, optionally, a Huber loss (iteratively reweighted).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics, project_parts
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.models.lps_model import LpsLine, sphere_retract, sphere_tangent_basis
from lps_gui.core.numerics.arrowhead import ArrowheadInverse, arrowhead_inverse, schur_step
from lps_gui.core.numerics.pose_normals import PoseNormals, pose_normals
from lps_gui.core.progress import CancelToken

N_POSE_PARAMS = 8  # rotation 3, l0 3, direction 2


@dataclass
class LpsState:
    """Current estimate of the LPS model; positions s_mm relative to the gauge view."""

    R: np.ndarray  # shape (3, 3) R_cam_board
    l0: np.ndarray  # shape (3,) mm
    n: np.ndarray  # shape (3,) unit
    s: np.ndarray  # shape (K,) mm
    intrinsics: CameraIntrinsics

    @property
    def positions(self) -> np.ndarray:
        """The views' positions as an estimate reports them, shape (K,)."""
        return self.s

    def line(self) -> LpsLine:
        return LpsLine(self.R.copy(), self.l0.copy(), self.n.copy())

    def regauged(self, ref: int) -> "LpsState":
        """Zero at view ``ref``: l0 absorbs the shift of every position (the translations stay)."""
        shift = self.s[ref]
        return LpsState(self.R, self.l0 + shift * self.n, self.n, self.s - shift, self.intrinsics)

    def copy(self) -> "LpsState":
        return LpsState(self.R.copy(), self.l0.copy(), self.n.copy(), self.s.copy(), self.intrinsics)


@dataclass
class LmOptions:
    """Settings of the joint solver."""

    max_iterations: int = 50
    robust: bool = False  # Huber loss on each corner's residual
    huber_scale: float = 3.0  # in units of the robust residual scale (MAD)
    estimate_intrinsics: bool = False  # self-calibration with the prior N(I0, Sigma_I)
    fix_positions: bool = False  # hybrid step 3: only theta moves
    relative_tolerance: float = 1e-9
    step_tolerance_chi2: float = 1e-6  # stop when the model's decrease is below this many noise variances
    # near Gauss-Newton from the PnP start: at K=1600, 1e-4 held the steps short and stopped 1.2e-4 um from the
    # minimum after 3 iterations; 1e-6 stops 5e-6 um from it after 2 (a failed step still raises the damping)
    initial_damping: float = 1e-6


@dataclass
class NormalEquations:
    """Blocks of J^T W J and J^T W r at one linearization point."""

    A: np.ndarray  # shape (p, p)
    B: np.ndarray  # shape (K, p)
    D: np.ndarray  # shape (K,)
    g_theta: np.ndarray  # shape (p,)
    g_s: np.ndarray  # shape (K,)
    cost: float  # sum of robust costs (== SSR without robust loss)
    ssr: float  # plain sum of squared residuals over used corners, px^2
    n_obs: int  # number of scalar residuals used (2 per corner)
    basis: np.ndarray = field(default_factory=lambda: np.zeros((3, 2)))  # tangent basis of n
    weights: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # shape (K, N)
    view_ssr: np.ndarray = field(default_factory=lambda: np.zeros(0))  # shape (K,): each view's plain SSR, px^2


@dataclass
class LmResult:
    state: LpsState
    weights: np.ndarray  # shape (K, N) final weights (mask x robust)
    equations: NormalEquations  # at the solution
    iterations: int
    converged: bool
    cost_history: list[float]


def residuals(state: LpsState, X: np.ndarray, corners: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Reprojection residuals uv - measured, shape (K, N, 2); zero where not seen."""
    t = state.l0[None, :] + state.s[:, None] * state.n[None, :]  # shape (K, 3)
    return pose_residuals(state.R, t, X, state.intrinsics, corners, mask)


def camera_points(R: np.ndarray, t: np.ndarray, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Camera-frame coordinates R X + t_i of every corner in every view: three arrays of shape (K, N).

    ``R`` (3, 3) is the common orientation, ``t`` (K, 3) the per-view translations of any model.
    """
    RX = X @ R.T  # shape (N, 3)
    return tuple(RX[None, :, i] + t[:, i, None] for i in range(3))  # type: ignore[return-value]


def pose_residuals(R: np.ndarray, t: np.ndarray, X: np.ndarray, intrinsics: CameraIntrinsics, corners: np.ndarray,
                   mask: np.ndarray) -> np.ndarray:
    """Residuals uv - measured (K, N, 2) of views with a common R and translations t (K, 3); zero where unused."""
    x, y, z = camera_points(R, t, X)
    parts = project_parts(x, y, z, intrinsics)
    m = np.nan_to_num(corners)
    r = np.empty(corners.shape)
    r[..., 0] = np.where(mask, parts.u - m[..., 0], 0.0)
    r[..., 1] = np.where(mask, parts.v - m[..., 1], 0.0)
    return r


def huber_threshold(r: np.ndarray, mask: np.ndarray, huber_scale: float) -> float:
    """Huber threshold (px) on a corner's residual norm: ``huber_scale`` robust sigmas.

    The residual norm of a 2-D Gaussian error is Rayleigh distributed; its
    median is sigma * sqrt(2 ln 2), which turns the median into a sigma.
    """
    e = np.linalg.norm(r, axis=-1)[mask]
    if e.size == 0:
        return np.inf
    return huber_scale * float(np.median(e)) / np.sqrt(2.0 * np.log(2.0)) + 1e-12


def huber_weights(r: np.ndarray, mask: np.ndarray, c: float | None) -> np.ndarray:
    """IRLS weights per corner, shape (K, N): 1 inside the threshold, c/e beyond."""
    if c is None:
        return mask.astype(float)
    e = np.linalg.norm(r, axis=-1)
    w = np.where(e <= c, 1.0, c / np.maximum(e, 1e-300))
    return np.where(mask, w, 0.0)


def robust_cost(r: np.ndarray, mask: np.ndarray, c: float | None) -> float:
    """Sum of squared residuals, or of the Huber function of each corner's residual norm."""
    e2 = np.sum(r * r, axis=-1)[mask]
    if c is None:
        return float(np.sum(e2))
    e = np.sqrt(e2)
    return float(np.sum(np.where(e <= c, e2, 2.0 * c * e - c * c)))


def linearize(
    state: LpsState,
    X: np.ndarray,
    corners: np.ndarray,
    mask: np.ndarray,
    huber_c: float | None = None,
    with_intrinsics: bool = False,
    want_residuals: bool = True,
) -> tuple[NormalEquations, np.ndarray | None]:
    """Normal-equation blocks at ``state``; returns them and the residuals (K, N, 2) (None if not wanted).

    ``huber_c`` (px) turns on the Huber loss: its IRLS weights enter the blocks.
    ``with_intrinsics`` appends the 9 intrinsics to theta.
    """
    eq, pn = linearize_poses(state, X, corners, mask, huber_c, with_intrinsics, want_residuals)
    return eq, pn.residuals


def linearize_poses(
    state: LpsState, X: np.ndarray, corners: np.ndarray, mask: np.ndarray, huber_c: float | None = None,
    with_intrinsics: bool = False, want_residuals: bool = False, views: np.ndarray | None = None,
) -> tuple[NormalEquations, PoseNormals]:
    """The blocks from each view's 6x6 pose blocks (:mod:`lps_gui.core.numerics.pose_normals`), and those pose blocks.

    The LPS model is a parametrization of the poses: view k sits at
    ``R, t_k = l0 + s_k n``, so its pose perturbation is ``(w, t) = T_k
    (theta, s_k)`` with rotation -> w, l0 -> t, direction -> s_k basis, s_k -> n.
    ``J^T W J`` is then sum_k T_k^T H_k T_k: sums of H_k weighted by 1, s_k,
    s_k^2, never a Jacobian over the corners. The pose blocks are returned
    too: the per-view fits that start from the model reuse them.

    ``views`` (K,) bool: only these views enter the equations (as if the
    others' corners were masked); the pose blocks still cover every view of
    ``mask``, so one pass serves the solve and the views outside it.
    """
    t = state.l0[None, :] + state.s[:, None] * state.n[None, :]
    pn = pose_normals(state.R, t, X, corners, mask, state.intrinsics, huber_c, want_weights=huber_c is not None,
                      want_residuals=want_residuals, with_intrinsics=with_intrinsics, summed_views=views)
    s, n = state.s, state.n
    basis = sphere_tangent_basis(n)
    sel = np.ones(len(s), bool) if views is None else np.asarray(views, bool)
    H = np.where(sel[:, None, None], pn.H, 0.0)
    g = np.where(sel[:, None], pn.g, 0.0)
    H0, H1, H2 = H.sum(axis=0), np.einsum("kij,k->ij", H, s), np.einsum("kij,k->ij", H[:, 3:, 3:], s * s)
    p = N_POSE_PARAMS + (9 if with_intrinsics else 0)
    A = np.empty((p, p))
    A[0:6, 0:6] = H0
    A[0:6, 6:8] = H1[:, 3:] @ basis
    A[6:8, 0:6] = A[0:6, 6:8].T
    A[6:8, 6:8] = basis.T @ H2 @ basis
    h = H[:, :, 3:] @ n  # the (w, t) rows against s_k: shape (K, 6)
    B = np.empty((len(s), p))
    B[:, 0:6] = h
    B[:, 6:8] = s[:, None] * (h[:, 3:] @ basis)
    g_sum = g.sum(axis=0)
    g_theta = np.concatenate([g_sum, basis.T @ (g[:, 3:].T @ s)])
    if with_intrinsics:
        HI = np.where(sel[:, None, None], pn.H_pose_intrinsics, 0.0)  # (K, 6, 9)
        A[0:6, 8:] = HI.sum(axis=0)
        A[6:8, 8:] = basis.T @ np.einsum("kij,k->ij", HI[:, 3:], s)
        A[8:, 0:8] = A[0:8, 8:].T
        A[8:, 8:] = pn.H_intrinsics
        B[:, 8:] = np.einsum("kij,i->kj", HI[:, 3:], n)
        g_theta = np.concatenate([g_theta, pn.g_intrinsics])
    weights = (pn.weights if pn.weights is not None else mask.astype(float)) * sel[:, None]
    eq = NormalEquations(
        A=A, B=B, D=h[:, 3:] @ n, g_theta=g_theta, g_s=g[:, 3:] @ n,
        cost=float(pn.cost[sel].sum()), ssr=float(pn.ssr[sel].sum()), n_obs=int(pn.n_obs[sel].sum()),
        basis=basis, weights=weights, view_ssr=np.where(sel, pn.ssr, 0.0),
    )
    return eq, pn


def solve_arrowhead(
    eq: NormalEquations,
    free_s: np.ndarray,
    damping: float = 0.0,
    prior_A: np.ndarray | None = None,
    prior_g: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Newton / LM step (:func:`lps_gui.core.numerics.arrowhead.schur_step`, one unknown per view).

    Solves (H + damping * diag(H)) [d_theta; d_s] = -[g_theta; g_s] with the
    positions not in ``free_s`` held fixed. Returns d_theta (p,), d_s (K,).
    """
    A = eq.A + (prior_A if prior_A is not None else 0.0)
    g = eq.g_theta + (prior_g if prior_g is not None else 0.0)
    d_theta, d_s = schur_step(A, eq.B[:, None, :], eq.D[:, None, None], g, eq.g_s[:, None], free_s, damping)
    return d_theta, d_s[:, 0]


def line_inverse(A: np.ndarray, B: np.ndarray, D: np.ndarray, free_s: np.ndarray) -> ArrowheadInverse:
    """H^-1 of the line's blocks (B (K, p), D (K,)) at the solution, factored with one unknown per view."""
    return arrowhead_inverse(A, B[:, None, :], D[:, None, None], free_s, "the line",
                             "capture over a longer travel or more positions")


def predicted_decrease(
    eq: NormalEquations, d_theta: np.ndarray, d_s: np.ndarray,
    prior_A: np.ndarray | None = None, prior_g: np.ndarray | None = None,
) -> float:
    """How much the Gauss-Newton model says a step lowers the cost: -(2 g.d + d^T H d)."""
    A = eq.A + (prior_A if prior_A is not None else 0.0)
    g = eq.g_theta + (prior_g if prior_g is not None else 0.0)
    quad = d_theta @ A @ d_theta + 2.0 * d_theta @ (eq.B.T @ d_s) + d_s @ (eq.D * d_s)
    return float(-(2.0 * (g @ d_theta + eq.g_s @ d_s) + quad))


def apply_step(state: LpsState, d_theta: np.ndarray, d_s: np.ndarray, basis: np.ndarray) -> LpsState:
    """Move the state by a step of :func:`solve_arrowhead`."""
    R = exp_so3(d_theta[0:3]) @ state.R
    l0 = state.l0 + d_theta[3:6]
    n = sphere_retract(state.n, d_theta[6:8], basis)
    intr = state.intrinsics
    if d_theta.size > N_POSE_PARAMS:
        intr = intr.with_vector(intr.vector() + d_theta[8:17])
    return LpsState(R, l0, n, state.s + d_s, intr)


def solve_joint(
    state: LpsState,
    X: np.ndarray,
    corners: np.ndarray,
    mask: np.ndarray,
    free_s: np.ndarray,
    options: LmOptions | None = None,
    cancel: CancelToken | None = None,
    intrinsics_prior: tuple[np.ndarray, np.ndarray] | None = None,
) -> LmResult:
    """Minimize the reprojection error of the LPS model (paper Eq. 4) by LM.

    Parameters
    ----------
    state : initial estimate (positions of fixed views stay as given)
    X : board points, shape (N, 3) mm
    corners : measured corners, shape (K, N, 2) px (NaN where missing)
    mask : which corners to use, shape (K, N) bool (excluded views all False)
    free_s : which positions to estimate, shape (K,) bool (gauge view False)
    intrinsics_prior : (I0 (9,), Sigma_I (9, 9)) when options.estimate_intrinsics
    """
    opt = options or LmOptions()
    with_intr = opt.estimate_intrinsics
    prior_A = prior_g = None
    if with_intr:
        if intrinsics_prior is None:
            raise ValueError("self-calibration needs an intrinsics prior (I0, covariance)")
        I0, cov_I = intrinsics_prior
        info_I = np.linalg.inv(cov_I)
        prior_A = np.zeros((17, 17))
        prior_A[8:, 8:] = info_I
    free = free_s.copy() if not opt.fix_positions else np.zeros_like(free_s)
    huber_c = huber_threshold(residuals(state, X, corners, mask), mask, opt.huber_scale) if opt.robust else None
    eq, _ = linearize(state, X, corners, mask, huber_c, with_intr)

    def prior_terms(st: LpsState) -> tuple[float, np.ndarray | None]:
        if not with_intr:
            return 0.0, None
        dI = st.intrinsics.vector() - I0
        g = np.zeros(17)
        g[8:] = info_I @ dI
        return float(dI @ info_I @ dI), g

    prior_cost, prior_g = prior_terms(state)
    cost = eq.cost + prior_cost
    history = [cost]
    lam = opt.initial_damping
    converged = False
    it = 0
    for it in range(1, opt.max_iterations + 1):
        if cancel is not None:
            cancel.check("estimation")
        d_theta, d_s = solve_arrowhead(eq, free, lam, prior_A, prior_g)
        noise_var = cost / max(eq.n_obs, 1)
        if predicted_decrease(eq, d_theta, d_s, prior_A, prior_g) <= opt.step_tolerance_chi2 * noise_var:
            converged = True  # the step would move the parameters by < 1e-3 sigma jointly: no pass spent on it
            break
        trial = apply_step(state, d_theta, d_s, eq.basis)
        trial_prior, trial_prior_g = prior_terms(trial)
        trial_eq, _ = linearize(trial, X, corners, mask, huber_c, with_intr, want_residuals=False)
        trial_cost = trial_eq.cost + trial_prior
        if trial_cost <= cost:  # one pass both judges the step and linearizes at the new state
            improvement = (cost - trial_cost) / max(cost, 1e-300)
            state, eq, prior_g, cost = trial, trial_eq, trial_prior_g, trial_cost
            history.append(cost)
            lam = max(lam / 10.0, 1e-12)
            if improvement < opt.relative_tolerance:
                converged = True
                break
        else:
            lam *= 10.0
            if lam > 1e10:  # no descent direction left: at the minimum to machine precision
                converged = True
                break
    return LmResult(state, eq.weights, eq, it, converged, history)


def solve_positions_only(
    state: LpsState, X: np.ndarray, corners: np.ndarray, mask: np.ndarray, iterations: int = 8
) -> np.ndarray:
    """Each view's own best position with R, l0, n fixed (1-D Gauss-Newton per view).

    ``state.s`` holds the starting positions of exactly the views in
    ``corners`` (shape (k, N, 2)); returns their positions, shape (k,).
    """
    sub = state.copy()
    if sub.s.size == 0:
        return sub.s
    for _ in range(iterations):
        eq, _ = linearize(sub, X, corners, mask)
        step = np.where(eq.D > 0, -eq.g_s / np.where(eq.D > 0, eq.D, 1.0), 0.0)
        sub.s = sub.s + step
        if np.max(np.abs(step)) < 1e-10:
            break
    return sub.s
