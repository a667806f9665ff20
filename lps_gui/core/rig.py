"""A simulated rig: board, camera, how the camera sits on the stage, and the stage's errors.

The rig turns a :class:`TruePose` of the carriage into camera poses, so the
point simulator, the image simulator and the simulated stage share one truth.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.core.board import Board
from lps_gui.core.camera_model import CameraIntrinsics
from lps_gui.core.lps_model import motion_frame, unit
from lps_gui.core.rotation import exp_so3
from lps_gui.core.stage_errors import StageErrorModel, TruePose


def carried_camera_poses(R_cam_board: np.ndarray, C_board: np.ndarray, w_board: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Poses of a camera whose carriage sits at centres ``C_board`` (K, 3) mm, rotated by ``w_board`` (K, 3) rad.

    The carriage rotates by Q = exp(w) in the board frame, so the camera's
    orientation R_cam_board becomes R Q^T and t = -R C. Returns R (K, 3, 3), t (K, 3).
    """
    Q = exp_so3(w_board)
    R = np.einsum("ij,kjl->kil", R_cam_board, np.transpose(Q, (0, 2, 1)))
    t = -np.einsum("kij,kj->ki", R, C_board)
    return R, t


@dataclass(frozen=True)
class Rig:
    """Everything the simulators need to know about the physical set-up."""

    board: Board
    intrinsics: CameraIntrinsics
    R_cam_board: np.ndarray  # shape (3, 3): camera orientation with no angular error
    C0_board: np.ndarray  # shape (3,) mm: camera centre at commanded position 0
    u_board: np.ndarray  # shape (3,): unit motion direction of the carriage
    errors: StageErrorModel

    def frame(self) -> np.ndarray:
        """Motion frame (u, v1, v2) as columns in the board frame."""
        return motion_frame(self.R_cam_board, self.u_board)

    def camera_poses(self, pose: TruePose) -> tuple[np.ndarray, np.ndarray]:
        """Camera poses for true carriage poses.

        Returns R_cam_board shape (K, 3, 3) and t_cam_board shape (K, 3) mm.
        The carriage rotates by Q = exp(roll u + pitch v1 + yaw v2) in the
        board frame, so the camera's orientation becomes R Q^T.
        """
        F = self.frame()
        u, v1, v2 = F[:, 0], F[:, 1], F[:, 2]
        C = (
            self.C0_board[None, :]
            + pose.axis_mm[:, None] * u[None, :]
            + 1e-3 * (pose.straightness_um[:, :1] * v1[None, :] + pose.straightness_um[:, 1:2] * v2[None, :])
        )
        return carried_camera_poses(self.R_cam_board, C, 1e-6 * pose.angles_urad @ F.T)

    @classmethod
    def facing_board(
        cls,
        board: Board,
        intrinsics: CameraIntrinsics,
        distance_mm: float,
        travel_mm: tuple[float, float],
        errors: StageErrorModel | None = None,
        tilt_deg: tuple[float, float, float] = (2.0, -3.0, 1.0),
        axis_misalignment_deg: tuple[float, float] = (0.5, -0.3),
    ) -> "Rig":
        """A camera looking at the board from ``distance_mm``, moving along the board's x.

        The board centre is seen at mid-travel; the camera is slightly tilted
        and the axis slightly misaligned, as on any real rig.
        """
        R = exp_so3(np.deg2rad(np.asarray(tilt_deg)))
        a, b = np.deg2rad(axis_misalignment_deg)
        u = unit(np.array([np.cos(a) * np.cos(b), np.sin(a), np.sin(b)]))
        mid = 0.5 * (travel_mm[0] + travel_mm[1])
        optical_axis_board = R.T @ np.array([0.0, 0.0, 1.0])
        C_mid = board.centre_mm() - distance_mm * optical_axis_board
        C0 = C_mid - mid * u
        return cls(board, intrinsics, R, C0, u, errors or StageErrorModel())
