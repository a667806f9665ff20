"""Board warp (mrcal's calobject_warp) estimated with the intrinsics, validated on rendered truth."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.camera.detection import detect_chessboard
from lps_gui.camera.render import BoardRenderer, Lighting
from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.intrinsics.calibration import calibrate_intrinsics
from lps_gui.core.intrinsics.refine import WarpNotSeparableError, _residuals_and_jacobian
from lps_gui.core.truth.simulate import small_spec

INTR = small_spec().rig.intrinsics
BOW = (0.6, 0.4)  # the centre stands 1 mm off the board's corners


def poses(board, n, rng, max_tilt_deg=40.0):
    """Varied poses, tilt directions around the circle, board centred somewhere in the image."""
    out = []
    for k in range(n):
        phi = 2 * np.pi * k / n + rng.uniform(-0.2, 0.2)
        R = exp_so3(np.array([np.cos(phi), np.sin(phi), 0.0]) * np.deg2rad(max_tilt_deg) * rng.uniform(0.5, 1.0))
        t = np.array([rng.uniform(-35, 35), rng.uniform(-25, 25), rng.uniform(330, 420)]) - R @ board.centre_mm()
        uv = project_board(R, t, board.object_points(), INTR)
        if np.all(uv > 25) and np.all(uv < np.array(INTR.image_size) - 25):
            out.append((R, t))
    return out


def rendered_corners(board, n, seed):
    """Corners detected in rendered images (noise 2 grey levels) of the board at n varied poses."""
    rng = np.random.default_rng(seed)
    renderer = BoardRenderer(board, INTR, lighting=Lighting(), noise_grey=2.0)
    out = []
    for R, t in poses(board, 3 * n, rng)[:n]:
        c = detect_chessboard(renderer.render(R, t, rng), board)
        assert c is not None
        out.append(c)
    assert len(out) == n
    return out


def z_scores(cal):
    return (cal.intrinsics.vector() - INTR.vector())[:4] / cal.std[:4]


def _check_warped_set(n_views, seed):
    board = Board(9, 6, 20.0, warp_mm=BOW)
    corners = rendered_corners(board, n_views, seed)
    on = calibrate_intrinsics(board.flat_points(), corners, INTR.image_size, warp="on")
    off = calibrate_intrinsics(board.flat_points(), corners, INTR.image_size, warp="off")
    z_on, z_off = z_scores(on), z_scores(off)
    assert np.all(np.abs(z_on) < 3), z_on
    assert np.all(np.abs((on.warp_mm - BOW) / on.warp_sigma_mm) < 3), (on.warp_mm, on.warp_sigma_mm)
    assert np.max(np.abs(z_off[:2])) > 4, z_off  # a flat-board calibration is biased in focal length
    return z_on, z_off, on


def test_rendered_bowed_board_recovers_truth_with_warp_and_is_biased_without():
    _check_warped_set(12, seed=3)


@pytest.mark.slow
def test_rendered_bowed_board_full_set():
    z_on, z_off, on = _check_warped_set(30, seed=5)
    assert np.max(np.abs(z_off[:2])) > 8, z_off


def test_rendered_flat_board_finds_no_warp_and_changes_nothing():
    board = Board(9, 6, 20.0)
    corners = rendered_corners(board, 12, seed=4)
    on = calibrate_intrinsics(board.flat_points(), corners, INTR.image_size)
    off = calibrate_intrinsics(board.flat_points(), corners, INTR.image_size, warp="off")
    assert np.all(np.abs(on.warp_mm / on.warp_sigma_mm) < 2), (on.warp_mm, on.warp_sigma_mm)
    assert np.all(np.abs(z_scores(on)) < 3) and np.all(np.abs(z_scores(off)) < 3)
    # the warp costs a little precision, moves the values by less than their sigma
    assert np.all(np.abs(on.intrinsics.vector()[:4] - off.intrinsics.vector()[:4]) < off.std[:4])
    assert on.rms_px == pytest.approx(off.rms_px, rel=0.05)


def test_line_only_views_refuse_the_warp():
    board = Board(9, 6, 20.0)
    rng = np.random.default_rng(0)
    R = exp_so3(np.array([0.05, 0.02, 0.01]))
    uv = [project_board(R, np.array([-60 + 6 * k, -50, 350 + 8 * k]), board.object_points(), INTR) + rng.normal(0, 0.1, (54, 2))
          for k in range(10)]
    with pytest.raises(WarpNotSeparableError, match="cannot separate the board's bow"):
        calibrate_intrinsics(board.flat_points(), uv, INTR.image_size, warp="on")
    cal = calibrate_intrinsics(board.flat_points(), uv, INTR.image_size)  # auto: flat, with a warning
    assert cal.warp_mm is None and any("board bow not estimated" in w for w in cal.warnings)


def test_outlier_corners_are_rejected_and_listed():
    board = Board(9, 6, 20.0)
    rng = np.random.default_rng(7)
    uv = [project_board(R, t, board.object_points(), INTR) + rng.normal(0, 0.1, (54, 2)) for R, t in poses(board, 40, rng)[:15]]
    uv[3][10] += [2.0, -1.5]
    uv[8][40] += [0.0, 3.0]
    cal = calibrate_intrinsics(board.flat_points(), uv, INTR.image_size)
    assert {(c.view, c.corner) for c in cal.rejected_corners} == {(3, 10), (8, 40)}
    assert {round(c.residual_px) for c in cal.rejected_corners} == {2, 3}
    assert "rejected 2 corner(s)" in cal.summary()
    assert np.all(np.abs(z_scores(cal)) < 3)


def test_refine_jacobian_matches_finite_differences():
    board = Board(9, 6, 20.0)
    rng = np.random.default_rng(1)
    ps = poses(board, 10, rng)[:3]
    X = [board.flat_points()] * 3
    uv = [project_board(R, t, board.object_points(), INTR) for R, t in ps]
    import cv2

    free = np.ones(9, dtype=bool)
    p = np.concatenate([INTR.vector(), [0.3, -0.2], *[np.r_[cv2.Rodrigues(R)[0].ravel(), t] for R, t in ps]])
    args = (X, uv, free, INTR.vector(), board.size_mm, True)
    _, J = _residuals_and_jacobian(p, *args)
    num = np.zeros_like(J)
    for i in range(p.size):
        h = 1e-6 * max(1.0, abs(p[i]))
        dp = np.zeros_like(p)
        dp[i] = h
        num[:, i] = (_residuals_and_jacobian(p + dp, *args, want_jac=False)[0]
                     - _residuals_and_jacobian(p - dp, *args, want_jac=False)[0]) / (2 * h)
    assert np.allclose(J, num, rtol=1e-5, atol=1e-5 * np.abs(num).max())


def test_rendered_bowed_board_matches_projection():
    board = Board(9, 6, 20.0, warp_mm=(3.0, 2.0))
    R = exp_so3(np.array([0.4, 0.3, 0.1]))
    t = np.array([0.0, 0.0, 400.0]) - R @ board.centre_mm()
    c = detect_chessboard(BoardRenderer(board, INTR).render(R, t), board)
    assert np.abs(c - project_board(R, t, board.object_points(), INTR)).max() < 0.1
    assert np.abs(project_board(R, t, board.flat_points(), INTR) - project_board(R, t, board.object_points(), INTR)).max() > 2


def test_lps_estimate_with_the_bowed_board_is_back_at_the_noise():
    """An LPS run of a bowed board: the flat model leaves structure in the residuals and errors in the positions."""
    from dataclasses import replace

    from lps_gui.core.estimator.estimate import EstimateOptions, estimate
    from lps_gui.core.truth.simulate import observations_of, simulate_views

    spec = small_spec(seed=1, noise_px=0.05)
    bowed = replace(spec.rig.board, warp_mm=(2.0, 1.0))
    spec = replace(spec, rig=replace(spec.rig, board=bowed))
    views = simulate_views(spec)
    s_true = np.asarray(views.truth["positions_mm"])
    out = {}
    for name, board in (("flat", replace(bowed, warp_mm=None)), ("bowed", bowed)):
        est = estimate(replace(observations_of(spec, views), board=board), EstimateOptions())
        err = (est.state.s - est.state.s[0]) - (s_true - s_true[0])
        out[name] = (float(np.sqrt(np.mean(err**2))), est.sigma_px)
    assert out["bowed"][1] == pytest.approx(0.05, rel=0.1)  # residuals back at the corner noise
    assert out["flat"][1] > 1.5 * out["bowed"][1]
    assert out["flat"][0] > 2 * out["bowed"][0], out
