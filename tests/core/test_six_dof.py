"""core/models/six_dof: the per-view pose solver and the straightness / angle Jacobians against central differences."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.geometry.rotation import exp_so3, log_so3
from lps_gui.core.models.six_dof import ViewPoses, refine_view_poses, six_dof_motion
from lps_gui.core.truth.simulate import simulate_views, small_spec
from lps_gui.core.truth.stage_errors import ErrorProfile, StageErrorModel
from tests.core.finite_differences import central_jacobian, normalized_difference

TOL = 1e-5


@pytest.fixture(scope="module")
def case():
    errors = StageErrorModel(straightness_um=(ErrorProfile(amplitude=30.0, period_mm=20.0), ErrorProfile(poly=(0.0, 50.0))),
                             pitch_urad=ErrorProfile(amplitude=200.0, period_mm=30.0), roll_urad=ErrorProfile(poly=(0.0, 300.0)))
    spec = small_spec(seed=2, views=6, noise_px=0.2, errors=errors)
    views = simulate_views(spec)
    mask = np.all(np.isfinite(views.corners_px), axis=-1)
    return spec, views, mask


def pose_residuals(R, t, X, corners, mask, intrinsics):
    uv = project_board(R, t, X, intrinsics)
    return np.where(mask[..., None], uv - np.nan_to_num(corners), 0.0)


def test_pose_normal_matrix_matches_central_differences(case):
    """iterations=0 returns (J^T J)^-1 at the start pose: compare J^T J with the numeric one per view."""
    spec, views, mask = case
    X, intr = spec.rig.board.object_points(), spec.rig.intrinsics
    R0 = np.einsum("ij,kjl->kil", exp_so3(np.array([1e-3, -2e-3, 5e-4])), views.R_cam_board)
    t0 = views.t_cam_board + np.array([0.3, -0.2, 1.0])
    poses = refine_view_poses(R0, t0, X, views.corners_px, mask, intr, iterations=0)
    for k in range(len(views.stops)):
        def r_of(d, k=k):
            R = exp_so3(d[:3]) @ R0[k]
            return pose_residuals(R[None], (t0[k] + d[3:])[None], X, views.corners_px[k : k + 1], mask[k : k + 1], intr).reshape(-1)

        J = central_jacobian(r_of, 6, np.r_[np.full(3, 1e-6), np.full(3, 1e-4)])
        assert normalized_difference(np.linalg.inv(poses.cov_unit[k]), J.T @ J) < TOL
        assert poses.ssr[k] == pytest.approx(float(np.sum(r_of(np.zeros(6)) ** 2)))


def test_pose_refinement_converges_to_the_least_squares_pose(case):
    spec, views, mask = case
    X, intr = spec.rig.board.object_points(), spec.rig.intrinsics
    R0 = np.einsum("ij,kjl->kil", exp_so3(np.array([2e-3, 1e-3, -1e-3])), views.R_cam_board)
    poses = refine_view_poses(R0, views.t_cam_board + 0.5, X, views.corners_px, mask, intr, iterations=5)
    r = pose_residuals(poses.R, poses.t, X, views.corners_px, mask, intr)
    assert np.allclose(poses.ssr, np.sum(r**2, axis=(1, 2)))
    # at the minimum the gradient vanishes: no small step lowers any view's cost
    for d in np.eye(6)[:, None, :] * np.r_[np.full(3, 1e-5), np.full(3, 1e-3)][:, None, None]:
        for sign in (1, -1):
            Rp = np.einsum("ij,kjl->kil", exp_so3(sign * d[0, :3]), poses.R)
            rp = pose_residuals(Rp, poses.t + sign * d[0, 3:], X, views.corners_px, mask, intr)
            assert np.all(np.sum(rp**2, axis=(1, 2)) >= poses.ssr - 1e-9)


def _motion_sigmas(poses, R_common, valid, v):
    """Sigmas of six_dof_motion with a rank-one pose covariance v v^T: they are |J v| for its Jacobians."""
    K = poses.R.shape[0]
    cov = np.broadcast_to(np.outer(v, v), (K, 6, 6)).copy()
    return six_dof_motion(ViewPoses(poses.R, poses.t, cov, poses.ssr), R_common, valid, 1.0)


def test_straightness_and_angle_jacobians_match_central_differences(case):
    """d straightness / d pose and d angles / d pose (the sigmas' propagation) against central differences.

    A rank-one covariance v v^T turns each reported sigma into |J v|; random
    directions v catch wrong signs as well as wrong magnitudes. The line and
    frame are held where the unperturbed fit puts them (the sigma is per view).
    The angle Jacobian is the one at R_i = R (angles are small), so every
    view here takes the common rotation, with its own refined translation.
    """
    spec, views, mask = case
    X, intr = spec.rig.board.object_points(), spec.rig.intrinsics
    refined = refine_view_poses(views.R_cam_board, views.t_cam_board, X, views.corners_px, mask, intr)
    R_common = spec.rig.R_cam_board
    poses = ViewPoses(np.broadcast_to(R_common, refined.R.shape).copy(), refined.t, refined.cov_unit, refined.ssr)
    valid = np.ones(len(views.stops), bool)
    base = six_dof_motion(poses, R_common, valid, 1.0)
    F = base.frame
    rng = np.random.default_rng(0)
    for _ in range(4):
        v = rng.normal(size=6) * np.r_[np.full(3, 1e-4), np.full(3, 0.1)]
        out = _motion_sigmas(poses, R_common, valid, v)
        for k in range(len(views.stops)):
            def motion(eps, k=k):
                R = exp_so3(eps[0] * v[:3]) @ poses.R[k]
                t = poses.t[k] + eps[0] * v[3:]
                C = -R.T @ t
                return np.r_[1e3 * C @ F[:, 1:], 1e6 * log_so3(R.T @ R_common) @ F]

            d = central_jacobian(motion, 1, 1e-3)[:, 0]
            assert np.allclose(out.straightness_sigma_um[k], np.abs(d[:2]), rtol=1e-6, atol=1e-9)
            assert np.allclose(out.angles_sigma_urad[k], np.abs(d[2:]), rtol=1e-6, atol=1e-9)


def test_six_dof_recovers_a_straight_line_and_no_rotation():
    spec = small_spec(seed=1, views=6, noise_px=0.0, errors=StageErrorModel())
    views = simulate_views(spec)
    mask = np.all(np.isfinite(views.corners_px), axis=-1)
    poses = refine_view_poses(views.R_cam_board, views.t_cam_board, spec.rig.board.object_points(), views.corners_px, mask,
                              spec.rig.intrinsics)
    out = six_dof_motion(poses, spec.rig.R_cam_board, np.ones(6, bool), 0.01)
    assert np.max(np.abs(out.straightness_um)) < 1e-6 and np.max(np.abs(out.angles_urad)) < 1e-6
    assert np.dot(out.frame[:, 0], spec.rig.u_board) > 1 - 1e-12
    assert np.allclose(out.frame.T @ out.frame, np.eye(3), atol=1e-12)
