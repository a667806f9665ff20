"""core/models/lps_model: the line of SPEC 3, its frame, and the sphere tangent step of the direction."""
from __future__ import annotations

import numpy as np

from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.models.lps_model import LpsLine, motion_frame, sphere_retract, sphere_tangent_basis, unit
from tests.core.finite_differences import central_jacobian


def test_translations_and_camera_centres_describe_one_line():
    R = exp_so3(np.array([0.1, -0.2, 0.05]))
    u = unit(np.array([1.0, 0.02, -0.01]))
    C0 = np.array([100.0, 50.0, -600.0])
    line = LpsLine(R, -R @ C0, -R @ u)
    s = np.array([0.0, 1.5, 40.0])
    t = line.translations(s)
    C = line.camera_centres_board(s)
    assert np.allclose(C, -np.einsum("ji,kj->ki", R, t))  # C_i = -R^T t_i
    assert np.allclose(line.u_board, u) and np.allclose(line.C0_board, C0)
    assert np.allclose(C - C0, s[:, None] * u)


def test_motion_frame_is_orthonormal_with_v1_towards_the_camera_y_axis():
    R = exp_so3(np.array([0.3, 0.1, -0.2]))
    F = motion_frame(R, np.array([2.0, 0.1, 0.0]))
    assert np.allclose(F.T @ F, np.eye(3), atol=1e-12) and np.linalg.det(F) > 0
    assert np.allclose(F[:, 0], unit(np.array([2.0, 0.1, 0.0])))
    y_cam = R[1, :]
    assert np.dot(F[:, 1], y_cam) > 0 and abs(np.dot(F[:, 2], y_cam)) < 1e-12


def test_tangent_step_derivative_is_the_basis():
    """d retract(n, delta) / d delta at 0 is the tangent basis: the solvers' direction columns rely on it."""
    n = unit(np.array([0.1, -0.3, 0.9]))
    B = sphere_tangent_basis(n)
    assert np.allclose(B.T @ B, np.eye(2)) and np.allclose(n @ B, 0.0)
    J = central_jacobian(lambda d: sphere_retract(n, d, B), 2, 1e-6)
    assert np.allclose(J, B, atol=1e-9)
    assert np.isclose(np.linalg.norm(sphere_retract(n, np.array([0.3, -0.2]))), 1.0)
