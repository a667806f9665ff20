"""The block arrowhead of every stage model: Schur steps and the factored inverse (SPEC 4, 10, 13).

Each view has b own unknowns (b = 1: a line's position s_i; 2: a plane's
(x_i, y_i); a target model's D; a free pose's 6) beside p shared ones, so the
Gauss-Newton matrix is

    H = [[A, B^T], [B, blockdiag(D_1..D_K)]],  A: (p, p), B_k: (b, p), D_k: (b, b).

The block diagonal is eliminated by the Schur complement S = A - sum_k B_k^T D_k^-1 B_k,
batched over the views (one step costs O(K b^2 p) after the linearization), and the
covariance is never formed densely:

    cov(theta)      = S^-1
    cov(s_i, s_j)   = delta_ij D_i^-1 + W_i S^-1 W_j^T,   W_k = D_k^-1 B_k.

Views whose unknowns are held (the gauge view, excluded views) get D_k^-1 = 0.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.errors import DegenerateGeometryError

MIN_DET_RATIO = 1e-12  # a view's block counts as determined when det D_k > this x trace(D_k)^b


def determined_views(D: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Free views whose own block is positive definite (seen by enough corners); D shape (K, b, b)."""
    b = D.shape[1]
    if b == 1:
        det = D[:, 0, 0]
    else:
        det = np.linalg.det(D)
    return free & (det > MIN_DET_RATIO * np.maximum(np.einsum("kii->k", D) ** b, 1e-300))


def block_inverse(D: np.ndarray, free: np.ndarray) -> np.ndarray:
    """D_k^-1 for the free views, zero blocks for the held ones; D shape (K, b, b)."""
    out = np.zeros_like(D)
    if D.shape[1] == 1:
        out[free] = 1.0 / D[free]
    elif free.any():
        out[free] = np.linalg.inv(D[free])
    return out


def per_view(M: np.ndarray, X: np.ndarray) -> np.ndarray:
    """M_k X_k for every view: M (K, b, b), X (K, b, m); a broadcast product for b = 1 (batched 1x1 matrix
    products cost more than the arithmetic)."""
    return M * X if M.shape[1] == 1 else M @ X


def stacked(X: np.ndarray) -> np.ndarray:
    """(K, b, m) as the (K b, m) rows of one matrix, for one BLAS product over all views."""
    return X.reshape(-1, X.shape[-1])


def solve_spd(S: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve the small reduced system by Cholesky (numpy: scipy.linalg's import costs more than the solve)."""
    if S.size == 0:
        return np.zeros_like(b)
    try:
        L = np.linalg.cholesky(S)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(S, b, rcond=None)[0]
    return np.linalg.solve(L.T, np.linalg.solve(L, b))


@dataclass(frozen=True)
class Schur:
    """The views eliminated: S = A - sum_k B_k^T W_k with W_k = D_k^-1 B_k (zero for held views)."""

    S: np.ndarray  # (p, p)
    W: np.ndarray  # (K, b, p)
    D_inv: np.ndarray  # (K, b, b)


def eliminate(A: np.ndarray, B: np.ndarray, D: np.ndarray, free: np.ndarray, damping: float = 0.0,
              screen: bool = True) -> Schur:
    """The Schur complement of the (damped: diag(H) (1 + damping)) arrowhead; shapes A (p, p), B (K, b, p),
    D (K, b, b). ``screen`` holds free views whose block is singular (:func:`determined_views`)."""
    if damping:
        A = A + damping * np.diag(np.diag(A))
        D = D + damping * D * np.eye(D.shape[1])[None]
    free = determined_views(D, free) if screen else np.asarray(free, bool)
    D_inv = block_inverse(D, free)
    W = per_view(D_inv, B)
    return Schur(A - stacked(B).T @ stacked(W), W, D_inv)


def schur_step(A: np.ndarray, B: np.ndarray, D: np.ndarray, g_theta: np.ndarray, g_s: np.ndarray, free: np.ndarray,
               damping: float = 0.0, screen: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """LM step: (H + damping diag(H)) [d_theta; d_s] = -[g_theta; g_s] with the views not in ``free`` held.

    Shapes: g_theta (p,), g_s (K, b); returns d_theta (p,), d_s (K, b) with zeros for held views.
    """
    sc = eliminate(A, B, D, free, damping, screen)
    d_theta = -solve_spd(sc.S, g_theta - stacked(sc.W).T @ g_s.ravel())
    d_s = -per_view(sc.D_inv, (g_s + B @ d_theta)[..., None])[..., 0]
    return d_theta, d_s


@dataclass(frozen=True)
class ArrowheadInverse:
    """H^-1 of a block arrowhead matrix, kept factored (in the units of H^-1: multiply by sigma^2)."""

    S_inv: np.ndarray  # shape (p, p)
    W: np.ndarray  # shape (K, b, p): D_k^-1 B_k, zero for held views
    D_inv: np.ndarray  # shape (K, b, b), zero for held views

    def cov_view(self) -> np.ndarray:
        """Each view's own b x b covariance block, shape (K, b, b)."""
        return self.D_inv + np.einsum("kap,kbp->kab", self.W @ self.S_inv, self.W)

    def variances(self) -> np.ndarray:
        """The diagonal of every view's block, shape (K, b)."""
        return np.einsum("kii->ki", self.cov_view())

    def cov_between(self, i: np.ndarray, j: np.ndarray) -> np.ndarray:
        """cov(s_i, s_j) (n, b, b) for index arrays i, j of one shape (n,)."""
        i, j = np.asarray(i), np.asarray(j)
        same = np.where((i == j)[:, None, None], self.D_inv[i], 0.0)
        return same + np.einsum("kap,pq,kbq->kab", self.W[i], self.S_inv, self.W[j])

    def cov_difference(self, i: np.ndarray, j: np.ndarray) -> np.ndarray:
        """cov(s_j - s_i) (n, b, b), e.g. of each step."""
        c = self.cov_view()
        cross = self.cov_between(i, j)
        return c[i] + c[j] - cross - np.swapaxes(cross, 1, 2)

    def functional_covariance(self, L: np.ndarray) -> np.ndarray:
        """Covariance of m linear functionals sum_k L[:, k, :] . s_k; L shape (m, K, b) -> (m, m).

        Uses the full covariance (correlations through the shared parameters count),
        at O(m^2 K b^2) cost.
        """
        direct = np.einsum("mka,kab,nkb->mn", L, self.D_inv, L)
        LW = np.einsum("mka,kap->mp", L, self.W)
        return direct + LW @ self.S_inv @ LW.T

    def solve(self, rhs_theta: np.ndarray, rhs_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """H^-1 [rhs_theta; rhs_s] for right-hand sides of shapes (p, m) and (K, b, m)."""
        y_theta = self.S_inv @ (rhs_theta - stacked(self.W).T @ stacked(rhs_s))
        return y_theta, per_view(self.D_inv, rhs_s) - self.W @ y_theta


def arrowhead_inverse(A: np.ndarray, B: np.ndarray, D: np.ndarray, free: np.ndarray,
                      what: str = "the stage model", remedy: str = "capture more views over a longer travel",
                      screen: bool = True) -> ArrowheadInverse:
    """Factor H^-1 at the solution; views not in ``free`` are held. ``what`` names the shared unknowns and
    ``remedy`` what to do, in the error raised when the views do not determine them."""
    sc = eliminate(A, B, D, free, screen=screen)
    if sc.S.size == 0:
        return ArrowheadInverse(sc.S, sc.W, sc.D_inv)
    try:
        L = np.linalg.cholesky(sc.S)
    except np.linalg.LinAlgError:
        raise DegenerateGeometryError(f"the views do not determine {what} (normal equations singular); {remedy}"
                                      ) from None
    L_inv = np.linalg.inv(L)
    return ArrowheadInverse(L_inv.T @ L_inv, sc.W, sc.D_inv)


def intrinsics_sensitivity(inverse: ArrowheadInverse, cross_theta: np.ndarray, cross_s: np.ndarray) -> np.ndarray:
    """d s / d intrinsics = -(H^-1 J^T W J_I) of the views' unknowns, shape (K, b, m).

    ``cross_theta``: J_theta^T W J_I, shape (p, m); ``cross_s``: J_s^T W J_I per view, shape (K, b, m).
    """
    return -inverse.solve(cross_theta, cross_s)[1]
