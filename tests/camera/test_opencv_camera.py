"""OpenCVCamera on files OpenCV can decode (no device needed), and the open_camera factory."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from lps_gui.camera import open_camera
from lps_gui.camera.folder_replay import FolderReplayCamera
from lps_gui.camera.opencv_camera import OpenCVCamera
from lps_gui.core.clock import SimClock
from lps_gui.errors import HardwareError, InputError


def _sequence(folder, n=4, size=(64, 48)):
    """Image sequence img_000.png.. with distinct grey levels 20, 70, 120..."""
    levels = [20 + 50 * i for i in range(n)]
    for i, g in enumerate(levels):
        img = np.full((size[1], size[0], 3), g, np.uint8)
        img[0, 0] = (255, 0, 0)
        cv2.imwrite(str(folder / f"img_{i:03d}.png"), img)
    return levels


def test_image_sequence_file_is_read_in_order_then_exhausted(tmp_path):
    levels = _sequence(tmp_path)
    clock = SimClock(5.0)
    cam = OpenCVCamera(str(tmp_path / "img_%03d.png"), clock=clock)
    with cam:
        props = cam.properties()
        assert (props["width"], props["height"]) == (64, 48)
        got = []
        for _ in levels:
            f = cam.grab()
            assert f.image.shape == (48, 64) and f.image.dtype == np.uint8 and f.time == 5.0
            got.append(int(np.median(f.image)))
        assert got == levels
        with pytest.raises(HardwareError, match="no more frames after 4"):
            cam.grab()
    assert not cam.is_open


def test_colour_frames_when_asked(tmp_path):
    _sequence(tmp_path, n=1)
    with OpenCVCamera(str(tmp_path / "img_%03d.png"), grey=False) as cam:
        img = cam.grab().image
    assert img.shape == (48, 64, 3) and tuple(img[0, 0]) == (255, 0, 0)


def test_video_file(tmp_path):
    path = tmp_path / "clip.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (64, 48))
    assert writer.isOpened(), "opencv-python-headless writes MJPG .avi with its own codec"
    for g in (40, 200):
        writer.write(np.full((48, 64, 3), g, np.uint8))
    writer.release()
    with open_camera(str(path)) as cam:
        assert isinstance(cam, OpenCVCamera)
        assert abs(int(np.median(cam.grab().image)) - 40) <= 3
        assert abs(int(np.median(cam.grab().image)) - 200) <= 3


def test_missing_device_and_file_are_clear_errors(tmp_path):
    with pytest.raises(HardwareError, match="cannot open; check the path"):
        OpenCVCamera(str(tmp_path / "nothing_%03d.png")).open()
    with pytest.raises(HardwareError, match="grab before open"):
        OpenCVCamera(0).grab()
    with pytest.raises(InputError, match="no such device, folder, file or URL"):
        open_camera(str(tmp_path / "absent.avi"))


def test_open_camera_dispatch(tmp_path):
    _sequence(tmp_path)
    cam = open_camera(str(tmp_path))
    assert isinstance(cam, FolderReplayCamera) and cam.is_open and len(cam) == 4
    with pytest.raises(InputError, match="simulated stage"):
        open_camera("sim")
