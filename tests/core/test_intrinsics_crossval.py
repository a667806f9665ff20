"""Cross-validation of two calibrations (even / odd views) and the projection-uncertainty map."""
from __future__ import annotations

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.intrinsics.calibration import calibrate_intrinsics
from lps_gui.core.intrinsics.crossval import cross_validate, projection_diff, uncertainty_map
from lps_gui.core.truth.simulate import small_spec

INTR = small_spec().rig.intrinsics
BOARD = Board(9, 6, 20.0)


def corners(seed, odd_focal_scale=1.0, n=24):
    """Noisy corners of n varied views; the odd views are seen by a camera whose fx, fy are scaled."""
    rng = np.random.default_rng(seed)
    odd = INTR.with_vector(INTR.vector() * np.r_[odd_focal_scale, odd_focal_scale, np.ones(7)])
    out = []
    for k in range(n):
        phi = 2 * np.pi * k / n
        R = exp_so3(np.array([np.cos(phi), np.sin(phi), 0.0]) * np.deg2rad(40) * rng.uniform(0.4, 1.0))
        t = np.array([rng.uniform(-40, 40), rng.uniform(-30, 30), rng.uniform(380, 460)]) - R @ BOARD.centre_mm()
        out.append(project_board(R, t, BOARD.object_points(), odd if k % 2 else INTR) + rng.normal(0, 0.1, (54, 2)))
    return out


def test_consistent_halves_say_consistent():
    for seed in (0, 1):
        cv = cross_validate(BOARD.flat_points(), corners(seed), INTR.image_size)
        assert cv.diff.consistent, cv.diff.verdict()
        assert cv.diff.verdict().startswith("consistent") and cv.diff.figure < 2
        assert cv.even_views == list(range(0, 24, 2)) and cv.odd_views == list(range(1, 24, 2))


def test_a_changed_focal_length_in_one_half_is_inconsistent():
    for seed in (0, 1):
        cv = cross_validate(BOARD.flat_points(), corners(seed, odd_focal_scale=1.015), INTR.image_size)
        assert not cv.diff.consistent, cv.diff.verdict()
        assert cv.diff.verdict().startswith("the model or the data falls short") and cv.diff.figure > 4
        assert "cross-validation: 12 even views against 12 odd views" in cv.summary()


def test_identical_models_differ_by_nothing_and_a_rotation_is_taken_out():
    cal = calibrate_intrinsics(BOARD.flat_points(), corners(2), INTR.image_size)
    d = projection_diff(cal.intrinsics, cal.intrinsics)
    assert np.nanmax(np.abs(d.diff_px)) < 1e-6 and np.allclose(d.rotation, np.eye(3), atol=1e-9)
    assert np.isfinite(d.diff_px[3:-3, 3:-3]).all()  # only the extrapolated image corners may be unreachable
    # a principal-point shift of 1 px is (almost) a rotation: little is left after the fit
    shifted = cal.intrinsics.with_vector(cal.intrinsics.vector() + np.r_[0, 0, 1.0, 0, np.zeros(5)])
    d = projection_diff(cal.intrinsics, shifted)
    assert np.nanmedian(np.linalg.norm(d.diff_px, axis=-1)) < 0.1


def test_uncertainty_map_is_smallest_where_the_corners_were():
    cal = calibrate_intrinsics(BOARD.flat_points(), corners(3), INTR.image_size)
    q, sigma = uncertainty_map(cal.intrinsics, grid=(16, 12))
    assert q.shape == (12, 16, 2) and sigma.shape == (12, 16)
    seen = cal.coverage_on((16, 12)) > 0
    assert np.median(sigma[seen]) < 0.5 and np.median(sigma[seen]) < np.median(sigma[~seen])
    # more views: less uncertainty
    many = calibrate_intrinsics(BOARD.flat_points(), corners(3, n=48), INTR.image_size)
    assert np.median(uncertainty_map(many.intrinsics)[1][seen]) < np.median(sigma[seen])


def rendered_set(seed, odd_focal_scale=1.0, n=16):
    """Corners detected in rendered images (noise 2 grey levels); odd views through a camera with scaled fx, fy."""
    from lps_gui.camera.detection import detect_chessboard
    from lps_gui.camera.render import BoardRenderer

    rng = np.random.default_rng(seed)
    odd = INTR.with_vector(INTR.vector() * np.r_[odd_focal_scale, odd_focal_scale, np.ones(7)])
    cams = [BoardRenderer(BOARD, INTR, noise_grey=2.0), BoardRenderer(BOARD, odd, noise_grey=2.0)]
    out = []
    while len(out) < n:
        k = len(out)
        phi = 2 * np.pi * k / n
        R = exp_so3(np.array([np.cos(phi), np.sin(phi), 0.0]) * np.deg2rad(40) * rng.uniform(0.5, 1.0))
        t = np.array([rng.uniform(-50, 50), rng.uniform(-40, 40), rng.uniform(300, 400)]) - R @ BOARD.centre_mm()
        uv = project_board(R, t, BOARD.object_points(), INTR)
        if np.any(uv < 25) or np.any(uv > np.array(INTR.image_size) - 25):
            continue
        c = detect_chessboard(cams[k % 2].render(R, t, rng), BOARD)
        assert c is not None
        out.append(c)
    return out


def test_rendered_set_consistent_and_with_a_changed_focal_length_inconsistent():
    same = cross_validate(BOARD.flat_points(), rendered_set(11), INTR.image_size)
    assert same.diff.consistent, same.diff.verdict()
    changed = cross_validate(BOARD.flat_points(), rendered_set(11, odd_focal_scale=1.01), INTR.image_size)
    assert not changed.diff.consistent, changed.diff.verdict()
    assert changed.diff.figure > 3 * same.diff.figure
    print(same.diff.verdict(), changed.diff.verdict(), sep="\n")
