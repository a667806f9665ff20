"""Rendered rows of ChArUco targets: every visible target found, its corners where the camera model puts them."""
from __future__ import annotations

import numpy as np
from scipy.ndimage import binary_erosion

from lps_gui.camera.charuco_targets import detect_targets
from lps_gui.camera.render import BoardRenderer
from lps_gui.camera.render_targets import TargetsRenderer, marker_mask
from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.geometry.target_rig import TargetLayout, observe, row_layout
from lps_gui.core.geometry.targets import pack_targets

CAMERA = CameraIntrinsics.from_values((960, 540), 1160.0, 1160.0, 480.0, 270.0, dist=(-0.05, 0.02, 0.0, 0.0, 0.0))
BOARD = Board(8, 5, 30.0, type="charuco", marker_mm=22.0)
R = exp_so3(np.array([0.01, -0.02, 0.005]))


def _scene(depth_mm=None):
    targets = pack_targets([BOARD] * 3)
    layout = row_layout(targets, 290.0, tilt_sigma_rad=0.01, offset_sigma_mm=2.0, depth_mm=depth_mm, seed=3)
    t = R @ np.array([-150.0, -60.0, 0.0]) + np.array([0.0, 0.0, 900.0])
    return targets, layout, t


def test_a_rendered_row_is_detected_where_the_model_projects_it():
    targets, layout, t = _scene()
    image = TargetsRenderer(layout, CAMERA, noise_grey=1.0).render(R, t, np.random.default_rng(0))
    truth = observe(layout, CAMERA, R, t[None])[0]
    found = detect_targets(image, targets)
    assert [f.target for f in found] == ["T0", "T1"]  # T2 is out of view
    for f in found:
        j = int(f.target[1:])
        ref = truth[j * BOARD.n_corners + f.corner]
        assert np.isfinite(ref).all()
        assert len(f.corner) >= 0.8 * np.isfinite(truth[j * 40:(j + 1) * 40, 0]).sum()
        assert np.sqrt(np.mean((f.xy - ref) ** 2)) < 0.05
        assert np.abs(f.xy - ref).max() < 0.15


def test_the_nearer_target_hides_the_one_behind():
    targets = pack_targets([BOARD] * 2)
    Q = np.stack([np.eye(3), np.eye(3)])
    p = np.array([[0.0, 0.0, 0.0], [60.0, 30.0, -300.0]])  # target 1 in front of target 0, overlapping it
    layout = TargetLayout(tuple(targets), Q, p)
    t = R @ np.array([-105.0, -60.0, 0.0]) + np.array([0.0, 0.0, 900.0])
    image = TargetsRenderer(layout, CAMERA).render(R, t)
    found = {f.target: f for f in detect_targets(image, targets)}
    assert found["T1"].corner.size == BOARD.n_corners
    assert "T0" not in found or found["T0"].corner.size < BOARD.n_corners // 2


def test_the_checker_of_one_target_renders_as_the_single_board_renderer():
    """Off the markers, a target's grey levels are the exact-area chessboard render."""
    targets, layout, t = _scene()
    one = TargetLayout(targets[:1], layout.Q[:1], layout.p[:1])
    scene = TargetsRenderer(one, CAMERA, margin_squares=1.0).render_float(R, t)
    board = BoardRenderer(BOARD, CAMERA, margin_squares=1.0).render_float(R, t)
    surface = BoardRenderer(BOARD, CAMERA).surface(R, t)
    k = 96
    mask = marker_mask(targets[0])
    col = np.clip(((surface.bx + 1) * k).astype(int), 0, mask.shape[1] - 1)
    row = np.clip(((surface.by + 1) * k).astype(int), 0, mask.shape[0] - 1)
    off_marker = (mask[row, col] == 0) & (surface.bx > -1) & (surface.by > -1)
    off_marker &= (surface.bx < BOARD.cols) & (surface.by < BOARD.rows)
    # blur spreads the markers by a few pixels: compare away from them
    from scipy.ndimage import binary_erosion
    far = binary_erosion(off_marker, iterations=6)
    assert far.sum() > 10000
    assert np.abs(scene[far] - board[far]).max() < 0.05  # grey levels of a 35..215 scale: the same render


def test_the_marker_mask_only_darkens_white_squares():
    mask = marker_mask(pack_targets([BOARD])[0], texels=20)
    squares = mask.reshape(BOARD.rows + 1, 20, BOARD.cols + 1, 20).max(axis=(1, 3))
    r, c = np.mgrid[0:BOARD.rows + 1, 0:BOARD.cols + 1]
    assert np.all(squares[(r + c) % 2 == 0] == 0) and np.all(squares[(r + c) % 2 == 1] > 0.9)


def test_a_two_depth_constellation_renders_both_rows_where_the_model_projects_them():
    """SPEC 14's layout (core/truth/two_depth) at half the paper camera's resolution: near row on top, far row below."""
    from lps_gui.core.truth.two_depth import two_depth_rig

    half = CameraIntrinsics.from_values((960, 540), 1159.5, 1159.5, 480.0, 270.0)
    tr = two_depth_rig(600.0, intrinsics=half, seed=2)
    pose = tr.rig.errors.true_pose(np.array([300.0]), np.ones(1))
    Rv, tv = tr.rig.camera_poses(pose)
    truth = observe(tr.layout, half, Rv, tv)[0]
    image = TargetsRenderer(tr.layout, half, noise_grey=1.0).render(Rv[0], tv[0], np.random.default_rng(0))
    found = detect_targets(image, list(tr.layout.targets))
    ids = [t.id for t in tr.layout.targets]
    start = np.cumsum([0] + [t.board.n_corners for t in tr.layout.targets])
    rows = {f.target[0] for f in found if len(f.corner) >= 20}
    assert rows == {"F", "N"}  # both depths found in one view
    for f in found:
        ref = truth[start[ids.index(f.target)] + f.corner]
        assert np.isfinite(ref).all()  # nothing found that the model hides (behind the near row, outside)
        assert np.sqrt(np.mean((f.xy - ref) ** 2)) < 0.05
