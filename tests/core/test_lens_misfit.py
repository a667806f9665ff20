"""The lens-misfit pieces of issue 35: the residual-structure check, the true misfit lens, the poses' sensitivity."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from lps_gui.core.geometry.camera_model import CameraIntrinsics, project
from lps_gui.core.geometry.board import Board
from lps_gui.core.intrinsics.residual_structure import residual_structure, second_difference_noise
from lps_gui.core.metrology.lens_tilts import lens_misfit
from lps_gui.core.truth.lens_misfit import misfit_lens, refit_residual_px

INTR = CameraIntrinsics.from_values((640, 480), 600.0, 600.0, 322.0, 238.0, dist=(-0.12, 0.08, 5e-4, -3e-4, -0.01))


def _grid_views(rng, V=30, cols=9, rows=6):
    """Corner pixels of V board-like grids spread over the image (V, N, 2) and each corner's row."""
    base = np.stack(np.meshgrid(np.arange(cols) * 25.0, np.arange(rows) * 25.0), axis=-1).reshape(-1, 2)
    offsets = rng.uniform([10, 10], [640 - 10 - 200, 480 - 10 - 125], (V, 2))
    return base[None] + offsets[:, None], np.repeat(np.arange(rows), cols)


def test_noise_alone_is_not_structure_and_its_sigma_is_recovered():
    rng = np.random.default_rng(0)
    uv, row_of = _grid_views(rng)
    res = rng.normal(0, 0.05, uv.shape)
    assert abs(second_difference_noise(res, row_of) - 0.05) < 0.003
    rs = residual_structure(uv, res, (640, 480), row_of)
    assert not rs.significant and not rs.exceeds_noise and rs.misfit_px < 0.02


def test_a_smooth_field_above_the_noise_is_flagged_and_sized():
    rng = np.random.default_rng(1)
    uv, row_of = _grid_views(rng)
    field = 0.1 * np.stack([np.sin(uv[..., 0] / 150.0), np.cos(uv[..., 1] / 120.0)], axis=-1)
    res = field + rng.normal(0, 0.03, uv.shape)
    rs = residual_structure(uv, res, (640, 480), row_of)
    assert abs(rs.noise_px - 0.03) < 0.004  # the smooth field cancels in second differences
    assert rs.significant and rs.exceeds_noise
    assert abs(rs.misfit_px - np.sqrt(np.mean(np.sum(field**2, axis=-1)))) < 0.01
    assert "lps intrinsics --model rational" in rs.message("these views")
    weak = residual_structure(uv, 0.1 * field + rng.normal(0, 0.03, uv.shape), (640, 480), row_of)
    assert not weak.exceeds_noise  # below the corner noise: no flag


def test_misfit_lens_leaves_the_asked_misfit_after_a_5_coefficient_refit():
    for px in (0.05, 0.3):
        lens = misfit_lens(INTR, px)
        assert lens.has_higher
        assert abs(refit_residual_px(lens) - px) < 1e-3 * px
    assert not misfit_lens(INTR, 0.0).has_higher


def test_pose_sensitivity_matches_refitting_the_pose_to_a_perturbed_lens():
    """G h is the pose change of a least-squares PnP on corners projected through the lens with extra terms h
    (less what the whole-image 5-coefficient calibration absorbs)."""
    from lps_gui.core.geometry.rotation import exp_so3

    board = Board(cols=9, rows=6, square_mm=20.0)
    X = board.object_points()
    R = exp_so3(np.array([0.1, -0.15, 0.05]))
    t = np.array([-60.0, -40.0, 450.0])
    from lps_gui.core.intrinsics.crossval import pixel_grid, unproject

    h = 1e-5 * np.array([1, -1, 1, 1, -1, 1, -1])  # a small misfit (well under 0.01 px): the linear regime
    lens = replace(INTR, higher=h)
    rays = unproject(pixel_grid(INTR.image_size, (16, 12)).reshape(-1, 2), INTR)
    calibrated = INTR  # the 5-coefficient model fitted to that lens over the whole image (a calibration's result)
    for _ in range(4):
        p = project(rays, calibrated, want_intrinsics_jacobian=True)
        step = np.linalg.lstsq(p.d_uv_d_intrinsics.reshape(-1, 9), (project(rays, lens).uv - p.uv).ravel(), rcond=None)[0]
        calibrated = calibrated.with_vector(calibrated.vector() + step)
    target = project(X @ R.T + t, lens).uv
    v = np.zeros(6)  # Gauss-Newton of the pose (left rotation, translation) under the calibrated model
    for _ in range(6):
        Rv, tv = exp_so3(v[:3]) @ R, t + v[3:]
        RW = X @ Rv.T
        p = project(RW + tv, calibrated, want_jacobian=True)
        J = np.concatenate([-np.cross(p.d_uv_d_xcam, RW[:, None, :]), p.d_uv_d_xcam], axis=2).reshape(-1, 6)
        v += np.linalg.lstsq(J, (target - p.uv).ravel(), rcond=None)[0]
    lm = lens_misfit(R[None], t[None], X, np.ones((1, len(X)), bool), np.ones(1, bool), INTR, 0.05)
    predicted = lm.sensitivity[0] @ h
    assert np.abs(v[:3]).max() > 1e-7  # the lens moved the pose ...
    assert np.allclose(predicted, v, rtol=0.02, atol=0.02 * np.abs(v).max())  # ... as predicted
    assert lens_misfit(R[None], t[None], X, np.ones((1, len(X)), bool), np.ones(1, bool), INTR, 0.0) is None


@pytest.mark.parametrize("misfit_px, model", [(0.0, "opencv5"), (0.3, "rational")])
def test_cross_validation_chooses_the_lens_model_the_data_need(misfit_px, model):
    """lps intrinsics --model auto: the rational/thin-prism model only when it predicts held-out views better."""
    from lps_gui.core.geometry.camera_model import project_board
    from lps_gui.core.intrinsics.crossval import choose_lens_model
    from lps_gui.sim.images import sample_intrinsics_poses

    board = Board(cols=9, rows=6, square_mm=20.0)
    true = misfit_lens(INTR, misfit_px)
    rng = np.random.default_rng(0)
    X = board.object_points()
    views = [project_board(R, t, X, true) + rng.normal(0.0, 0.03, (len(X), 2))
             for R, t in sample_intrinsics_poses(board, true, 20, rng)]
    choice = choose_lens_model(X, views, true.image_size)
    assert choice.model == model, choice.summary()
