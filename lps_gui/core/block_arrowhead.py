"""Arrowhead normal equations with a small dense block per view (planar: 2x2).

The planar model (SPEC 10) gives every view b = 2 own unknowns (x_i, y_i)
beside p shared ones, so the Gauss-Newton matrix is

    H = [[A, B^T], [B, blockdiag(D_1..D_K)]],  A: (p, p), B_k: (b, p), D_k: (b, b).

The block diagonal is eliminated by a Schur complement S = A - sum_k B_k^T D_k^-1 B_k:
one step costs O(K b^2 p) after the O(K N) linearization, and the covariance

    cov(theta)      = S^-1
    cov(s_i, s_j)   = delta_ij D_i^-1 + W_i S^-1 W_j^T,   W_k = D_k^-1 B_k

is never formed densely. Views whose positions are held (the gauge view,
excluded views) get D_k^-1 = 0.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.core.joint_lm import solve_spd
from lps_gui.errors import DegenerateGeometryError


def block_inverse(D: np.ndarray, free: np.ndarray) -> np.ndarray:
    """D_k^-1 for the free views, zero blocks for the held ones; D shape (K, b, b)."""
    out = np.zeros_like(D)
    if free.any():
        out[free] = np.linalg.inv(D[free])
    return out


def free_views(D: np.ndarray, free_s: np.ndarray) -> np.ndarray:
    """Views that are free and whose own block is positive definite (seen by enough corners)."""
    det = np.linalg.det(D)
    return free_s & (det > 1e-12 * np.maximum(np.einsum("kii->k", D) ** D.shape[1], 1e-300))


def solve_block_arrowhead(
    A: np.ndarray,
    B: np.ndarray,
    D: np.ndarray,
    g_theta: np.ndarray,
    g_s: np.ndarray,
    free_s: np.ndarray,
    damping: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """LM step: (H + damping diag(H)) [d_theta; d_s] = -[g_theta; g_s].

    Shapes: A (p, p), B (K, b, p), D (K, b, b), g_theta (p,), g_s (K, b);
    returns d_theta (p,), d_s (K, b) with zeros for held views.
    """
    A = A + damping * np.diag(np.diag(A))
    b = D.shape[1]
    Dd = D + damping * D * np.eye(b)[None]
    free = free_views(Dd, free_s)
    Dinv = block_inverse(Dd, free)
    W = Dinv @ B  # shape (K, b, p)
    S = A - np.einsum("kbp,kbq->pq", B, W)
    rhs = g_theta - np.einsum("kbp,kb->p", W, g_s)
    d_theta = -solve_spd(S, rhs)
    d_s = -np.einsum("kab,kb->ka", Dinv, g_s + B @ d_theta)
    return d_theta, d_s


@dataclass(frozen=True)
class BlockArrowheadInverse:
    """H^-1 of a block arrowhead matrix, kept factored (units of sigma^2)."""

    S_inv: np.ndarray  # shape (p, p)
    W: np.ndarray  # shape (K, b, p): D_k^-1 B_k, zero for held views
    D_inv: np.ndarray  # shape (K, b, b), zero for held views

    def cov_view(self) -> np.ndarray:
        """Each view's own b x b covariance block, shape (K, b, b)."""
        return self.D_inv + np.einsum("kap,pq,kbq->kab", self.W, self.S_inv, self.W)

    def functional_covariance(self, L: np.ndarray) -> np.ndarray:
        """Covariance of m linear functionals sum_k L[:, k, :] . s_k; L shape (m, K, b) -> (m, m).

        Uses the full covariance (correlations through the shared parameters count),
        at O(m^2 K b^2) cost.
        """
        direct = np.einsum("mka,kab,nkb->mn", L, self.D_inv, L)
        LW = np.einsum("mka,kap->mp", L, self.W)
        return direct + LW @ self.S_inv @ LW.T


def block_arrowhead_inverse(
    A: np.ndarray, B: np.ndarray, D: np.ndarray, free_s: np.ndarray
) -> BlockArrowheadInverse:
    """Factor H^-1 of the normal equations at the solution."""
    free = free_views(D, free_s)
    D_inv = block_inverse(D, free)
    W = D_inv @ B
    S = A - np.einsum("kbp,kbq->pq", B, W)
    try:
        L = np.linalg.cholesky(S)
    except np.linalg.LinAlgError:
        raise DegenerateGeometryError(
            "the views do not determine the plane of motion (normal equations singular); "
            "capture a grid that spans both axes"
        ) from None
    L_inv = np.linalg.inv(L)
    return BlockArrowheadInverse(L_inv.T @ L_inv, W, D_inv)


def block_intrinsics_sensitivity(inverse: BlockArrowheadInverse, cross_theta: np.ndarray, cross_s: np.ndarray
                                 ) -> np.ndarray:
    """d s / d intrinsics = -(H^-1 J^T W J_I) of the positions, shape (K, b, m).

    ``cross_theta``: J_theta^T W J_I, shape (p, m); ``cross_s``: J_s^T W J_I per view, shape (K, b, m).
    The block twin of :func:`lps_gui.core.uncertainty.intrinsics_sensitivity`.
    """
    y_theta = inverse.S_inv @ (cross_theta - np.einsum("kbp,kbm->pm", inverse.W, cross_s))
    return -(inverse.D_inv @ cross_s - inverse.W @ y_theta)
