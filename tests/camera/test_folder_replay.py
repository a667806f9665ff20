"""FolderReplayCamera: natural order, session order, end of folder, unreadable files."""
from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from lps_gui.camera.folder_replay import FolderReplayCamera, natural_key
from lps_gui.errors import HardwareError, InputError


def _write(path, grey):
    cv2.imwrite(str(path), np.full((8, 10), grey, np.uint8))


def test_natural_order_and_end(tmp_path):
    for n, g in ((10, 100), (2, 20), (1, 10)):
        _write(tmp_path / f"img{n}.png", g)
    (tmp_path / "notes.txt").write_text("ignored")
    cam = FolderReplayCamera(tmp_path)
    cam.open()
    assert [int(cam.grab().image[0, 0]) for _ in range(3)] == [10, 20, 100]
    assert cam.properties()["width"] == 10
    with pytest.raises(HardwareError, match="all 3 images replayed"):
        cam.grab()


def test_loop(tmp_path):
    _write(tmp_path / "a.png", 1)
    _write(tmp_path / "b.png", 2)
    cam = FolderReplayCamera(tmp_path, loop=True)
    cam.open()
    assert [int(cam.grab().image[0, 0]) for _ in range(5)] == [1, 2, 1, 2, 1]


def test_session_folder_replays_listed_frames_in_index_order(tmp_path):
    (tmp_path / "images").mkdir()
    lines = []
    for index, g in ((1, 50), (0, 40), (2, 60)):  # listed out of order
        _write(tmp_path / "images" / f"{index:06d}.png", g)
        lines.append(json.dumps({"index": index, "file": f"images/{index:06d}.png"}))
    _write(tmp_path / "images" / "000003.png", 99)  # written but never listed (a crash): not replayed
    (tmp_path / "captures.jsonl").write_text("\n".join(lines) + "\n{\"index\": 3, \"fi")
    cam = FolderReplayCamera(tmp_path)
    cam.open()
    assert len(cam) == 3
    assert [int(cam.grab().image[0, 0]) for _ in range(3)] == [40, 50, 60]


def test_errors_name_the_folder_or_file(tmp_path):
    with pytest.raises(InputError, match="not found"):
        FolderReplayCamera(tmp_path / "missing").open()
    with pytest.raises(InputError, match="no images"):
        FolderReplayCamera(tmp_path).open()
    (tmp_path / "broken.png").write_bytes(b"not a png")
    cam = FolderReplayCamera(tmp_path)
    cam.open()
    with pytest.raises(InputError, match="broken.png: not a PNG, TIFF, BMP, PGM/PPM, JPEG or WebP image"):
        cam.grab()


def test_natural_key():
    assert sorted(["f10", "f9", "F1"], key=natural_key) == ["F1", "f9", "f10"]
