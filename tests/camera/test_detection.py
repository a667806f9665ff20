"""Per-image detection and tracking, validated against the renderer's truth."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from lps_gui.camera.detection import (
    ChessboardTracker,
    detect_chessboard,
    grid_irregularity,
    orient,
    sharpness,
    why_not_found,
)
from lps_gui.camera.render import BoardRenderer
from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.truth.simulate import small_spec, true_views


@pytest.fixture(scope="module")
def scene():
    spec = small_spec(views=12)
    _, R, t, _ = true_views(spec, np.random.default_rng(0))
    renderer = BoardRenderer(spec.rig.board, spec.rig.intrinsics, noise_grey=2.0)
    truth = project_board(R, t, spec.rig.board.object_points(), spec.rig.intrinsics)  # shape (K, N, 2)
    images = [renderer.render(R[k], t[k], np.random.default_rng(k)) for k in range(len(R))]
    return spec.rig.board, images, truth


def rms(a, b):
    return float(np.sqrt(np.nanmean(np.sum((a - b) ** 2, axis=-1))))


def test_full_detection_is_in_spec_order_and_accurate(scene):
    board, images, truth = scene
    found = detect_chessboard(images[0], board)
    assert found is not None and found.shape == (board.n_corners, 2)
    assert rms(found, truth[0]) < 0.06  # SPEC order: corner k matches true corner k


def test_detect_in_colour_image(scene):
    board, images, truth = scene
    bgr = cv2.cvtColor(images[3], cv2.COLOR_GRAY2BGR)
    assert rms(detect_chessboard(bgr, board), truth[3]) < 0.06


def test_orientation_undoes_a_180_degree_flip(scene):
    board, _, truth = scene
    flipped = truth[0][::-1]
    assert np.allclose(orient(flipped, board), truth[0])
    assert np.allclose(orient(flipped, board, reference_px=truth[1]), truth[0])


def test_orientation_makes_a_mirrored_order_right_handed(scene):
    board, _, truth = scene
    mirrored = truth[0].reshape(board.rows, board.cols, 2)[::-1].reshape(-1, 2)
    assert np.allclose(orient(mirrored, board), truth[0])


def test_tracker_tracks_and_stays_accurate(scene):
    board, images, truth = scene
    tracker = ChessboardTracker(board)
    found = [tracker.detect(img) for img in images]
    assert found[0].method == "full"
    assert tracker.n_tracked >= len(images) - 2
    assert rms(np.array([f.corners_px for f in found]), truth) < 0.06


def test_tracker_recovers_after_a_frame_without_board(scene):
    board, images, truth = scene
    tracker = ChessboardTracker(board)
    tracker.detect(images[0])
    blank = np.full_like(images[1], 90)
    miss = tracker.detect(blank)
    assert miss.corners_px is None and miss.method == "failed" and "board not found" in miss.reason
    again = tracker.detect(images[2])
    assert again.method == "full" and rms(again.corners_px, truth[2]) < 0.06


def test_tracker_falls_back_when_the_board_jumps(scene):
    board, images, truth = scene
    tracker = ChessboardTracker(board)
    tracker.detect(images[0])
    shifted = np.roll(images[6], (40, 60), axis=(0, 1))  # a bump: large unexpected motion
    det = tracker.detect(shifted)
    assert det.corners_px is not None
    assert rms(det.corners_px, truth[6] + [60, 40]) < 0.1


def test_wrong_board_size_is_named(scene):
    _, images, _ = scene
    reason = why_not_found(images[0], Board(cols=8, rows=6, square_mm=20.0))
    assert "9x6" in reason and "board.json" in reason
    assert detect_chessboard(images[0], Board(cols=8, rows=6, square_mm=20.0)) is None


def test_grid_irregularity_catches_a_misplaced_corner(scene):
    board, _, truth = scene
    assert grid_irregularity(truth[0], board) < 0.05
    bad = truth[0].copy()
    bad[20] += [8.0, 0.0]  # a third of a square off
    assert grid_irregularity(bad, board) > 0.2


def test_sharpness_drops_with_blur(scene):
    _, images, _ = scene
    assert sharpness(cv2.GaussianBlur(images[0], (0, 0), 3.0)) < 0.5 * sharpness(images[0])


def test_frame_homography_residual_and_ordering(scene):
    from lps_gui.camera.detection import frame_homography_residual, same_ordering

    board, _, truth = scene
    assert frame_homography_residual(truth[0], truth[1]) < 0.1  # neighbouring LPS frames
    bad = truth[1].copy()
    bad[20] += [6.0, 0.0]
    assert frame_homography_residual(truth[0], bad) > 3.0
    assert same_ordering(truth[0], truth[1], board)
    assert not same_ordering(truth[0], truth[1][::-1], board)
