"""The LPS model of SPEC section 3 (paper Eq. 4).

The board is fixed, the camera translates along a line with a constant
orientation: ``t_i = l0 + s_i n`` in the camera frame, with ``n = -R u`` and
``u`` the unit motion direction in the board frame. The direction lives on
the unit sphere; solvers update it through a 2-D tangent step.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def unit(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def sphere_tangent_basis(n: np.ndarray) -> np.ndarray:
    """Two orthonormal vectors perpendicular to unit ``n``, shape (3, 2)."""
    n = unit(n)
    helper = np.eye(3)[int(np.argmin(np.abs(n)))]
    b1 = unit(np.cross(n, helper))
    b2 = np.cross(n, b1)
    return np.stack([b1, b2], axis=1)


def sphere_retract(n: np.ndarray, delta: np.ndarray, basis: np.ndarray | None = None) -> np.ndarray:
    """Move unit ``n`` by a tangent step ``delta`` (shape (2,)) and renormalize."""
    B = sphere_tangent_basis(n) if basis is None else basis
    return unit(n + B @ np.asarray(delta, dtype=float))


def motion_frame(R_cam_board: np.ndarray, u_board: np.ndarray) -> np.ndarray:
    """Orthonormal frame (u, v1, v2) of the motion, as columns in the board frame.

    ``u`` is the motion direction, ``v1`` the perpendicular closest to the
    camera's y axis, ``v2 = u x v1`` (roughly the viewing direction).
    Straightness is measured along v1 and v2; roll is about u, pitch about v1,
    yaw about v2.
    """
    u = unit(u_board)
    y_cam_in_board = np.asarray(R_cam_board)[1, :]
    v1 = unit(y_cam_in_board - np.dot(y_cam_in_board, u) * u)
    v2 = np.cross(u, v1)
    return np.stack([u, v1, v2], axis=1)


@dataclass(frozen=True)
class LpsLine:
    """Common orientation and line of the camera (SPEC 3); lengths in mm."""

    R_cam_board: np.ndarray  # shape (3, 3)
    l0_cam: np.ndarray  # shape (3,): t at s = 0
    n_cam: np.ndarray  # shape (3,): unit direction of t as s grows

    def translations(self, s_mm: np.ndarray) -> np.ndarray:
        """t_i = l0 + s_i n, shape (K, 3)."""
        return self.l0_cam[None, :] + np.asarray(s_mm, dtype=float)[:, None] * self.n_cam[None, :]

    @property
    def u_board(self) -> np.ndarray:
        """Motion direction of the camera centre in the board frame."""
        return -self.R_cam_board.T @ self.n_cam

    @property
    def C0_board(self) -> np.ndarray:
        """Camera centre at s = 0 in the board frame."""
        return -self.R_cam_board.T @ self.l0_cam

    def camera_centres_board(self, s_mm: np.ndarray) -> np.ndarray:
        """C_i = C_0 + s_i u in the board frame, shape (K, 3)."""
        return self.C0_board[None, :] + np.asarray(s_mm, dtype=float)[:, None] * self.u_board[None, :]

    def frame(self) -> np.ndarray:
        """Motion frame (u, v1, v2) as columns, see :func:`motion_frame`."""
        return motion_frame(self.R_cam_board, self.u_board)
