"""Every target of a row found in one image, told apart by marker ids (SPEC 13)."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from lps_gui.camera.charuco import board_image
from lps_gui.camera.charuco_targets import dense_corners, detect_targets
from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.targets import Target, pack_targets

PX, MARGIN = 40, 40


def _row_image(targets: list[Target], gap_px: int = 30) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Targets printed side by side on white, and where each corner truly is (pixel centres at integers)."""
    tiles = [board_image(t.board, PX, MARGIN, t.first_marker) for t in targets]
    h = max(tile.shape[0] for tile in tiles) + 2 * gap_px
    w = sum(tile.shape[1] for tile in tiles) + gap_px * (len(tiles) + 1)
    image = np.full((h, w), 255, np.uint8)
    truth = {}
    x0 = gap_px
    for t, tile in zip(targets, tiles):
        image[gap_px: gap_px + tile.shape[0], x0: x0 + tile.shape[1]] = tile
        r, c = np.mgrid[0: t.board.rows, 0: t.board.cols]
        truth[t.id] = np.stack([x0 + MARGIN + (c.ravel() + 1) * PX - 0.5, gap_px + MARGIN + (r.ravel() + 1) * PX - 0.5], 1)
        x0 += tile.shape[1] + gap_px
    return cv2.GaussianBlur(image, (3, 3), 0.8), truth


def _boards(n: int) -> list[Target]:
    return pack_targets([Board(6, 4, 30.0, type="charuco", marker_mm=21.0, dictionary="DICT_5X5_1000")] * n)


def test_three_targets_in_one_image_are_each_found_with_their_own_corners():
    targets = _boards(3)
    image, truth = _row_image(targets)
    found = detect_targets(image, targets)
    assert [f.target for f in found] == ["T0", "T1", "T2"]
    dense = dense_corners(found, targets)
    for t in targets:
        assert np.isfinite(dense[t.id]).all()
        assert np.abs(dense[t.id] - truth[t.id]).max() < 0.1


def test_a_target_cut_by_the_image_border_keeps_the_corners_it_has():
    targets = _boards(2)
    image, truth = _row_image(targets)
    cut = image[:, : image.shape[1] - 150]  # the right target loses its last columns
    found = {f.target: f for f in detect_targets(cut, targets)}
    assert set(found) == {"T0", "T1"}
    part = found["T1"]
    assert 6 <= len(part.corner) < targets[1].board.n_corners
    assert np.abs(part.xy - truth["T1"][part.corner]).max() < 0.1


def test_markers_of_a_target_not_in_the_session_are_ignored():
    targets = _boards(3)
    image, _ = _row_image(targets)
    found = detect_targets(image, [targets[0], targets[2]])
    assert [f.target for f in found] == ["T0", "T2"]


def test_no_target_in_a_blank_image():
    assert detect_targets(np.full((200, 300), 128, np.uint8), _boards(2)) == []


@pytest.mark.parametrize("first", [0, 17])
def test_corner_numbers_follow_spec_order_whatever_the_first_marker(first):
    board = Board(5, 3, 20.0, type="charuco", marker_mm=14.0)
    t = Target("A", board, first)
    image, truth = _row_image([t])
    (f,) = detect_targets(image, [t])
    np.testing.assert_array_equal(f.corner, np.arange(board.n_corners))
    assert np.abs(f.xy - truth["A"]).max() < 0.1
