"""The lean board-plane truth solve against a plain Gauss-Newton on pixels (what joint_lm's positions-only
solve computed for it before)."""
import numpy as np

from lps_gui.core.geometry.camera_model import project, project_board
from lps_gui.core.truth.board_plane_truth import BLOCK_VIEWS, positions_on_line
from lps_gui.core.truth.simulate import board_plane_positions, paper_rig_spec, paper_stage_errors, small_spec


def _old_board_plane_positions(rig, pose, iterations=30):
    """Project every true pose; per view, Gauss-Newton on s with d uv / d s = (d uv / d x_cam) n, all corners at once."""
    R, t = rig.camera_poses(pose)
    X = rig.board.object_points()
    uv_true = project_board(R, t, X, rig.intrinsics)  # shape (K, N, 2)
    l0, n = -rig.R_cam_board @ rig.C0_board, -rig.R_cam_board @ rig.u_board
    s = np.asarray(pose.axis_mm, dtype=float).copy()
    for _ in range(iterations):
        p = project((X @ rig.R_cam_board.T + l0)[None] + s[:, None, None] * n, rig.intrinsics, want_jacobian=True)
        J = p.d_uv_d_xcam @ n  # shape (K, N, 2)
        s -= np.einsum("knc,knc->k", J, p.uv - uv_true) / np.einsum("knc,knc->k", J, J)
    return s


def test_same_minimum_as_the_joint_lm_path_with_angular_errors_over_several_blocks():
    errors = paper_stage_errors()
    rig = paper_rig_spec(errors=errors).rig
    K = 2 * BLOCK_VIEWS + 7  # full blocks and a partial one
    x = np.linspace(0.0, 399.0, K)
    pose = errors.true_pose(x, np.where(np.arange(K) % 2 == 0, 1.0, -1.0), np.random.default_rng(3))
    new = board_plane_positions(rig, pose)
    old = _old_board_plane_positions(rig, pose)
    assert new.shape == (K,)
    assert np.max(np.abs(new - pose.axis_mm)) > 1e-3  # the Abbe terms are there (um), so the test has teeth
    np.testing.assert_allclose(new, old, rtol=0, atol=1e-12)


def test_distortion_and_unequal_focal_lengths_weigh_pixels_as_before():
    spec = small_spec()  # 640x480 with all five distortion terms
    rig = spec.rig
    intr = rig.intrinsics.with_vector(rig.intrinsics.vector() * np.array([1.0, 1.1, 1, 1, 1, 1, 1, 1, 1]))
    rig = type(rig)(rig.board, intr, rig.R_cam_board, rig.C0_board, rig.u_board, rig.errors)
    x = np.linspace(0.0, 58.0, 30)
    pose = paper_stage_errors().true_pose(x, np.ones(30))
    np.testing.assert_allclose(board_plane_positions(rig, pose), _old_board_plane_positions(rig, pose), rtol=0, atol=1e-12)


def test_no_views():
    rig = paper_rig_spec().rig
    out = positions_on_line(np.zeros((0, 3, 3)), np.zeros((0, 3)), rig.board.object_points(), rig.intrinsics,
                            rig.R_cam_board, np.zeros(3), np.array([1.0, 0.0, 0.0]), np.zeros(0))
    assert out.shape == (0,)
