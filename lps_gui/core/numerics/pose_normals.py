"""Per-view Gauss-Newton blocks of camera poses: the one linearization the pose models share.

Every model fitted to the views here (the LPS line, the constant-orientation
fit, free 6-DOF poses) is a parametrization of each view's pose ``x = Q_k X
+ t_k``. A left perturbation ``x <- exp([w]x) Q_k X + t_k + dt`` moves a
corner by ``dx = -[y]x w + dt`` with ``y = Q_k X``, so with the corner's
d uv / d x = P (2x3) and ``M = P^T W P``, ``q = P^T W r`` (3x3 and 3, per
corner) the view's 6x6 normal equations are

    H_ww = sum [y]x^T M [y]x,  H_wt = sum [y]x M,  H_tt = sum M,
    g_w = sum y x q,           g_t = sum q.

Because ``y = Q_k X_n``, each sum is a moment of M and q against the board
points (1, X_n, X_n X_n^T) rotated by Q_k: one matrix product over the
corners, no (K, N, 2, 6) Jacobian. A model maps the blocks through its own
small Jacobian (6 x its parameters per view). Views are processed in blocks
that stay in cache; the arithmetic is exact (tests compare it with central
differences).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics, ProjectionParts, intrinsics_rows, project_parts
from lps_gui.core.numerics.blocks import in_parallel

BLOCK_VIEWS = 32  # views per pass: ~17k corners, each temporary ~140 kB (cache-resident)

_LEVI = np.zeros((3, 3, 3))
for _i, _j, _k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
    _LEVI[_i, _j, _k], _LEVI[_i, _k, _j] = 1.0, -1.0
# [y]x_ik = eps_ilk y_l: maps of the moments to the blocks (rows: moment index, columns: block entry)
_G_W = np.einsum("ilk->kli", _LEVI).reshape(9, 3)  # sum_n q_k y_l -> g_w_i
_H_WT = np.einsum("ilk,jm->kjlim", _LEVI, np.eye(3)).reshape(27, 9)  # sum_n M_kj y_l -> H_wt_im
_H_WW = np.einsum("ali,bpj->ablpij", _LEVI, _LEVI).reshape(81, 9)  # sum_n M_ab y_l y_p -> H_ww_ij
_SYM = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))  # the 6 distinct entries of M
_FULL = np.array([[0, 1, 2], [1, 3, 4], [2, 4, 5]])  # M entry (a, b) -> its index in _SYM


@dataclass
class PoseNormals:
    """Per-view J^T W J and J^T W r in (w, t), and the view's residual sums."""

    H: np.ndarray  # shape (K, 6, 6)
    g: np.ndarray  # shape (K, 6)
    ssr: np.ndarray  # shape (K,) px^2, plain sum of squares over the used corners
    cost: np.ndarray  # shape (K,) robust cost (== ssr without a loss)
    n_obs: np.ndarray  # shape (K,) scalar residuals used (2 per corner)
    weights: np.ndarray | None = None  # shape (K, N): mask x robust weight, when asked
    residuals: np.ndarray | None = None  # shape (K, N, 2): projected - observed (0 where unused), when asked
    H_pose_intrinsics: np.ndarray | None = None  # shape (K, 6, 9): (w, t) against the intrinsics, when asked
    H_intrinsics: np.ndarray | None = None  # shape (9, 9): summed over all views
    g_intrinsics: np.ndarray | None = None  # shape (9,)


def board_moments(X: np.ndarray) -> np.ndarray:
    """The board points' monomials (1, X, X X^T) per corner, shape (N, 13)."""
    X = np.asarray(X, float)
    return np.concatenate([np.ones((len(X), 1)), X, (X[:, :, None] * X[:, None, :]).reshape(-1, 9)], axis=1)


def pose_normals(
    Q: np.ndarray,
    t: np.ndarray,
    X: np.ndarray,
    corners: np.ndarray,
    mask: np.ndarray,
    intrinsics: CameraIntrinsics,
    huber_c: float | None = None,
    want_weights: bool = False,
    want_residuals: bool = False,
    with_intrinsics: bool = False,
    summed_views: np.ndarray | None = None,
) -> PoseNormals:
    """The 6x6 blocks of every view at poses ``x = Q_k X + t_k``.

    ``Q`` is one rotation (3, 3) shared by all views or one per view (K, 3, 3);
    ``t`` (K, 3) mm; ``corners`` (K, N, 2) px with ``mask`` (K, N) the corners to
    use; ``huber_c`` (px) turns on the Huber loss on each corner's residual
    norm (its IRLS weights enter H and g). ``with_intrinsics`` adds the blocks
    of the 9 intrinsics (:data:`~lps_gui.core.geometry.camera_model.INTRINSIC_NAMES`):
    against each view's pose, and among themselves summed over the views in
    ``summed_views`` (K,) bool (all by default).
    """
    t = np.asarray(t, float)
    K, N = mask.shape
    Q = np.asarray(Q, float)
    X = np.asarray(X, float)
    moments = board_moments(X)
    out = PoseNormals(np.empty((K, 6, 6)), np.empty((K, 6)), np.empty(K), np.empty(K), 2 * mask.sum(axis=1),
                      np.empty((K, N)) if want_weights else None, np.empty((K, N, 2)) if want_residuals else None)
    if with_intrinsics:
        out.H_pose_intrinsics = np.empty((K, 6, 9))
    y_common = X @ Q.T if Q.ndim == 2 else None

    def one(lo: int) -> tuple[np.ndarray, np.ndarray] | None:
        b = slice(lo, min(K, lo + BLOCK_VIEWS))
        Qb = Q if Q.ndim == 2 else Q[b]
        y = y_common[None] if y_common is not None else np.matmul(X[None], np.transpose(Qb, (0, 2, 1)))
        return _block(out, b, Qb, y, t[b], corners[b], mask[b], moments, intrinsics, huber_c,
                      None if summed_views is None else summed_views[b])

    sums = in_parallel(one, range(0, K, BLOCK_VIEWS))
    if with_intrinsics:
        out.H_intrinsics = sum((h for h, _ in sums), np.zeros((9, 9)))
        out.g_intrinsics = sum((g for _, g in sums), np.zeros(9))
    return out


def _block(out: PoseNormals, b: slice, Q: np.ndarray, y: np.ndarray, t: np.ndarray, corners: np.ndarray,
           mask: np.ndarray, moments: np.ndarray, intrinsics: CameraIntrinsics, huber_c: float | None,
           summed: np.ndarray | None) -> tuple[np.ndarray, np.ndarray] | None:
    """Fill views ``b`` of ``out``; ``y`` (1 or B, N, 3) = Q X; ``summed``: the views that enter the global sums.

    Returns this block's share of the intrinsics' own blocks (H_II, g_I) when asked for them.
    """
    B, N = mask.shape
    x = [y[..., a] + t[:, a, None] for a in range(3)]
    parts = project_parts(x[0], x[1], x[2], intrinsics, want_jacobian=True)
    all_seen = bool(mask.all())
    ru = parts.u - corners[..., 0]
    rv = parts.v - corners[..., 1]
    if not all_seen:
        ru = np.where(mask, ru, 0.0)  # also clears the NaN of missing corners
        rv = np.where(mask, rv, 0.0)
    e2 = ru * ru + rv * rv
    out.ssr[b] = e2.sum(axis=1)
    w = None if all_seen else mask.astype(float)
    if huber_c is not None:
        e = np.sqrt(e2)
        inside = e <= huber_c
        robust = np.where(inside, 1.0, huber_c / np.maximum(e, 1e-300))
        w = robust if w is None else robust * w
        out.cost[b] = np.where(inside, e2, 2.0 * huber_c * e - huber_c * huber_c).sum(axis=1, where=mask)
    else:
        out.cost[b] = out.ssr[b]
    if out.weights is not None:
        out.weights[b] = 1.0 if w is None else w
    if out.residuals is not None:
        out.residuals[b, :, 0], out.residuals[b, :, 1] = ru, rv
    du, dv = parts.du, parts.dv
    wdu, wdv = (du, dv) if w is None else ([w * d for d in du], [w * d for d in dv])
    C = np.empty((9, B, N))  # the 6 entries of M = P^T W P, then q = P^T W r
    for c, (i, j) in enumerate(_SYM):
        np.multiply(wdu[i], du[j], out=C[c])
        C[c] += wdv[i] * dv[j]
    for i in range(3):
        np.multiply(wdu[i], ru, out=C[6 + i])
        C[6 + i] += wdv[i] * rv
    S = (C.reshape(9 * B, N) @ moments).reshape(9, B, 13)
    _assemble(out, b, Q, S)
    if out.H_pose_intrinsics is None:
        return None
    w_sum = w if summed is None or summed.all() else np.broadcast_to(summed[:, None], (B, N)) * (1.0 if w is None else w)
    return _intrinsics_block(out, b, Q, parts, ru, rv, w, w_sum, moments[:, :4], intrinsics)


def _intrinsics_block(out: PoseNormals, b: slice, Q: np.ndarray, parts: ProjectionParts, ru: np.ndarray,
                      rv: np.ndarray, w: np.ndarray | None, w_sum: np.ndarray | None, moments: np.ndarray,
                      intrinsics: CameraIntrinsics) -> tuple[np.ndarray, np.ndarray]:
    """Views ``b``'s intrinsics blocks: P^T W J_I per corner, moments against (1, X) -> (w, t) rows.

    Returns the block's (H_II, g_I); ``w_sum`` weights the corners in them
    (zero for views left out of the sums over views).
    """
    B, N = ru.shape
    Ju, Jv = intrinsics_rows(parts, intrinsics)  # each (9, B, N)
    du, dv = np.stack(parts.du), np.stack(parts.dv)  # (3, B, N)
    if w is not None:
        du, dv = du * w, dv * w
    C = du[:, None] * Ju[None] + dv[:, None] * Jv[None]  # (3, 9, B, N): sum P^T W J_I
    S = (C.reshape(27 * B, N) @ moments).reshape(3, 9, B, 4)
    Qb = np.broadcast_to(Q, (B, 3, 3))
    S1 = np.einsum("blm,kjbm->bkjl", Qb, S[..., 1:4])  # first moments in y = Q X: (B, 3, 9, 3)
    H = out.H_pose_intrinsics[b]
    H[:, 3:] = np.moveaxis(S[..., 0], -1, 0)  # t rows: sum P^T W J_I
    H[:, :3] = np.einsum("ilk,bkjl->bij", _LEVI, S1)  # w rows: sum [y]x P^T W J_I
    G = np.concatenate([Ju, Jv], axis=2).reshape(9, 2 * B * N)  # (9, 2 B N)
    r = np.concatenate([ru, rv], axis=1).reshape(-1)
    Gw = G if w_sum is None else G * np.concatenate([w_sum, w_sum], axis=1).reshape(-1)
    return Gw @ G.T, Gw @ r


def _assemble(out: PoseNormals, b: slice, Q: np.ndarray, S: np.ndarray) -> None:
    """The 6x6 blocks from the moments S (9, B, 13) against (1, X, X X^T), rotated into the camera frame."""
    B = S.shape[1]
    Qb = np.broadcast_to(Q, (B, 3, 3))
    S0 = np.moveaxis(S[..., 0], 0, -1)  # (B, 9)
    S1 = np.einsum("blm,cbm->bcl", Qb, S[..., 1:4])  # moments of y: (B, 9, 3)
    T2 = S[..., 4:13].reshape(9, B, 3, 3)
    S2 = np.einsum("blm,cbmo,bpo->bclp", Qb, T2, Qb)  # of y y^T: (B, 9, 3, 3)
    M0 = S0[:, _FULL]  # (B, 3, 3)
    M1 = S1[:, _FULL]  # (B, 3, 3, 3): [a, b, l] = sum M_ab y_l
    M2 = S2[:, _FULL]  # (B, 3, 3, 3, 3)
    H = out.H[b]
    H[:, 3:, 3:] = M0
    H_wt = (M1.reshape(B, 27) @ _H_WT).reshape(B, 3, 3)
    H[:, :3, 3:] = H_wt
    H[:, 3:, :3] = np.transpose(H_wt, (0, 2, 1))
    H[:, :3, :3] = (M2.reshape(B, 81) @ _H_WW).reshape(B, 3, 3)
    out.g[b, 3:] = S0[:, 6:9]
    out.g[b, :3] = S1[:, 6:9].reshape(B, 9) @ _G_W
