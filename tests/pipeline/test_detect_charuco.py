"""A ChArUco board through the detection pipeline: partly hidden views keep their identified corners."""
from __future__ import annotations

import cv2
import numpy as np

from lps_gui.io.corners.vnl import read_corners_vnl, write_corners_vnl
from lps_gui.pipeline.detect import detect_images
from tests.camera.test_charuco import BOARD, _scene


def test_charuco_views_through_detect_images(tmp_path):
    frame, truth = _scene()
    hidden = frame.copy()
    hidden[:, 330:] = 128
    paths = [tmp_path / "full.png", tmp_path / "half.png", tmp_path / "none.png"]
    cv2.imwrite(str(paths[0]), frame)
    cv2.imwrite(str(paths[1]), hidden)
    cv2.imwrite(str(paths[2]), np.full_like(frame, 128))
    table = detect_images(paths, BOARD, workers=1)
    assert list(table.failed) == [str(paths[2])] and "ChArUco" in table.failed[str(paths[2])]
    seen_full = np.all(np.isfinite(table.corners_px[0]), axis=1)
    seen_half = np.all(np.isfinite(table.corners_px[1]), axis=1)
    assert seen_half.sum() < seen_full.sum() and np.all(seen_full[seen_half])
    err = table.corners_px[1][seen_half] - truth[seen_half]
    assert np.sqrt(np.mean(np.sum(err**2, axis=1))) < 0.3
    write_corners_vnl(tmp_path / "c.vnl", table)
    back = read_corners_vnl(tmp_path / "c.vnl", BOARD.n_corners)
    assert np.array_equal(np.isfinite(back.corners_px[1]), np.isfinite(table.corners_px[1]))
