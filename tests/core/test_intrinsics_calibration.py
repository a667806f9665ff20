"""calibrate_intrinsics on projected points with known noise: recovery, per-view RMS, flags, warnings."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.intrinsics.calibration import calibrate_intrinsics, coverage_grid
from lps_gui.core.truth.simulate import small_spec
from lps_gui.errors import DegenerateGeometryError, InputError

INTR = small_spec().rig.intrinsics
BOARD = Board(cols=9, rows=6, square_mm=20.0)
NOISE_PX = 0.1


def views(n, rng, max_tilt_deg=40.0, spread=True):
    """Projected corners of n poses around the image, shape (n, N, 2)."""
    out = []
    for k in range(n):
        phi = 2 * np.pi * k / n if spread else 0.3
        tilt = np.deg2rad(max_tilt_deg * (0.4 + 0.6 * rng.random()))
        R = exp_so3(np.array([np.cos(phi), np.sin(phi), 0.0]) * tilt)
        t = np.array([rng.uniform(-40, 40), rng.uniform(-30, 30), 420.0]) - R @ BOARD.centre_mm()
        out.append(project_board(R, t, BOARD.object_points(), INTR))
    return np.array(out)


def test_recovers_truth_within_3_std_and_reports_noise():
    rng = np.random.default_rng(0)
    uv = views(20, rng)
    noisy = uv + rng.normal(0, NOISE_PX, uv.shape)
    cal = calibrate_intrinsics(BOARD.object_points(), list(noisy), INTR.image_size)
    z = (cal.intrinsics.vector() - INTR.vector()) / cal.std
    assert np.all(np.abs(z) < 3), z
    # OpenCV's RMS is of the 2-D error length: sqrt(2) sigma per coordinate
    assert cal.rms_px == pytest.approx(np.sqrt(2) * NOISE_PX, rel=0.1)
    assert np.median(cal.per_view_rms_px) == pytest.approx(np.sqrt(2) * NOISE_PX, rel=0.15)
    assert np.allclose(np.sqrt(np.diag(cal.intrinsics.covariance)), cal.std)
    assert cal.flagged_views == [] and cal.coverage.shape == (6, 8)


def test_missing_corners_and_skipped_views():
    rng = np.random.default_rng(1)
    uv = views(12, rng) + rng.normal(0, NOISE_PX, (12, BOARD.n_corners, 2))
    uv[2, :10] = np.nan  # a partly seen board still counts
    uv[4, :] = np.nan  # a failed view is skipped
    cal = calibrate_intrinsics(BOARD.object_points(), list(uv), INTR.image_size)
    assert 4 not in cal.used_views and 2 in cal.used_views
    assert np.isnan(cal.per_view_rms_px[4]) and np.isfinite(cal.per_view_rms_px[2])
    assert abs(cal.intrinsics.fx - INTR.fx) < 3 * cal.std[0]


def test_a_bad_view_is_flagged():
    rng = np.random.default_rng(2)
    uv = views(15, rng) + rng.normal(0, NOISE_PX, (15, BOARD.n_corners, 2))
    uv[7] += rng.normal(0, 2.0, uv[7].shape)  # a blurred or moved frame
    cal = calibrate_intrinsics(BOARD.object_points(), list(uv), INTR.image_size)
    assert cal.flagged_views == [7]
    assert "flagged" in cal.summary()


def test_similar_views_and_poor_coverage_warn():
    rng = np.random.default_rng(3)
    uv = views(8, rng, max_tilt_deg=3.0, spread=False) + rng.normal(0, NOISE_PX, (8, BOARD.n_corners, 2))
    cal = calibrate_intrinsics(BOARD.object_points(), list(uv), INTR.image_size)
    text = " ".join(cal.warnings)
    assert "too similar" in text and "cover" in text and "views" in text


def test_too_few_views_and_wrong_corner_count():
    uv = views(2, np.random.default_rng(4))
    with pytest.raises(DegenerateGeometryError, match="usable views"):
        calibrate_intrinsics(BOARD.object_points(), list(uv), INTR.image_size)
    with pytest.raises(InputError, match="corners"):
        calibrate_intrinsics(BOARD.object_points(), [uv[0][:10]], INTR.image_size)


def test_coverage_grid_counts_cells():
    pts = np.array([[10.0, 10.0], [630.0, 470.0], [np.nan, 1.0]])
    grid = coverage_grid(pts, (640, 480), (8, 6))
    assert grid.sum() == 2 and grid[0, 0] == 1 and grid[-1, -1] == 1


def test_full_covariance_matches_opencv_std_and_keeps_correlations():
    import cv2

    rng = np.random.default_rng(5)
    uv = views(15, rng) + rng.normal(0, NOISE_PX, (15, BOARD.n_corners, 2))
    cal = calibrate_intrinsics(BOARD.object_points(), list(uv), INTR.image_size)
    cov = cal.intrinsics.covariance
    assert np.allclose(np.sqrt(np.diag(cov)), cal.std, rtol=0.02)
    # with a flat board and no rejections our refinement is OpenCV's solution, with OpenCV's sigmas
    flat = calibrate_intrinsics(BOARD.object_points(), list(uv), INTR.image_size, warp="off", reject_outliers=False)
    objs = [BOARD.object_points().astype(np.float32)] * 15
    rms, K, dist, *_rest, std_cv, _, _ = cv2.calibrateCameraExtended(
        objs, [u.astype(np.float32).reshape(-1, 1, 2) for u in uv], INTR.image_size, None, None,
        criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12))
    assert np.allclose(flat.intrinsics.vector()[:4], [K[0, 0], K[1, 1], K[0, 2], K[1, 2]], atol=1e-4)
    assert np.allclose(flat.std, std_cv.ravel()[:9], rtol=0.02)
    assert flat.rms_px == pytest.approx(rms, rel=1e-4)
    corr_k1_k2 = cov[4, 5] / np.sqrt(cov[4, 4] * cov[5, 5])
    assert corr_k1_k2 < -0.8  # radial terms trade off: a diagonal covariance would hide it
    fixed = calibrate_intrinsics(BOARD.object_points(), list(uv), INTR.image_size, flags=cv2.CALIB_FIX_K3)
    assert fixed.std[8] == 0 and np.all(fixed.intrinsics.covariance[8] == 0)
    assert fixed.intrinsics.dist[4] == 0
