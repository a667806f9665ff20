"""Rotations: exp/log maps, skew matrices and the chordal mean.

Vectorized over leading axes with scipy's Rotation. Solvers perturb a rotation
on the left, ``R <- exp([w]x) R``, so that the derivative of ``R X`` with
respect to ``w`` is simply ``-[R X]x``.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrices ``[v]x`` for ``v`` of shape (..., 3) -> (..., 3, 3)."""
    v = np.asarray(v, dtype=float)
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def exp_so3(rvec: np.ndarray) -> np.ndarray:
    """Rotation matrices from rotation vectors (rad); shape (..., 3) -> (..., 3, 3)."""
    rvec = np.asarray(rvec, dtype=float)
    flat = Rotation.from_rotvec(rvec.reshape(-1, 3)).as_matrix()
    return flat.reshape(rvec.shape[:-1] + (3, 3))


def log_so3(R: np.ndarray) -> np.ndarray:
    """Rotation vectors (rad) of rotation matrices; shape (..., 3, 3) -> (..., 3)."""
    R = np.asarray(R, dtype=float)
    flat = Rotation.from_matrix(R.reshape(-1, 3, 3)).as_rotvec()
    return flat.reshape(R.shape[:-2] + (3,))


def project_to_so3(M: np.ndarray) -> np.ndarray:
    """Nearest rotation (Frobenius norm) to a 3x3 matrix, by SVD."""
    U, _, Vt = np.linalg.svd(np.asarray(M, dtype=float))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    return U @ D @ Vt


def chordal_mean(Rs: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Chordal L2 mean of rotations (paper Eq. 5 init): SVD projection of sum R_i.

    Parameters
    ----------
    Rs : shape (K, 3, 3)
    weights : shape (K,), optional
    """
    Rs = np.asarray(Rs, dtype=float)
    w = np.ones(len(Rs)) if weights is None else np.asarray(weights, dtype=float)
    return project_to_so3(np.einsum("k,kij->ij", w, Rs))
