"""ChArUco detection maps marker-identified corners to SPEC 2 indices."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from lps_gui.camera.charuco import board_image, detect_charuco
from lps_gui.core.geometry.board import Board
from lps_gui.errors import InputError

BOARD = Board(cols=7, rows=5, square_mm=30.0, type="charuco", marker_mm=22.0, dictionary="DICT_4X4_50")
PX = 50  # px per square in the printed image
MARGIN = 40


def _scene():
    """The printed board warped by a mild homography into a 640x480 frame, and the true corners."""
    printed = board_image(BOARD, PX, MARGIN)
    h, w = printed.shape
    src = np.float32([[0, 0], [w, 0], [w, h], [0, h]])
    dst = np.float32([[60, 50], [590, 70], [570, 430], [80, 410]])
    H = cv2.getPerspectiveTransform(src, dst)
    frame = cv2.warpPerspective(printed, H, (640, 480), flags=cv2.INTER_AREA, borderValue=128)
    frame = cv2.GaussianBlur(frame, (0, 0), 0.8)
    X = BOARD.object_points()[:, :2] / BOARD.square_mm  # squares from corner (0, 0)
    printed_px = MARGIN + (X + 1.0) * PX - 0.5  # pixel centres: corner (r, c) of the print
    truth = cv2.perspectiveTransform(printed_px.reshape(-1, 1, 2).astype(np.float64), H).reshape(-1, 2)
    return frame, truth


def test_corners_match_spec_order():
    frame, truth = _scene()
    corners, reason = detect_charuco(frame, BOARD)
    assert corners is not None, reason
    seen = np.all(np.isfinite(corners), axis=1)
    assert seen.sum() >= 0.9 * BOARD.n_corners
    assert np.sqrt(np.mean(np.sum((corners[seen] - truth[seen]) ** 2, axis=1))) < 0.3


def test_partly_hidden_board_gives_nan_for_hidden_corners():
    frame, truth = _scene()
    frame[:, 330:] = 128  # hide the right half
    corners, _ = detect_charuco(frame, BOARD)
    assert corners is not None
    seen = np.all(np.isfinite(corners), axis=1)
    assert 0 < seen.sum() < BOARD.n_corners
    assert np.all(truth[seen, 0] < 335)
    assert np.sqrt(np.mean(np.sum((corners[seen] - truth[seen]) ** 2, axis=1))) < 0.3


def test_no_board_gives_a_reason():
    corners, reason = detect_charuco(np.full((480, 640), 128, np.uint8), BOARD)
    assert corners is None and "ChArUco board not found" in reason


def test_unknown_dictionary_is_an_input_error():
    with pytest.raises(InputError, match="dictionary"):
        detect_charuco(np.zeros((10, 10), np.uint8), Board(7, 5, 30.0, type="charuco", dictionary="DICT_NOPE"))
