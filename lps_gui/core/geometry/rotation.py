"""Rotations: exp/log maps, skew matrices and the chordal mean.

Vectorized over leading axes in numpy, through unit quaternions with the same
formulas as scipy's ``Rotation`` (Markley's matrix-to-quaternion choice, the
series near zero angle), so results agree with it to rounding; importing
``scipy.spatial`` for these would cost ``lps estimate`` a third of a second.
Solvers perturb a rotation on the left, ``R <- exp([w]x) R``, so that the
derivative of ``R X`` with respect to ``w`` is simply ``-[R X]x``.
"""
from __future__ import annotations

import numpy as np


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
    rv = rvec.reshape(-1, 3)
    angle = np.linalg.norm(rv, axis=1)
    small = angle <= 1e-3
    a2 = angle**2
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(small, 0.5 - a2 / 48 + a2 * a2 / 3840, np.sin(angle / 2) / np.where(small, 1.0, angle))
    q = np.concatenate([scale[:, None] * rv, np.cos(angle / 2)[:, None]], axis=1)
    return _quat_to_matrix(q).reshape(rvec.shape[:-1] + (3, 3))


def log_so3(R: np.ndarray) -> np.ndarray:
    """Rotation vectors (rad) of rotation matrices; shape (..., 3, 3) -> (..., 3)."""
    R = np.asarray(R, dtype=float)
    q = _matrix_to_quat(_nearest_rotation(R.reshape(-1, 3, 3)))
    q = np.where(q[:, 3:] < 0, -q, q)
    vnorm = np.linalg.norm(q[:, :3], axis=1)
    angle = 2 * np.arctan2(vnorm, q[:, 3])
    small = angle <= 1e-3
    a2 = angle**2
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(small, 2 + a2 / 12 + 7 * a2 * a2 / 2880, angle / np.sin(np.where(small, 1.0, angle) / 2))
    return (scale[:, None] * q[:, :3]).reshape(R.shape[:-2] + (3,))


def _quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """(x, y, z, w) unit quaternions, shape (M, 4) -> (M, 3, 3)."""
    x, y, z, w = q.T
    xx, yy, zz, ww = x * x, y * y, z * z, w * w
    xy, zw, xz, yw, yz, xw = x * y, z * w, x * z, y * w, y * z, x * w
    out = np.empty((len(q), 3, 3))
    out[:, 0, 0] = xx - yy - zz + ww
    out[:, 1, 0] = 2 * (xy + zw)
    out[:, 2, 0] = 2 * (xz - yw)
    out[:, 0, 1] = 2 * (xy - zw)
    out[:, 1, 1] = -xx + yy - zz + ww
    out[:, 2, 1] = 2 * (yz + xw)
    out[:, 0, 2] = 2 * (xz + yw)
    out[:, 1, 2] = 2 * (yz - xw)
    out[:, 2, 2] = -xx - yy + zz + ww
    return out


def _nearest_rotation(M: np.ndarray) -> np.ndarray:
    """Orthogonalize (M, 3, 3) matrices (SVD), as scipy does before converting."""
    U, _, Vt = np.linalg.svd(M)
    d = np.sign(np.linalg.det(U @ Vt))
    return (U * np.stack([np.ones_like(d), np.ones_like(d), d], axis=1)[:, None, :]) @ Vt


def _matrix_to_quat(M: np.ndarray) -> np.ndarray:
    """Unit quaternions (x, y, z, w) of matrices (M, 3, 3): Markley's choice of the best-conditioned form."""
    decision = np.concatenate([np.diagonal(M, axis1=1, axis2=2), np.trace(M, axis1=1, axis2=2)[:, None]], axis=1)
    choice = np.argmax(decision, axis=1)
    q = np.empty((len(M), 4))
    on_axis = choice != 3
    i = choice[on_axis]
    j, k = (i + 1) % 3, (i + 2) % 3
    m = M[on_axis]
    r = np.arange(len(m))
    q[on_axis, i] = 1 - decision[on_axis, 3] + 2 * m[r, i, i]
    q[on_axis, j] = m[r, j, i] + m[r, i, j]
    q[on_axis, k] = m[r, k, i] + m[r, i, k]
    q[on_axis, 3] = m[r, k, j] - m[r, j, k]
    m = M[~on_axis]
    q[~on_axis, 0] = m[:, 2, 1] - m[:, 1, 2]
    q[~on_axis, 1] = m[:, 0, 2] - m[:, 2, 0]
    q[~on_axis, 2] = m[:, 1, 0] - m[:, 0, 1]
    q[~on_axis, 3] = 1 + decision[~on_axis, 3]
    return q / np.linalg.norm(q, axis=1, keepdims=True)


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
