"""The rectified light field of a measured stage (issue 38, SPEC 17): one virtual camera, every view's rotation
to it, and whether the measured positions form a uniform grid.

The virtual camera has the measured common orientation turned so that its image plane is parallel to the
motion: x along the motion axis (line) or the X axis (plane), z the normal of the motion closest to the
common optical axis, y = z x x. Its focal length is the mean of fx, fy; its principal point is put where
the common optical axis lands, so a view keeps its field. A view's true orientation is the common one
with that view's residual rotation (R_i = E_i R Q_i^T: Q_i the carriage's tilt in the world frame, E_i
its image rotation about the optical axis); the rotation that rectifies it is R_v R_i^T (OpenCV's ``R``
of ``initUndistortRectifyMap``). Nothing moves a view's centre: rectification is a rotation only.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.models.lps_model import motion_frame, unit

UNIFORM_K = 2.0  # SPEC 17: every position within 2 sigma of a uniform grid


@dataclass(frozen=True)
class VirtualCamera:
    """The one camera every rectified view is seen through: orientation (virtual from world), K, size."""

    R: np.ndarray  # shape (3, 3): rows x_v, y_v, z_v in the world (board) frame
    K: np.ndarray  # shape (3, 3)
    image_size: tuple[int, int]

    @property
    def focal_px(self) -> float:
        return float(self.K[0, 0])

    def to_dict(self) -> dict[str, Any]:
        return {"image_size": list(self.image_size), "camera_matrix": self.K.tolist(), "R_cam_board": self.R.tolist()}


def virtual_camera(R_common: np.ndarray, axes_board: np.ndarray, intrinsics: CameraIntrinsics) -> VirtualCamera:
    """The virtual camera of a line (``axes_board`` (3,): u) or a plane ((3, 2): the X and Y motions)."""
    R = np.asarray(R_common, dtype=float)
    A = np.asarray(axes_board, dtype=float).reshape(3, -1)
    x = unit(A[:, 0]) * np.sign(A[:, 0] @ R[0])  # rows run with the motion, left to right in the image
    if A.shape[1] == 1:
        z = unit(R[2] - (R[2] @ x) * x)
    else:
        z = unit(np.cross(A[:, 0], A[:, 1]))
        z = z * np.sign(z @ R[2])
        x = unit(x - (x @ z) * z)
    Rv = np.stack([x, np.cross(z, x), z])
    f = 0.5 * (intrinsics.fx + intrinsics.fy)
    d = Rv @ R.T @ np.array([0.0, 0.0, 1.0])  # the common optical axis in the virtual frame
    K = np.array([[f, 0.0, intrinsics.cx - f * d[0] / d[2]], [0.0, f, intrinsics.cy - f * d[1] / d[2]], [0.0, 0.0, 1.0]])
    return VirtualCamera(Rv, K, tuple(int(v) for v in intrinsics.image_size))


def view_rotations(R_common: np.ndarray, tilt_world_rad: np.ndarray, image_rotation_rad: np.ndarray) -> np.ndarray:
    """Every view's orientation (K, 3, 3): the common R with the carriage's tilt ``tilt_world_rad`` (K, 3)
    (a rotation vector in the world frame) and the image rotation about the optical axis (K,), both rad."""
    w = np.asarray(tilt_world_rad, dtype=float).reshape(-1, 3)
    phi = np.asarray(image_rotation_rad, dtype=float).ravel()
    E = exp_so3(phi[:, None] * np.array([0.0, 0.0, 1.0]))
    Q = exp_so3(w)
    return np.einsum("kij,jl,kml->kim", E, np.asarray(R_common, dtype=float), Q)


def rectifying_rotations(vc: VirtualCamera, R_views: np.ndarray) -> np.ndarray:
    """R_v R_i^T (K, 3, 3): from each view's camera frame to the virtual camera's."""
    return np.einsum("ij,kmj->kim", vc.R, np.asarray(R_views, dtype=float))


def tilt_from_board_shift(R_common: np.ndarray, u_board: np.ndarray, board_depth_mm: float,
                          shift_v1_mm: np.ndarray) -> np.ndarray:
    """The tilt (K, 3) rad, world frame, that shifts the line of sight at the board by ``shift_v1_mm`` along v1.

    One board sees a tilt across the motion and a straightness error as one shift at the board (SPEC 11).
    A light field needs the image shift wherever the scene is, so the shift is taken as a tilt about
    the axis that moves the line of sight along v1 (w = a x delta / Z): exact for scene points at the
    board's distance whatever the split, and at any distance when the tilt dominates (100 urad at 600 mm is
    60 um, a lead-screw stage's straightness a few um over a light field's travel).
    """
    R = np.asarray(R_common, dtype=float)
    v1 = motion_frame(R, u_board)[:, 1]
    delta = np.asarray(shift_v1_mm, dtype=float).ravel()[:, None] * v1
    return np.cross(R[2], delta) / float(board_depth_mm)


@dataclass(frozen=True)
class GridCheck:
    """How far measured positions are from a uniform grid (one spacing per axis, fitted)."""

    uniform: bool
    complete: bool  # every grid node exactly once
    shape: tuple[int, ...]  # views per axis
    spacing_mm: np.ndarray  # (D,)
    origin_mm: np.ndarray  # (D,)
    residual_um: np.ndarray  # (K, D)
    z: np.ndarray  # (K, D): |residual| / sigma
    worst: int  # view with the largest z
    worst_axis: int


def grid_indices(nominal_mm: np.ndarray) -> tuple[np.ndarray, tuple[int, ...]]:
    """Each view's node index per axis (K, D) from its nominal position, and the grid's size per axis."""
    t = np.asarray(nominal_mm, dtype=float).reshape(len(nominal_mm), -1)
    idx = np.zeros(t.shape, dtype=int)
    shape = []
    for a in range(t.shape[1]):
        values = np.unique(np.round(t[:, a], 9))
        if values.size == 1:
            shape.append(1)
            continue
        step = float(np.median(np.diff(values)))
        idx[:, a] = np.rint((t[:, a] - values[0]) / step).astype(int)
        shape.append(int(idx[:, a].max()) + 1)
    return idx, tuple(shape)


def uniform_grid(positions_mm: np.ndarray, nominal_mm: np.ndarray, sigma_um: np.ndarray,
                 k: float = UNIFORM_K) -> GridCheck:
    """Fit position = origin + spacing * node per axis (weighted by 1/sigma^2) and test every view at k sigma."""
    p = np.asarray(positions_mm, dtype=float).reshape(len(positions_mm), -1)
    s = np.asarray(sigma_um, dtype=float).reshape(p.shape)
    idx, shape = grid_indices(nominal_mm)
    nodes = np.ravel_multi_index(tuple(idx.T), shape) if all(n > 0 for n in shape) else np.arange(len(p))
    complete = len(p) == int(np.prod(shape)) and np.unique(nodes).size == len(p)
    spacing, origin, res = np.zeros(p.shape[1]), np.zeros(p.shape[1]), np.zeros(p.shape)
    for a in range(p.shape[1]):
        w = 1.0 / np.maximum(s[:, a], 1e-6) ** 2
        A = np.stack([np.ones(len(p)), idx[:, a].astype(float)], axis=1)
        coef = np.linalg.lstsq(A * np.sqrt(w)[:, None], p[:, a] * np.sqrt(w), rcond=None)[0]
        origin[a], spacing[a] = coef
        res[:, a] = 1e3 * (p[:, a] - A @ coef)
    z = np.abs(res) / np.maximum(s, 1e-9)
    worst = int(np.unravel_index(int(np.argmax(z)), z.shape)[0])
    worst_axis = int(np.argmax(z[worst]))
    return GridCheck(bool(complete and np.all(z <= k)), bool(complete), shape, spacing, origin, res, z, worst,
                     worst_axis)
