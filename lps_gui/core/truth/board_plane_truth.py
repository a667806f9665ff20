"""The positions a constant-orientation model sees of true poses: a lean 1-D least squares per view.

A simulated session's truth at the board plane (``core.simulate.board_plane_positions``)
is, per view, the position s along the rig's nominal line (R, l0, n fixed)
whose noise-free projections best match the true pose's projections, in
pixels. It used to run the estimator's joint-LM linearization (8 shared
columns and a 3x3 block per corner) over all K*N corners at once; only
d uv / d s is needed, and all K*N at once leaves the caches for memory on
every one of the ~40 array operations. Here each block of views is
projected and solved while its arrays stay in cache, with the projection
differentiated along the one direction n only (forward mode), and the
residual taken in normalized distorted coordinates scaled by (fx, fy),
which is the pixel residual without the principal point.

The solution is the same least-squares minimum as before (Gauss-Newton on
the same pixel residuals, to 1e-12 mm; tests/core/test_board_plane_truth.py
compares the two); the work is linear in K.
"""
from __future__ import annotations

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics, project_parts

BLOCK_VIEWS = 64  # views per block: its (64, N) arrays stay in L2 at N = 540
TOL_MM = 1e-12  # done when the step, or what is left after it at the contraction seen, is below this
MAX_ITERATIONS = 12


def _distorted_along(x: np.ndarray, y: np.ndarray, z: np.ndarray, n: np.ndarray, intr: CameraIntrinsics
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(xd, yd) and their derivatives along the camera-frame direction ``n`` (3,): d/ds of (x, y, z) + s n.

    The distortion of :func:`lps_gui.core.geometry.camera_model.project_parts`, differentiated along one
    direction only (forward mode): 2 derivatives per corner where its Jacobian has 6.
    """
    if intr.has_higher:  # rational / thin-prism lens: the full Jacobian (the simulator's true lens, rarely)
        pp = project_parts(x, y, z, intr, want_jacobian=True)
        return (pp.xd, pp.yd, sum(d * c for d, c in zip(pp.du, n)) / intr.fx,
                sum(d * c for d, c in zip(pp.dv, n)) / intr.fy)
    k1, k2, p1, p2, k3 = intr.dist
    inv_z = 1.0 / z
    xp, yp = x * inv_z, y * inv_z
    dxp, dyp = (n[0] - xp * n[2]) * inv_z, (n[1] - yp * n[2]) * inv_z
    xx, yy, xy = xp * xp, yp * yp, xp * yp
    r2 = xx + yy
    dr2 = 2.0 * (xp * dxp + yp * dyp)
    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    dradial = dr2 * (k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2))
    dxy = dxp * yp + xp * dyp
    xd = xp * radial + 2.0 * p1 * xy + p2 * (r2 + 2.0 * xx)
    yd = yp * radial + p1 * (r2 + 2.0 * yy) + 2.0 * p2 * xy
    dxd = dxp * radial + xp * dradial + 2.0 * p1 * dxy + p2 * (dr2 + 4.0 * xp * dxp)
    dyd = dyp * radial + yp * dradial + p1 * (dr2 + 4.0 * yp * dyp) + 2.0 * p2 * dxy
    return xd, yd, dxd, dyd


def positions_on_line(
    R_true: np.ndarray,
    t_true: np.ndarray,
    X_board: np.ndarray,
    intrinsics: CameraIntrinsics,
    R_line: np.ndarray,
    l0_cam: np.ndarray,
    n_cam: np.ndarray,
    s_start: np.ndarray,
) -> np.ndarray:
    """Each view's best position s on the line t = l0 + s n (orientation R_line) for its true pose.

    Parameters
    ----------
    R_true, t_true : shape (K, 3, 3), (K, 3) mm: the true camera poses (board to camera)
    X_board : shape (N, 3) mm, board points
    R_line, l0_cam, n_cam : shape (3, 3), (3,) mm, (3,): the constant-orientation line, held fixed
    s_start : shape (K,) mm, where Gauss-Newton starts (the axis positions)

    Returns s, shape (K,) mm: per view, the minimum of the summed squared
    pixel distances between the line's projections and the true pose's.
    """
    fx2, fy2 = intrinsics.fx ** 2, intrinsics.fy ** 2
    n = np.asarray(n_cam, dtype=float)
    a = X_board @ np.asarray(R_line).T + np.asarray(l0_cam)  # shape (N, 3): the line's points at s = 0
    a_x, a_y, a_z = (np.ascontiguousarray(a[:, j]) for j in range(3))
    XT = np.ascontiguousarray(X_board.T)  # shape (3, N)
    s_out = np.array(s_start, dtype=float)
    for lo in range(0, s_out.size, BLOCK_VIEWS):
        b = slice(lo, lo + BLOCK_VIEWS)
        xt = np.matmul(R_true[b], XT) + t_true[b, :, None]  # shape (k, 3, N)
        true = project_parts(xt[:, 0], xt[:, 1], xt[:, 2], intrinsics)  # the camera model's own projection
        xd_true, yd_true = true.xd, true.yd
        s = s_out[b].copy()
        previous = np.full(s.shape, np.inf)
        for _ in range(MAX_ITERATIONS):
            sc = s[:, None]
            xd, yd, dxd, dyd = _distorted_along(a_x + sc * n[0], a_y + sc * n[1], a_z + sc * n[2], n, intrinsics)
            # pixel residual u - u_true = fx (xd - xd_true); Gauss-Newton on sum |r|^2
            g = fx2 * np.einsum("kn,kn->k", dxd, xd - xd_true) + fy2 * np.einsum("kn,kn->k", dyd, yd - yd_true)
            D = fx2 * np.einsum("kn,kn->k", dxd, dxd) + fy2 * np.einsum("kn,kn->k", dyd, dyd)
            step = np.where(D > 0, -g / np.where(D > 0, D, 1.0), 0.0)
            s += step
            size = np.abs(step)
            # Gauss-Newton contracts by rho = size / previous per step (or faster): size rho / (1 - rho) is left
            shrank = (size < previous) & np.isfinite(previous)  # not on the first step: no contraction seen yet
            left = np.where(shrank, size * size / np.where(shrank, previous - size, 1.0), np.inf)
            if np.all((size < TOL_MM) | (left < TOL_MM)):
                break
            previous = size
        s_out[b] = s
    return s_out
