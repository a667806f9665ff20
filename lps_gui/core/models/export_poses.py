"""Every capture's camera pose under the estimated model, in the conventions of 3-D tools.

World = the board frame (SPEC 2, mm). The model holds one rotation R for every
view; the camera centre is C_i = -R^T l0 + s_i u (+ the measured straightness
along v1, v2 where it is resolved), so t_i = -R C_i.

- COLMAP (images.txt): world-to-camera, quaternion QW QX QY QZ (Hamilton,
  scalar first) of R and translation t, camera axes x right, y down, z forward.
- nerfstudio (transforms.json): camera-to-world 4x4 in OpenGL camera axes
  (x right, y up, z backward): [R^T diag(1,-1,-1) | C].
- Pixels: OpenCV puts pixel centres at integers; COLMAP and nerfstudio at
  +0.5 (the image corner is 0), so their cx, cy are OpenCV's + 0.5.
"""
from __future__ import annotations

import numpy as np

from lps_gui.core.models.lps_model import motion_frame

PIXEL_CENTRE_SHIFT = 0.5  # OpenCV (centre at 0) -> COLMAP / nerfstudio (corner at 0)
OPENGL_FROM_OPENCV = np.diag([1.0, -1.0, -1.0])


def camera_centres(R_cam_board: np.ndarray, l0_cam: np.ndarray, n_cam: np.ndarray, s_mm: np.ndarray,
                   straightness_mm: np.ndarray | None = None) -> np.ndarray:
    """Camera centres in the board frame (K, 3) on the fitted line, plus straightness (K, 2) along v1, v2."""
    R = np.asarray(R_cam_board, dtype=float)
    u = -R.T @ np.asarray(n_cam, dtype=float)
    C = -R.T @ np.asarray(l0_cam, dtype=float) + np.asarray(s_mm, dtype=float)[:, None] * u
    if straightness_mm is not None:
        frame = motion_frame(R, u)
        C = C + np.asarray(straightness_mm, dtype=float) @ frame[:, 1:].T
    return C


def rotation_to_quaternion(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z), Hamilton, w >= 0, of a rotation matrix (Shepperd's method)."""
    m = np.asarray(R, dtype=float)
    tr = np.trace(m)
    if tr > 0:
        s = 2.0 * np.sqrt(tr + 1.0)
        q = np.array([0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s])
    else:
        i = int(np.argmax(np.diag(m)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(1.0 + m[i, i] - m[j, j] - m[k, k])
        q = np.empty(4)
        q[0] = (m[k, j] - m[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (m[j, i] + m[i, j]) / s
        q[1 + k] = (m[k, i] + m[i, k]) / s
    q /= np.linalg.norm(q)
    return q if q[0] >= 0 else -q


def world_to_camera(R_cam_board: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """Translations t_i = -R C_i (K, 3) of the world-to-camera poses."""
    return -(np.asarray(centres, dtype=float) @ np.asarray(R_cam_board, dtype=float).T)


def camera_to_world_opengl(R_cam_board: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """nerfstudio's transform_matrix (4x4) of one view."""
    T = np.eye(4)
    T[:3, :3] = np.asarray(R_cam_board, dtype=float).T @ OPENGL_FROM_OPENCV
    T[:3, 3] = centre
    return T
