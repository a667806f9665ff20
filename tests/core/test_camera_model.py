"""The camera model against OpenCV: values and analytic Jacobians."""
import cv2
import numpy as np
import pytest

from lps_gui.core.geometry.camera_model import CameraIntrinsics, pose_jacobian_rodrigues, project
from lps_gui.core.truth.simulate import PAPER_INTRINSICS


def random_case(seed):
    rng = np.random.default_rng(seed)
    intr = CameraIntrinsics.from_values(
        (1920, 1080), 1400 + 200 * rng.random(), 1390 + 200 * rng.random(), 950 + 20 * rng.random(), 540 + 20 * rng.random(),
        dist=(-0.17 + 0.05 * rng.random(), 0.11, -7e-4, 3e-4, -0.02),
    )
    X = np.c_[rng.uniform(0, 300, 60), rng.uniform(0, 200, 60), np.zeros(60)]
    rvec = rng.normal(0, 0.2, 3)
    tvec = np.array([-150.0, -100.0, 600.0]) + rng.normal(0, 20, 3)
    return intr, X, rvec, tvec


def rel_err(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


@pytest.mark.parametrize("seed", range(5))
def test_projection_and_jacobians_match_opencv(seed):
    intr, X, rvec, tvec = random_case(seed)
    uv_cv, J_cv = cv2.projectPoints(X, rvec, tvec, intr.camera_matrix, intr.dist)
    uv, J, _ = pose_jacobian_rodrigues(rvec, tvec, X, intr)
    assert rel_err(uv, uv_cv.reshape(-1, 2)) < 1e-12
    J_cv = J_cv.reshape(-1, 2, J_cv.shape[1])[..., :15]  # rows alternate u, v per point
    assert rel_err(J, J_cv) < 1e-9


def test_board_point_jacobian_matches_finite_differences():
    intr, X, rvec, tvec = random_case(7)
    _, _, J_X = pose_jacobian_rodrigues(rvec, tvec, X, intr)
    h = 1e-4
    for k in range(3):
        dX = np.zeros(3)
        dX[k] = h
        up = pose_jacobian_rodrigues(rvec, tvec, X + dX, intr)[0]
        dn = pose_jacobian_rodrigues(rvec, tvec, X - dX, intr)[0]
        assert rel_err(J_X[..., k], (up - dn) / (2 * h)) < 1e-7


def test_stacked_projection_shapes_and_paper_distortion():
    x = np.random.default_rng(1).uniform([-300, -200, 500], [300, 200, 700], size=(4, 5, 3))
    proj = project(x, PAPER_INTRINSICS, want_jacobian=True, want_intrinsics_jacobian=True)
    assert proj.uv.shape == (4, 5, 2)
    assert proj.d_uv_d_xcam.shape == (4, 5, 2, 3)
    assert proj.d_uv_d_intrinsics.shape == (4, 5, 2, 9)
    ref = cv2.projectPoints(x.reshape(-1, 3), np.zeros(3), np.zeros(3), PAPER_INTRINSICS.camera_matrix, PAPER_INTRINSICS.dist)[0]
    assert rel_err(proj.uv.reshape(-1, 2), ref.reshape(-1, 2)) < 1e-12


@pytest.mark.parametrize("seed", range(3))
def test_point_and_intrinsics_jacobians_match_central_differences(seed):
    """d uv / d x_cam and d uv / d intrinsics of project(), column by column, against central differences."""
    from tests.core.finite_differences import central_jacobian, column_difference

    intr, X, rvec, tvec = random_case(seed)
    R = cv2.Rodrigues(rvec)[0]
    x_cam = X @ R.T + tvec
    proj = project(x_cam, intr, want_jacobian=True, want_intrinsics_jacobian=True)
    J_x = central_jacobian(lambda d: project(x_cam + d, intr).uv, 3, 1e-4)
    assert column_difference(proj.d_uv_d_xcam, J_x) < 1e-6
    v0 = intr.vector()
    h = np.full(9, 1e-3)  # uv is linear in the distortion coefficients: any step is exact there
    J_i = central_jacobian(lambda d: project(x_cam, intr.with_vector(v0 + d)).uv, 9, h)
    assert column_difference(proj.d_uv_d_intrinsics, J_i) < 1e-6
    # the check can fail: one distortion column off by 1 % is seen
    wrong = proj.d_uv_d_intrinsics.copy()
    wrong[..., 4] *= 1.01
    assert column_difference(wrong, J_i) > 1e-3


def higher_case(seed):
    """A lens with rational and thin-prism terms (OpenCV's 12-coefficient model)."""
    intr, X, rvec, tvec = random_case(seed)
    rng = np.random.default_rng(100 + seed)
    higher = np.array([0.02, -0.01, 0.005, 2e-3, -1e-3, -1.5e-3, 8e-4]) * (1 + 0.3 * rng.standard_normal(7))
    return CameraIntrinsics(intr.image_size, intr.camera_matrix, intr.dist, higher=higher), X, rvec, tvec


@pytest.mark.parametrize("seed", range(3))
def test_rational_thin_prism_projection_matches_opencv(seed):
    intr, X, rvec, tvec = higher_case(seed)
    assert intr.has_higher and intr.cv_dist.size == 12
    uv_cv, J_cv = cv2.projectPoints(X, rvec, tvec, intr.camera_matrix, intr.cv_dist)
    uv, J, _ = pose_jacobian_rodrigues(rvec, tvec, X, intr)
    assert rel_err(uv, uv_cv.reshape(-1, 2)) < 1e-12
    J_cv = J_cv.reshape(-1, 2, J_cv.shape[1])[..., :15]  # rvec, tvec, f, c, k1 k2 p1 p2 k3
    assert rel_err(J, J_cv) < 1e-9


@pytest.mark.parametrize("seed", range(3))
def test_rational_thin_prism_jacobians_match_central_differences(seed):
    """With the higher terms: d uv / d x_cam, d uv / d the 9 intrinsics and d uv / d the 7 higher terms."""
    from lps_gui.core.geometry.camera_model import higher_rows, project_parts
    from tests.core.finite_differences import central_jacobian, column_difference

    intr, X, rvec, tvec = higher_case(seed)
    x_cam = X @ cv2.Rodrigues(rvec)[0].T + tvec
    proj = project(x_cam, intr, want_jacobian=True, want_intrinsics_jacobian=True)
    assert column_difference(proj.d_uv_d_xcam, central_jacobian(lambda d: project(x_cam + d, intr).uv, 3, 1e-4)) < 1e-6
    v0 = intr.vector()
    J_i = central_jacobian(lambda d: project(x_cam, intr.with_vector(v0 + d)).uv, 9, np.full(9, 1e-4))
    assert column_difference(proj.d_uv_d_intrinsics, J_i) < 1e-6
    Ju, Jv = higher_rows(project_parts(x_cam[:, 0], x_cam[:, 1], x_cam[:, 2], intr), intr)
    J_h = np.stack([np.moveaxis(Ju, 0, -1), np.moveaxis(Jv, 0, -1)], axis=-2)
    h0 = intr.higher
    J_num = central_jacobian(lambda d: project(x_cam, CameraIntrinsics(intr.image_size, intr.camera_matrix, intr.dist,
                                                                      higher=h0 + d)).uv, 7, np.full(7, 1e-5))
    assert column_difference(J_h, J_num) < 1e-6
    wrong = J_h.copy()
    wrong[..., 0] *= 1.01
    assert column_difference(wrong, J_num) > 1e-3


def test_twelve_opencv_coefficients_fill_the_higher_terms():
    d = [-0.1, 0.05, 1e-3, -1e-3, 0.01, 0.02, -0.01, 0.005, 1e-3, 2e-3, 3e-3, 4e-3]
    intr = CameraIntrinsics.from_values((640, 480), 600, 600, 320, 240, dist=tuple(d))
    assert np.allclose(intr.dist, d[:5]) and np.allclose(intr.higher, d[5:]) and np.allclose(intr.cv_dist, d)
    assert np.allclose(intr.with_vector(intr.vector()).higher, d[5:])
    with pytest.raises(Exception, match="tilted"):
        CameraIntrinsics.from_values((640, 480), 600, 600, 320, 240, dist=tuple(d + [0.01, 0.0]))
