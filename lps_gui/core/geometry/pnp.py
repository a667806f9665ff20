"""Per-view pose with fixed intrinsics (paper Eq. 3): the baseline and every initializer."""
from __future__ import annotations

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.rotation import exp_so3


def solve_pnp(
    points_board: np.ndarray, corners_px: np.ndarray, intrinsics: CameraIntrinsics, refine: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pose of every view by cv2.solvePnP (iterative LM after a planar init).

    Parameters
    ----------
    points_board : shape (N, 3) mm
    corners_px : shape (K, N, 2), NaN where missing

    Returns
    -------
    R_cam_board shape (K, 3, 3), t_cam_board shape (K, 3) mm, ok shape (K,) bool.
    """
    import cv2

    K = corners_px.shape[0]
    R = np.tile(np.eye(3), (K, 1, 1))
    t = np.zeros((K, 3))
    ok = np.zeros(K, dtype=bool)
    Kmat, dist = intrinsics.camera_matrix, intrinsics.cv_dist
    for i in range(K):
        seen = np.all(np.isfinite(corners_px[i]), axis=-1)
        if seen.sum() < 6:
            continue
        obj = points_board[seen].astype(np.float64)
        img = corners_px[i, seen].astype(np.float64)
        planar = obj * np.array([1.0, 1.0, 0.0])  # IPPE needs z = 0; a bowed board (Board.warp_mm) is refined below
        try:
            good, rvec, tvec = cv2.solvePnP(planar, img, Kmat, dist, flags=cv2.SOLVEPNP_IPPE)
            if good and refine:
                rvec, tvec = cv2.solvePnPRefineLM(obj, img, Kmat, dist, rvec, tvec)
        except cv2.error:
            good = False
        if not good or not np.all(np.isfinite(tvec)) or tvec[2, 0] <= 0:
            continue
        R[i] = exp_so3(rvec.ravel())
        t[i] = tvec.ravel()
        ok[i] = True
    return R, t, ok
