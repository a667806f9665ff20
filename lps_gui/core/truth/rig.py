"""A simulated rig: board, camera, how the camera sits on the stage (one axis or an XY gantry), and the stage's errors.

The rig turns the carriage's true pose (:class:`TruePose` on one axis,
:class:`PlanarTruePose` on two) into camera poses, so the point simulator,
the image simulator and the simulated stage share one truth. One
:class:`Rig` of one or two axes faces the board (:func:`facing_camera`) and
carries the camera (:func:`carried_camera_poses`).

On a gantry, stage-plane coordinates (mm) are in an orthonormal frame with x
along the X-axis motion and y perpendicular to it in the plane of motion
(SPEC 10); the axes are not square (``PlanarErrorModel.squareness_urad``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.models.lps_model import motion_frame, unit
from lps_gui.core.truth.stage_errors import PlanarErrorModel, PlanarTruePose, StageErrorModel, TruePose


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


def facing_camera(board: Board, distance_mm: float, tilt_deg: tuple[float, float, float]
                  ) -> tuple[np.ndarray, np.ndarray]:
    """A camera slightly tilted by ``tilt_deg`` that sees the board centre from ``distance_mm``:
    its orientation R_cam_board (3, 3) and its centre (3,) mm in the board frame."""
    R = exp_so3(np.deg2rad(np.asarray(tilt_deg)))
    optical_axis_board = R.T @ np.array([0.0, 0.0, 1.0])
    return R, board.centre_mm() - distance_mm * optical_axis_board


@dataclass(frozen=True)
class Rig:
    """Everything the simulators need to know about the physical set-up, on one axis or an XY gantry.

    ``axes_board`` says how the stage moves in the board frame: on one axis
    the unit motion direction u, shape (3,); on a gantry the stage frame,
    shape (3, 3), columns e_x, e_y, e_n (SPEC 10). ``errors`` is the stage's
    error model of as many axes.
    """

    board: Board
    intrinsics: CameraIntrinsics
    R_cam_board: np.ndarray  # shape (3, 3): camera orientation with no angular error
    C0_board: np.ndarray  # shape (3,) mm: camera centre at commanded position 0 (or (0, 0))
    axes_board: np.ndarray  # shape (3,) on one axis, (3, 3) on a gantry
    errors: StageErrorModel | PlanarErrorModel

    @property
    def planar(self) -> bool:
        return np.ndim(self.axes_board) == 2

    @property
    def u_board(self) -> np.ndarray:
        """One axis: the unit motion direction of the carriage, shape (3,)."""
        return self.axes_board

    def frame(self) -> np.ndarray:
        """Columns (u, v1, v2) of the motion frame on one axis, (e_x, e_y, e_n) on a gantry, in the board frame."""
        return self.axes_board if self.planar else motion_frame(self.R_cam_board, self.axes_board)

    def camera_centres(self, pose: PlanarTruePose) -> np.ndarray:
        """A gantry's true camera centres in the board frame, shape (K, 3) mm."""
        E = self.axes_board
        return (self.C0_board[None, :] + pose.plane_mm @ E[:, :2].T
                + 1e-3 * pose.normal_um[:, None] * E[None, :, 2])

    def carriage_rotations(self, pose: TruePose | PlanarTruePose) -> np.ndarray:
        """The carriage's rotation vectors w (K, 3) rad in the board frame: its angles about the frame's axes."""
        return 1e-6 * np.asarray(pose.angles_urad, dtype=float) @ self.frame().T

    def camera_poses(self, pose: TruePose | PlanarTruePose) -> tuple[np.ndarray, np.ndarray]:
        """Camera poses for true carriage poses.

        Returns R_cam_board shape (K, 3, 3) and t_cam_board shape (K, 3) mm.
        The carriage rotates by Q = exp(w) in the board frame, w its angles
        about the frame's axes (roll u + pitch v1 + yaw v2 on one axis), so the
        camera's orientation becomes R Q^T.
        """
        if isinstance(pose, PlanarTruePose):
            return carried_camera_poses(self.R_cam_board, self.camera_centres(pose), self.carriage_rotations(pose))
        F = self.frame()
        u, v1, v2 = F[:, 0], F[:, 1], F[:, 2]
        C = (
            self.C0_board[None, :]
            + pose.axis_mm[:, None] * u[None, :]
            + 1e-3 * (pose.straightness_um[:, :1] * v1[None, :] + pose.straightness_um[:, 1:2] * v2[None, :])
        )
        return carried_camera_poses(self.R_cam_board, C, self.carriage_rotations(pose))

    @classmethod
    def facing_board(
        cls,
        board: Board,
        intrinsics: CameraIntrinsics,
        distance_mm: float,
        over_mm: tuple[float, float],
        errors: StageErrorModel | PlanarErrorModel | None = None,
        tilt_deg: tuple[float, float, float] = (2.0, -3.0, 1.0),
        misalignment_deg: tuple[float, ...] | None = None,
        planar: bool | None = None,
    ) -> "Rig":
        """A camera looking at the board from ``distance_mm``, slightly tilted, the motion slightly misaligned,
        as on any real rig.

        One axis: the camera moves along the board's x; ``over_mm`` is the
        travel (lo, hi), whose middle sees the board centre; the axis is
        misaligned by two angles (default (0.5, -0.3) deg). A gantry
        (``planar``, or a :class:`PlanarErrorModel`): the stage plane nearly
        parallel to the board, the board centre seen when the carriage is at
        ``over_mm`` = (x, y); the plane is turned by three angles (default
        (0.5, -0.3, 0.4) deg).
        """
        planar = isinstance(errors, PlanarErrorModel) if planar is None else planar
        R, C_mid = facing_camera(board, distance_mm, tilt_deg)
        if planar:
            E = exp_so3(np.deg2rad(np.asarray(misalignment_deg or (0.5, -0.3, 0.4))))  # columns: e_x, e_y, e_n
            C0 = C_mid - E[:, :2] @ np.asarray(over_mm, dtype=float)
            return cls(board, intrinsics, R, C0, E, errors or PlanarErrorModel())
        a, b = np.deg2rad(misalignment_deg or (0.5, -0.3))
        u = unit(np.array([np.cos(a) * np.cos(b), np.sin(a), np.sin(b)]))
        mid = 0.5 * (over_mm[0] + over_mm[1])
        C0 = C_mid - mid * u
        return cls(board, intrinsics, R, C0, u, errors or StageErrorModel())

    def to_dict(self) -> dict[str, Any]:
        """A gantry's rig as session.json's truth holds it (SPEC 10)."""
        return {"R_cam_board": self.R_cam_board.tolist(), "C0_board": self.C0_board.tolist(),
                "axes_board": self.axes_board.tolist(), "stage_errors": self.errors.to_dict()}
