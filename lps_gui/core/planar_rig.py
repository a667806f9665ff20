"""The true motion of a simulated XY gantry, and the rig that turns it into camera poses.

Each axis is a lead-screw stage with the error model of
:class:`~lps_gui.core.stage_errors.StageErrorModel` (scale, periodic error,
backlash, repeatability, two straightness profiles, three angles, each a
function of that axis' own commanded position). The axes are not square:
the +Y motion direction makes 90 deg + ``squareness_urad`` with +X.

Stage-plane coordinates (mm) are in an orthonormal frame with x along the
X-axis motion and y perpendicular to it in the plane of motion (SPEC 10).
Straightness profile 0 of an axis is in the plane (X's along y, Y's along x),
profile 1 out of the plane (along the plane normal).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lps_gui.core.board import Board
from lps_gui.core.camera_model import CameraIntrinsics
from lps_gui.core.rig import carried_camera_poses
from lps_gui.core.rotation import exp_so3
from lps_gui.core.stage_errors import StageErrorModel


@dataclass(frozen=True)
class PlanarTruePose:
    """Where the carriage really is, for K commanded (x, y) positions."""

    plane_mm: np.ndarray  # shape (K, 2): true position in the stage plane
    normal_um: np.ndarray  # shape (K,): out-of-plane displacement
    angles_urad: np.ndarray  # shape (K, 3): rotation about stage x, y and the plane normal


@dataclass(frozen=True)
class PlanarErrorModel:
    """Errors of an XY gantry: one :class:`StageErrorModel` per axis plus squareness."""

    x: StageErrorModel = field(default_factory=StageErrorModel)
    y: StageErrorModel = field(default_factory=StageErrorModel)
    squareness_urad: float = 0.0  # angle between +X and +Y motion minus 90 deg

    def true_pose(self, commanded_mm: np.ndarray, direction: np.ndarray,
                  rng: np.random.Generator | None = None) -> PlanarTruePose:
        """True pose for commanded (x, y) (shape (K, 2)) approached in ``direction`` (K, 2) of +-1."""
        c = np.atleast_2d(np.asarray(commanded_mm, dtype=float))
        d = np.broadcast_to(np.asarray(direction, dtype=float), c.shape)
        px = self.x.true_pose(c[:, 0], d[:, 0], rng)
        py = self.y.true_pose(c[:, 1], d[:, 1], rng)
        g = self.squareness_urad * 1e-6
        # the Y carriage moves along (-sin g, cos g); each axis' in-plane straightness is across its motion
        x_true = px.axis_mm - np.sin(g) * py.axis_mm + 1e-3 * py.straightness_um[:, 0]
        y_true = np.cos(g) * py.axis_mm + 1e-3 * px.straightness_um[:, 0]
        normal = px.straightness_um[:, 1] + py.straightness_um[:, 1]
        # X's roll is about x, Y's about y; pitch of X is about y (its v1 ~ y), of Y about x
        angles = np.stack([px.angles_urad[:, 0] + py.angles_urad[:, 1],
                           px.angles_urad[:, 1] + py.angles_urad[:, 0],
                           px.angles_urad[:, 2] + py.angles_urad[:, 2]], axis=-1)
        return PlanarTruePose(np.stack([x_true, y_true], axis=-1), normal, angles)

    def to_dict(self) -> dict[str, Any]:
        return {"x": self.x.to_dict(), "y": self.y.to_dict(), "squareness_urad": self.squareness_urad}

    @classmethod
    def from_dict(cls, d: dict[str, Any] | None) -> "PlanarErrorModel":
        d = d or {}
        return cls(StageErrorModel.from_dict(d.get("x")), StageErrorModel.from_dict(d.get("y")),
                   float(d.get("squareness_urad", 0.0)))


@dataclass(frozen=True)
class PlanarRig:
    """Board, camera and an XY gantry carrying the camera."""

    board: Board
    intrinsics: CameraIntrinsics
    R_cam_board: np.ndarray  # shape (3, 3): camera orientation with no angular error
    C0_board: np.ndarray  # shape (3,) mm: camera centre at commanded (0, 0)
    axes_board: np.ndarray  # shape (3, 3): columns e_x, e_y, e_n (stage frame in the board frame)
    errors: PlanarErrorModel

    def camera_centres(self, pose: PlanarTruePose) -> np.ndarray:
        """True camera centres in the board frame, shape (K, 3) mm."""
        E = self.axes_board
        return (self.C0_board[None, :] + pose.plane_mm @ E[:, :2].T
                + 1e-3 * pose.normal_um[:, None] * E[None, :, 2])

    def camera_poses(self, pose: PlanarTruePose) -> tuple[np.ndarray, np.ndarray]:
        """R_cam_board shape (K, 3, 3) and t_cam_board shape (K, 3) of the true poses."""
        return carried_camera_poses(self.R_cam_board, self.camera_centres(pose),
                                    1e-6 * pose.angles_urad @ self.axes_board.T)

    @classmethod
    def facing_board(
        cls,
        board: Board,
        intrinsics: CameraIntrinsics,
        distance_mm: float,
        centre_xy_mm: tuple[float, float],
        errors: PlanarErrorModel | None = None,
        tilt_deg: tuple[float, float, float] = (2.0, -3.0, 1.0),
        plane_misalignment_deg: tuple[float, float, float] = (0.5, -0.3, 0.4),
    ) -> "PlanarRig":
        """A camera array rig: the stage plane nearly parallel to the board, the board centre
        seen from ``distance_mm`` when the carriage is at ``centre_xy_mm``."""
        R = exp_so3(np.deg2rad(np.asarray(tilt_deg)))
        E = exp_so3(np.deg2rad(np.asarray(plane_misalignment_deg)))  # columns: e_x, e_y, e_n
        optical_axis_board = R.T @ np.array([0.0, 0.0, 1.0])
        C_mid = board.centre_mm() - distance_mm * optical_axis_board
        C0 = C_mid - E[:, :2] @ np.asarray(centre_xy_mm, dtype=float)
        return cls(board, intrinsics, R, C0, E, errors or PlanarErrorModel())

    def to_dict(self) -> dict[str, Any]:
        return {"R_cam_board": self.R_cam_board.tolist(), "C0_board": self.C0_board.tolist(),
                "axes_board": self.axes_board.tolist(), "stage_errors": self.errors.to_dict()}
