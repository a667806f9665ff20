"""The light field's virtual camera, view rotations, board-shift tilts and the uniform-grid test."""
import numpy as np
import pytest

from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.metrology.epipolar import disparity_fit, vertical_disparity_rms
from lps_gui.core.models.lightfield_views import (
    rectifying_rotations,
    tilt_from_board_shift,
    uniform_grid,
    view_rotations,
    virtual_camera,
)
from lps_gui.core.models.lps_model import motion_frame, unit

INTR = CameraIntrinsics.from_values((640, 480), 600.0, 602.0, 322.0, 238.0)


def _pinhole(K, R, C, P):
    x = (P - C) @ R.T
    return x[:, :2] / x[:, 2:] @ K[:2, :2].T + K[:2, 2]


def test_the_virtual_camera_looks_across_the_motion_with_rows_along_it():
    R = exp_so3(np.array([0.02, -0.03, 0.01]))
    u = unit(np.array([1.0, 0.004, -0.003]))
    vc = virtual_camera(R, u, INTR)
    assert vc.R @ vc.R.T == pytest.approx(np.eye(3), abs=1e-12)
    assert vc.R[0] == pytest.approx(u, abs=1e-12)  # x along the motion (same sense as the camera's x here)
    assert abs(vc.R[2] @ u) < 1e-12 and vc.R[2] @ R[2] > 0.99
    assert vc.focal_px == pytest.approx(601.0)
    # the common optical axis lands where the camera's principal point was
    d = vc.R @ R.T @ np.array([0.0, 0.0, 1.0])
    assert (vc.K @ d / d[2])[:2] == pytest.approx([322.0, 238.0], abs=1e-9)
    flipped = virtual_camera(R, -u, INTR)  # a motion against the camera's x still runs left to right
    assert flipped.R[0] == pytest.approx(u, abs=1e-12)
    plane = virtual_camera(R, np.stack([u, unit(np.array([0.003, 1.0, 0.002]))], axis=1), INTR)
    assert abs(plane.R[2] @ u) < 1e-12 and plane.R[0] @ u > 0.9999


def test_rectified_views_keep_every_point_on_one_row_and_move_it_as_f_s_over_z():
    rng = np.random.default_rng(3)
    R = exp_so3(np.array([0.01, -0.02, 0.004]))
    u = unit(np.array([1.0, 0.003, 0.002]))
    s = np.linspace(0.0, 40.0, 9)
    C = np.array([5.0, -2.0, -500.0]) + s[:, None] * u
    tilt = rng.normal(0.0, 4e-4, (9, 3))  # the carriage's tilts, world frame
    phi = rng.normal(0.0, 3e-4, 9)  # image rotations
    R_views = view_rotations(R, tilt, phi)
    for k in range(9):  # the composition the module promises: E_k R Q_k^T
        assert R_views[k] == pytest.approx(exp_so3(np.array([0, 0, phi[k]])) @ R @ exp_so3(tilt[k]).T, abs=1e-12)
    vc = virtual_camera(R, u, INTR)
    R_rect = rectifying_rotations(vc, R_views)
    z = vc.R[2]
    P = np.array([10.0, 20.0, 0.0]) + rng.uniform(-60, 60, (30, 1)) * vc.R[0] + rng.uniform(-40, 40, (30, 1)) * vc.R[1]
    P = P + 300.0 * z  # a plane parallel to the motion
    uv = np.stack([_pinhole(INTR.camera_matrix, R_views[k], C[k], P) for k in range(9)])
    rays = np.concatenate([(uv - INTR.camera_matrix[:2, 2]) / [600.0, 602.0], np.ones((9, 30, 1))], axis=2)
    r = np.einsum("kij,knj->kni", R_rect, rays)
    rect = r[..., :2] / r[..., 2:] * vc.focal_px + vc.K[:2, 2]
    assert vertical_disparity_rms(rect[..., 1]) < 1e-9
    assert vertical_disparity_rms(uv[..., 1]) > 0.1
    fit = disparity_fit(rect[..., 0], s)
    depth = (P[0] - C[0]) @ z
    assert fit.residual_rms_px < 1e-9
    assert fit.depth_mm(vc.focal_px) == pytest.approx(depth, rel=1e-9)


def test_a_board_shift_across_the_motion_becomes_the_tilt_that_makes_it():
    R = exp_so3(np.array([0.01, -0.02, 0.004]))
    u = unit(np.array([1.0, 0.003, 0.002]))
    v1 = motion_frame(R, u)[:, 1]
    a = R[2]
    Z = 600.0
    w_true = 3e-4 * unit(np.cross(a, v1))  # the tilt that moves the line of sight along v1
    shift = np.cross(w_true, Z * a) @ v1  # where the board centre appears to move
    w = tilt_from_board_shift(R, u, Z, np.array([shift]))[0]
    assert w == pytest.approx(w_true, abs=1e-9)


def test_uniform_grid_names_the_view_off_the_grid():
    nominal = np.arange(10.0) * 2.0
    sigma = np.full(10, 2.0)
    pos = 0.5 + nominal * (1 + 25e-6)  # scale error and offset: still a uniform grid
    ok = uniform_grid(pos, nominal, sigma)
    assert ok.uniform and ok.complete and ok.shape == (10,)
    assert ok.spacing_mm[0] == pytest.approx(2.0 * (1 + 25e-6), rel=1e-12)
    bumped = pos.copy()
    bumped[6] += 0.008  # 8 um: 4 sigma
    bad = uniform_grid(bumped, nominal, sigma)
    assert not bad.uniform and bad.worst == 6 and bad.z[6, 0] > 3.0
    gap = uniform_grid(np.delete(pos, 4), np.delete(nominal, 4), np.delete(sigma, 4))
    assert not gap.complete and not gap.uniform
    xy = np.array([[x, y] for y in (0.0, 5.0, 10.0) for x in (0.0, 5.0, 10.0, 15.0)])
    plane = uniform_grid(xy, xy, np.full(xy.shape, 1.0))
    assert plane.uniform and plane.shape == (4, 3)


def test_vertical_disparity_ignores_points_seen_once():
    v = np.array([[1.0, 5.0, np.nan], [1.2, np.nan, 7.0], [0.8, np.nan, np.nan]])
    assert vertical_disparity_rms(v) == pytest.approx(np.sqrt((0.04 + 0.04) / 3))
