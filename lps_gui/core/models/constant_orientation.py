"""Per-view translation and image rotation under the common orientation (SPEC 11).

With one planar board far away, a camera tilt about an axis parallel to the
board looks like a translation of (distance x angle), so free 6-DOF poses
are noise-dominated across the motion. The LPS model holds the orientation
constant; with that common R each view keeps only what the board resolves:
the board's reference point in the camera frame ``b_i`` (3 DOF) and a
rotation ``phi_i`` about the camera's optical axis z (1 DOF, the image
rotation)::

    x_cam = exp(phi_i [z]x) R (X - X0) + b_i

``X0`` is the board's centre. A camera rotation about its optical axis is
exactly a turn of the board about X0 plus a shift of X0, so this model
represents it without error wherever the board sits in the image; ``b_i`` is
the displacement of the line of sight at the board plane (the same Abbe
convention as the positions), decoupled from ``phi_i`` to first order. A tilt
about an axis across the optical axis is a translation at the board to first
order only: off-axis (field tangent x') a little of it (~x' times the tilt)
shows as image rotation (tests/core/test_constant_orientation.py bounds it). Every view's 4x4 normal
equations are solved batched; the covariance is ``sigma^2 H^-1`` from the
same Jacobian with the a-posteriori sigma of this fit. The common R, l0, n
are held fixed: their error is common to all views and the straightness is
taken relative to a least-squares line, which removes it to first order
(checked against Monte-Carlo truth in tests/core/test_constant_orientation.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics, project_parts
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.models.lps_model import motion_frame, unit
from lps_gui.core.numerics.pose_normals import PoseNormals, pose_normals

N_VIEW_PARAMS = 4  # b (3), phi (1)


@dataclass
class ConstantOrientationViews:
    """Per-view fit with the common orientation."""

    b: np.ndarray  # shape (K, 3) mm: board centre X0 in the camera frame
    phi: np.ndarray  # shape (K,) rad: rotation about the line of sight a_i
    axis: np.ndarray  # shape (K, 3): unit rotation axis (camera frame): the optical axis
    cov_unit: np.ndarray  # shape (K, 4, 4): (b, phi) covariance per unit noise variance
    ssr: np.ndarray  # shape (K,) px^2
    n_obs: np.ndarray  # shape (K,) scalar residuals (2 per corner)
    R: np.ndarray  # shape (3, 3): the common orientation used (refined when asked)


@dataclass
class LineResiduals:
    """Displacements off a least-squares line, with their sigmas."""

    values: np.ndarray  # shape (K, C)
    sigma: np.ndarray  # shape (K, C)


@dataclass
class BoardPlaneMotion:
    """Straightness at the board plane and image rotation, per view (SPEC 11)."""

    straightness_um: np.ndarray  # shape (K, 2): along v1, v2
    straightness_sigma_um: np.ndarray  # shape (K, 2)
    image_rotation_urad: np.ndarray  # shape (K,): camera's rotation about its optical axis, relative to the common R
    image_rotation_sigma_urad: np.ndarray  # shape (K,)
    frame: np.ndarray  # shape (3, 3): (u, v1, v2) columns, board frame
    sigma_px: float  # a-posteriori noise of this fit


def view_residuals(
    R: np.ndarray, b: np.ndarray, phi: np.ndarray, axis: np.ndarray, X: np.ndarray, X0: np.ndarray,
    corners: np.ndarray, mask: np.ndarray, intrinsics: CameraIntrinsics,
) -> np.ndarray:
    """Residuals (projected - observed) of the model, shape (K, N, 2), zero where masked."""
    Y = (np.asarray(X, float) - X0) @ R.T  # shape (N, 3)
    E = exp_so3(phi[:, None] * axis)  # shape (K, 3, 3)
    x = np.einsum("kij,nj->kni", E, Y) + b[:, None, :]
    parts = project_parts(x[..., 0], x[..., 1], x[..., 2], intrinsics)
    r = np.stack([parts.u - corners[..., 0], parts.v - corners[..., 1]], axis=-1)
    return np.where(mask[..., None], np.nan_to_num(r), 0.0)


@dataclass
class ViewEquations:
    """Normal-equation blocks of the (b, phi) fit and of R's two tilts, per view."""

    H: np.ndarray  # shape (K, 4, 4): (b, phi)
    g: np.ndarray  # shape (K, 4)
    B: np.ndarray  # shape (K, 4, 2): (b, phi) against the tilts (omega_x, omega_y)
    H_w: np.ndarray  # shape (K, 2, 2): the tilts
    g_w: np.ndarray  # shape (K, 2)
    ssr: np.ndarray  # shape (K,) px^2


def view_equations(
    R: np.ndarray, b: np.ndarray, phi: np.ndarray, axis: np.ndarray, X: np.ndarray, X0: np.ndarray,
    corners: np.ndarray, mask: np.ndarray, intrinsics: CameraIntrinsics, start: PoseNormals | None = None,
) -> ViewEquations:
    """The model as a parametrization of the poses, mapped through each view's 6x6 pose blocks.

    View k's pose is ``Q = E R``, ``t = b - Q X0`` with ``E = exp(phi [a]x)``.
    In the left pose perturbation (w, t): d b -> t; d phi -> w = a, t = -a x Q X0;
    a tilt of R about e_j, ``R <- exp([e_j]x) R``, -> w = E e_j, t = -E e_j x Q X0.
    ``start``: the pose blocks at these poses, when the caller has them.
    """
    E = exp_so3(phi[:, None] * axis)
    Q = E @ R
    c = Q @ X0  # Q X0 per view, shape (K, 3)
    pn = start if start is not None else pose_normals(Q, b - c, X, corners, mask, intrinsics)
    K = b.shape[0]
    T = np.zeros((K, 6, N_VIEW_PARAMS + 2))
    T[:, 3:, 0:3] = np.eye(3)
    T[:, :3, 3] = axis
    T[:, 3:, 3] = -np.cross(axis, c)
    Ej = np.transpose(E[:, :, 0:2], (0, 2, 1))  # E e_x, E e_y as rows, shape (K, 2, 3)
    T[:, :3, 4:6] = E[:, :, 0:2]
    T[:, 3:, 4:6] = -np.transpose(np.cross(Ej, c[:, None, :]), (0, 2, 1))
    Tt = np.transpose(T, (0, 2, 1))
    HT = Tt @ pn.H @ T  # shape (K, 6, 6) in (b, phi, omega_x, omega_y)
    gT = (Tt @ pn.g[..., None])[..., 0]
    v = slice(0, N_VIEW_PARAMS)
    w = slice(N_VIEW_PARAMS, N_VIEW_PARAMS + 2)
    return ViewEquations(HT[:, v, v], gT[:, v], HT[:, v, w], HT[:, w, w], gT[:, w], pn.ssr)


def solve_views(
    R: np.ndarray,
    b0: np.ndarray,
    X: np.ndarray,
    X0: np.ndarray,
    corners: np.ndarray,
    mask: np.ndarray,
    intrinsics: CameraIntrinsics,
    iterations: int = 2,
    refine_rotation: np.ndarray | None = None,
    start: PoseNormals | None = None,
) -> ConstantOrientationViews:
    """Batched Gauss-Newton on every view's (b, phi), optionally with the common R's two tilts.

    Started from the LPS model (b0 = R X0 + l0 + s_i n, phi = 0) two steps
    reach 1e-7 um (paper rig, K=400, with a 200 urad image-rotation drift and
    the R tilts refined; more cost time only); views without corners keep the
    start and get an infinite covariance.

    ``refine_rotation`` (bool per view): re-estimate the tilts of R (about the
    camera's x and y; a common turn about z is the gauge of the phi_i) from
    those views jointly with every view's (b, phi), by a Schur complement on
    the 4x4 blocks. The joint LM's R has no per-view image rotation, so an
    image-rotation drift biases its tilts, and off-axis a tilt error of R
    shows as image rotation; refining removes that. The phi covariance then
    includes R's uncertainty; the b covariance stays per view (a common R
    error moves the b_i smoothly, and the straightness' least-squares line
    takes it out to first order).
    """
    R = np.array(R, dtype=float, copy=True)
    X = np.asarray(X, float)
    b = np.array(b0, dtype=float, copy=True)
    K = b.shape[0]
    axis = np.broadcast_to(np.array([0.0, 0.0, 1.0]), (K, 3)).copy()
    phi = np.zeros(K)
    n_obs = 2 * mask.sum(axis=1)
    seen = n_obs >= 2 * N_VIEW_PARAMS
    common = None if refine_rotation is None else np.asarray(refine_rotation, bool) & seen
    eye = np.eye(N_VIEW_PARAMS)
    for it in range(iterations + 1):
        eqs = view_equations(R, b, phi, axis, X, X0, corners, mask, intrinsics, start if it == 0 else None)
        H = eqs.H.copy()
        H[~seen] = eye
        g = eqs.g.copy()
        g[~seen] = 0.0
        H_inv = np.linalg.inv(H)
        if common is not None:
            A = eqs.H_w[common].sum(axis=0)
            B = np.where(common[:, None, None], eqs.B, 0.0)  # shape (K, 4, 2)
            HB = H_inv @ B  # shape (K, 4, 2)
            S = A - np.einsum("kpa,kpb->ab", B, HB)
            S_inv = np.linalg.inv(S)
        if it == iterations:
            break
        g_view = g
        if common is not None:
            g_w = eqs.g_w[common].sum(axis=0)
            rhs = g_w - np.einsum("kpa,kp->a", HB, g_view)
            d_w = -S_inv @ rhs
            g_view = g_view + B @ d_w
            R = exp_so3(np.array([d_w[0], d_w[1], 0.0])) @ R
        delta = -np.einsum("kpq,kq->kp", H_inv, g_view)
        b = b + delta[:, :3]
        phi = phi + delta[:, 3]
    cov = H_inv.copy()
    if common is not None:
        cov[:, 3, 3] += np.einsum("ka,ab,kb->k", HB[:, 3, :], S_inv, HB[:, 3, :])
    cov[~seen] = np.inf
    ssr = eqs.ssr.copy()
    return ConstantOrientationViews(b, phi, axis, cov, ssr, n_obs, R)


def line_residuals(
    values: np.ndarray, variances: np.ndarray, along: np.ndarray, used: np.ndarray
) -> LineResiduals:
    """Each row's offset from a least-squares line fitted over the used rows, with its sigma.

    ``values`` (K, C) are independent per row with variances (K, C); the line
    is ``alpha + beta * along`` per column (the ISO 230-1 least-squares
    reference line). var(r_i) = var_i - 2 h_ii var_i [i used] + sum_j h_ij^2 var_j,
    with the hat matrix h of the unweighted regression, computed in O(K).
    Shared by the single-axis straightness and the planar cross-axis figures.
    """
    y = np.asarray(values, float)
    var = np.asarray(variances, float)
    s = np.asarray(along, float)
    used = np.asarray(used, bool) & np.all(np.isfinite(y), axis=1) & np.all(np.isfinite(var), axis=1)
    n = int(used.sum())
    if n < 3:
        nan = np.full(y.shape, np.nan)
        return LineResiduals(nan, nan.copy())
    su = s[used]
    mean_s = su.mean()
    a = s - mean_s
    Sxx = float(np.sum(a[used] ** 2))
    coef_b = (a[used] @ y[used]) / Sxx
    fitted = y[used].mean(axis=0)[None, :] + a[:, None] * coef_b[None, :]
    resid = y - fitted
    vu, au = var[used], a[used]
    # h(s_i, j) = 1/n + a_i a_j / Sxx
    sum_h2 = (vu.sum(axis=0)[None, :] / n**2 + 2.0 * a[:, None] * (au @ vu)[None, :] / (n * Sxx)
              + a[:, None] ** 2 * (au**2 @ vu)[None, :] / Sxx**2)
    h_ii = 1.0 / n + a**2 / Sxx
    var_r = var + sum_h2 - 2.0 * np.where(used, h_ii, 0.0)[:, None] * var
    return LineResiduals(resid, np.sqrt(np.maximum(var_r, 0.0)))


def board_plane_motion(
    views: ConstantOrientationViews,
    R: np.ndarray,
    u_board: np.ndarray,
    X0: np.ndarray,
    along_mm: np.ndarray,
    used: np.ndarray,
) -> BoardPlaneMotion:
    """Straightness v1, v2 at the board plane and the image rotation, with sigmas.

    The displacement at the board plane is D_i = X0 - R^T b_i (the camera
    centre a constant-orientation camera would have); its components along
    v1, v2 of the motion frame, minus their least-squares line against the
    position ``along_mm``, are the straightness. Sigma per view uses this
    fit's a-posteriori noise over the used views.
    """
    used = np.asarray(used, bool) & np.isfinite(views.ssr)
    dof = int(views.n_obs[used].sum()) - N_VIEW_PARAMS * int(used.sum())
    sigma2 = float(views.ssr[used].sum()) / dof if dof > 0 else np.nan
    frame = motion_frame(R, u_board)
    F_perp = frame[:, 1:]
    D = X0[None, :] - views.b @ R  # b @ R == (R^T b_i) rows
    perp_um = 1e3 * D @ F_perp  # shape (K, 2)
    M = -(R @ F_perp)  # d perp / d b = -F_perp^T R^T: rows of M^T
    cov_b = sigma2 * views.cov_unit[:, :3, :3]
    var_perp = 1e6 * np.einsum("ia,kij,ja->ka", M, cov_b, M)
    res = line_residuals(perp_um, var_perp, along_mm, used)
    rot = -1e6 * views.phi  # the board turns by phi in the camera frame: the camera turned by -phi
    rot_sigma = 1e6 * np.sqrt(sigma2 * views.cov_unit[:, 3, 3])
    return BoardPlaneMotion(res.values, res.sigma, rot, rot_sigma, frame, float(np.sqrt(sigma2)))


def board_plane_offsets(C_board: np.ndarray, w_board: np.ndarray, X0: np.ndarray) -> np.ndarray:
    """Where a constant-orientation camera appears for true poses: D = C + w x (X0 - C), shape (K, 3).

    A small carriage rotation w (board frame) of a camera at C moves the line
    of sight at the board point X0 by w x (X0 - C); the rotation about the
    line of sight itself moves nothing there. Simulator truth for
    :func:`board_plane_motion` (first order in w, independent of the solver).
    """
    C = np.asarray(C_board, float)
    return C + np.cross(np.asarray(w_board, float), X0[None, :] - C)


def board_plane_displacements(R: np.ndarray, t: np.ndarray, X0: np.ndarray, R0: np.ndarray) -> np.ndarray:
    """Where a camera of orientation R0 sees the board centre X0 as the poses (R, t) do: D = X0 - R0^T (R X0 + t).

    Exact for any rotation (:func:`board_plane_offsets` is its first order): the board centre's line of sight,
    the displacement at the board plane that the positions and straightness measure. Shape (K, 3).
    """
    b = np.einsum("kij,j->ki", np.asarray(R, float), X0) + np.asarray(t, float)
    return X0[None, :] - b @ np.asarray(R0, float)


def path_direction(D: np.ndarray, used: np.ndarray, towards: np.ndarray) -> np.ndarray:
    """Unit direction of the least-squares line through the used rows of D (K, 3), oriented along ``towards``."""
    Dv = D[np.asarray(used, bool) & np.all(np.isfinite(D), axis=1)]
    if Dv.shape[0] < 2:
        return np.asarray(towards, float) / np.linalg.norm(towards)
    a = np.linalg.svd(Dv - Dv.mean(axis=0), full_matrices=False)[2][0]
    return a if a @ towards >= 0 else -a


def start_from_line(R: np.ndarray, translations: np.ndarray, X0: np.ndarray) -> np.ndarray:
    """b_i = R X0 + t_i for the LPS model's translations t_i, shape (K, 3)."""
    return (R @ X0)[None, :] + np.asarray(translations, float)



def board_plane_from_model(
    R: np.ndarray,
    translations: np.ndarray,
    u_board: np.ndarray,
    X: np.ndarray,
    corners: np.ndarray,
    mask: np.ndarray,
    intrinsics: CameraIntrinsics,
    along_mm: np.ndarray,
    usable: np.ndarray,
    used: np.ndarray,
    start: PoseNormals | None = None,
) -> BoardPlaneMotion:
    """The whole step after the joint LM: per-view fit from the model's t_i, then the figures.

    Views without a board get NaN; outlier views (usable, not used) get their
    own figures relative to the used views' line. ``start``: the pose blocks
    at the model's poses over ``mask & usable``, when the caller has them.
    """
    X0 = np.asarray(X, float).mean(axis=0)
    usable = np.asarray(usable, bool)
    used = np.asarray(used, bool) & usable
    views = solve_views(R, start_from_line(R, translations, X0), X, X0, corners, mask & usable[:, None], intrinsics,
                        refine_rotation=used, start=start)
    out = board_plane_motion(views, views.R, u_board, X0, along_mm, used)
    for arr in (out.straightness_um, out.straightness_sigma_um, out.image_rotation_urad, out.image_rotation_sigma_urad):
        arr[~usable] = np.nan
    return out


def rotation_read_as_shift(corners_px: np.ndarray, intrinsics: CameraIntrinsics, directions_cam: np.ndarray
                           ) -> np.ndarray:
    """How much a carriage rotation's share of a board-plane displacement is overstated, per direction (C,).

    This model holds the camera's orientation constant, so it reads a rotation w about an axis across the view
    as a displacement Z w at the board plane. A rotation about the camera's x axis moves a corner at normalized
    image coordinates (x, y) by (1 + y^2) w, a displacement by w alone: the fitted displacement is (1 + mean
    y^2) Z w. For the direction d (camera frame, column of ``directions_cam`` (3, C)) the overstatement is
    mean((n . d_xy)^2) over the corners seen (``corners_px`` (K, N, 2), NaN where missing): 0.46 % of a 1.16 mm
    roll bow on the honesty campaign's ``motions`` stage (estimate minus truth 0.35-0.52 % over 10 seeds).
    """
    c = np.asarray(corners_px, float).reshape(-1, 2)
    c = c[np.all(np.isfinite(c), axis=1)]
    if not c.size:
        return np.zeros(np.asarray(directions_cam).shape[1])
    K = np.asarray(intrinsics.camera_matrix, float)
    n = np.c_[(c[:, 0] - K[0, 2]) / K[0, 0], (c[:, 1] - K[1, 2]) / K[1, 1]]
    return np.mean((n @ np.asarray(directions_cam, float)[:2]) ** 2, axis=0)
