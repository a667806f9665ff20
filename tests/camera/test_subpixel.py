"""Corners without pixel locking (issue 35: a planar gantry's squareness leaned 4 sigma on rendered images).

Two sub-pixel biases that do not average over a board, each a sine of the corner's sub-pixel phase:
cv2.cornerSubPix's bilinear window (up to 0.013 px on an ideal junction) and a renderer that blurred the
pixel-integrated image instead of the scene (about 0.01 px). Both are gone: the detector's polish is exact
on an ideal junction, and a noise-free render is detected where the corners project.
"""
from __future__ import annotations

import numpy as np
from scipy.special import erf

from lps_gui.camera.detection import refine, subpix_half_window
from lps_gui.camera.render import BoardRenderer, Lighting
from lps_gui.camera.subpixel import polish_corners
from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.truth.simulate import small_spec
from lps_gui.core.truth.stage_errors import TruePose


def _junction(u0: float, v0: float, sigma: float = 1.23, size: int = 81) -> np.ndarray:
    """An ideal blurred X-junction (grey 35..215) at (u0, v0), pixel centres at integers."""
    v, u = np.mgrid[0:size, 0:size].astype(float)
    return 35.0 + 180.0 * (0.5 + 0.5 * erf((u - u0) / (np.sqrt(2) * sigma)) * erf((v - v0) / (np.sqrt(2) * sigma)))


def test_an_ideal_junction_is_found_at_every_sub_pixel_phase():
    errors = []
    for phase in np.linspace(0.0, 1.0, 8, endpoint=False):
        c = np.array([[40.0 + phase, 40.37]])
        img = _junction(*c[0]).astype(np.float32)
        errors.append(refine(img, c + 0.3, 7) - c)
    errors = np.concatenate(errors)
    assert np.abs(errors).max() < 1e-3  # cornerSubPix alone: 0.013 px at a quarter pixel


def test_the_polish_leaves_what_is_not_a_junction_where_it_was():
    flat = np.full((60, 60), 100.0, np.float32)
    pts = np.array([[30.2, 29.7], [1.0, 1.0], [np.nan, 5.0]])
    out = polish_corners(flat, pts, 5)
    assert np.array_equal(out[:2], pts[:2]) and np.isnan(out[2, 0])


def test_a_noise_free_render_is_detected_where_its_corners_project():
    """The rendered board at sub-pixel shifts: corners within 0.004 px RMS of their projection (quantized
    to 8 bits); a render that blurred the pixel-integrated image, or cornerSubPix alone, gave ~0.015 px."""
    spec = small_spec()
    rig = spec.rig
    renderer = BoardRenderer(rig.board, rig.intrinsics, lighting=Lighting(blur_px=1.2))
    X = rig.board.object_points()
    errors = []
    for shift in (0.0, 0.26, 0.51, 0.77):
        pose = TruePose(np.array([20.0 + shift * 500.0 / 600.0]), np.zeros((1, 2)), np.zeros((1, 3)))
        R, t = rig.camera_poses(pose)
        uv = project_board(R, t, X, rig.intrinsics)[0]
        img = renderer.render(R[0], t[0])
        errors.append(refine(img, uv + 0.3, subpix_half_window(uv, rig.board)) - uv)
    errors = np.concatenate(errors)
    assert np.sqrt(np.mean(errors**2)) < 0.004
    assert np.abs(errors.mean(axis=0)).max() < 5e-4  # no common shift either
