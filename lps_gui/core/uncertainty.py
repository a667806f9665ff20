"""Covariances from the arrowhead normal equations (SPEC 4, "Uncertainty").

Cov = sigma^2 H^-1 with H = [[A, B^T], [B, diag(D)]]. The inverse is never
formed densely: with the Schur complement S = A - B^T D^-1 B and w_i = B_i / D_i,

    cov(theta)     = S^-1
    cov(s_i, s_j)  = delta_ij / D_i + w_i^T S^-1 w_j

so every per-position variance, and the variance of every step s_j - s_i,
costs O(p^2). The total position uncertainty adds the intrinsics' covariance
propagated through d s / d I = -H^-1 J^T J_I.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.errors import DegenerateGeometryError


@dataclass(frozen=True)
class ArrowheadInverse:
    """H^-1 of an arrowhead matrix, kept factored."""

    S_inv: np.ndarray  # shape (p, p)
    W: np.ndarray  # shape (K, p): B_i / D_i, zero rows for fixed positions
    D_inv: np.ndarray  # shape (K,): 1 / D_i, zero for fixed positions

    def var_s(self) -> np.ndarray:
        """Diagonal of the position block, shape (K,) (in units of sigma^2)."""
        return self.D_inv + np.einsum("kp,pq,kq->k", self.W, self.S_inv, self.W)

    def cov_s(self, i: np.ndarray, j: np.ndarray) -> np.ndarray:
        """cov(s_i, s_j) for index arrays of one shape."""
        i, j = np.asarray(i), np.asarray(j)
        same = np.where(i == j, self.D_inv[i], 0.0)
        return same + np.einsum("kp,pq,kq->k", self.W[i], self.S_inv, self.W[j])

    def var_difference(self, i: np.ndarray, j: np.ndarray) -> np.ndarray:
        """var(s_j - s_i), e.g. of each step (units sigma^2)."""
        vs = self.var_s()
        return vs[i] + vs[j] - 2.0 * self.cov_s(i, j)

    def solve(self, rhs_theta: np.ndarray, rhs_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """H^-1 [rhs_theta; rhs_s] for rhs of shapes (p, m) and (K, m)."""
        y_theta = self.S_inv @ (rhs_theta - self.W.T @ rhs_s)
        y_s = self.D_inv[:, None] * rhs_s - self.W @ y_theta
        return y_theta, y_s


def arrowhead_inverse(A: np.ndarray, B: np.ndarray, D: np.ndarray, free_s: np.ndarray) -> ArrowheadInverse:
    """Factor H^-1; positions not in ``free_s`` (the gauge view, excluded views) are held fixed."""
    free = free_s & (D > 0)
    D_inv = np.where(free, 1.0 / np.where(free, D, 1.0), 0.0)
    W = B * D_inv[:, None]
    S = A - B.T @ W
    try:
        L = np.linalg.cholesky(S)
    except np.linalg.LinAlgError:
        raise DegenerateGeometryError(
            "the views do not determine the line (normal equations singular); capture over a longer travel or more positions"
        ) from None
    L_inv = np.linalg.inv(L)
    return ArrowheadInverse(L_inv.T @ L_inv, W, D_inv)


def noise_variance(ssr: float, n_obs: int, n_params: int) -> float:
    """A-posteriori residual variance sigma_hat^2 = SSR / (2NK - p) (px^2)."""
    dof = n_obs - n_params
    if dof <= 0:
        raise DegenerateGeometryError(
            f"{n_obs} residuals for {n_params} unknowns: no redundancy to estimate the noise; add views or corners"
        )
    return ssr / dof


def intrinsics_sensitivity(
    inverse: ArrowheadInverse, cross_theta: np.ndarray, cross_s: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """d (theta, s) / d intrinsics = -H^-1 J^T W J_I.

    Parameters
    ----------
    cross_theta : J_theta^T W J_I, shape (p, 9)
    cross_s : J_s^T W J_I per view, shape (K, 9)
    """
    y_theta, y_s = inverse.solve(cross_theta, cross_s)
    return -y_theta, -y_s


def propagated_variance(G_s: np.ndarray, cov_intrinsics: np.ndarray) -> np.ndarray:
    """Variance of each position from the intrinsics alone, shape (K,) mm^2."""
    return np.einsum("ki,ij,kj->k", G_s, cov_intrinsics, G_s)
