"""The camera preview on the simulated rig: frames arrive, the board is found, the UI never waits."""
from __future__ import annotations

import numpy as np
import pytest

from tests.gui.conftest import connect_sim

pytestmark = pytest.mark.gui


def test_preview_shows_the_simulated_board_without_blocking(qtbot, window, gap_meter):
    connect_sim(qtbot, window)
    cam = window.camera_panel
    qtbot.waitUntil(lambda: cam.sim_camera is not None, timeout=5000)
    assert cam.source.currentData() == "sim"
    with gap_meter() as meter:
        assert cam.start()
        qtbot.waitUntil(lambda: cam.frames_shown >= 2, timeout=15000)
    img = cam.last_image()
    assert img is not None and img.shape == (480, 640)
    assert img.dtype == np.uint8 and img.std() > 20  # a board, not a blank frame
    # detection: the 9x6 board of the simulated rig is found and overlaid
    qtbot.waitUntil(lambda: cam.detect_label.text().startswith("found"), timeout=10000)
    assert cam.detect_label.text() == "found: 54 corners"
    x, _ = cam.overlay.getData()
    assert len(x) == 54
    assert "sharpness" in cam.sharpness_label.text() and cam.sharpness_bar.value() > 0
    cam.stop()
    assert cam.grabber is None
    assert meter.max_busy_cpu_s < 0.25, f"GUI thread busy {meter.max_busy_cpu_s * 1000:.0f} ms between two ticks while previewing"


def test_a_camera_that_cannot_open_is_reported(qtbot, window):
    cam = window.camera_panel
    cam.source.setCurrentIndex(cam.source.findData("7"))  # no such device here
    if cam.source.currentData() != "7":
        cam.source.addItem("Camera device 7", "7")
        cam.source.setCurrentIndex(cam.source.count() - 1)
    assert cam.start()  # returns at once: the device opens on the preview thread
    qtbot.waitUntil(lambda: window.last_error is not None, timeout=10000)
    title, message = window.last_error
    assert title == "Camera not opened" and "camera device 7" in message and "\n" not in message
    qtbot.waitUntil(lambda: cam.grabber is None and cam.open_btn.text() == "Start preview", timeout=5000)


def test_a_failed_camera_open_is_one_log_line_and_the_preview_clears(qtbot, window, caplog):
    import logging

    import numpy as np

    caplog.set_level(logging.INFO)
    cam = window.camera_panel
    cam.image.setImage(np.full((48, 64), 200, np.uint8))  # a frame from before
    cam.source.addItem("Camera device 7", "7")
    cam.source.setCurrentIndex(cam.source.count() - 1)
    assert cam.start()
    qtbot.waitUntil(lambda: window.last_error is not None and cam.grabber is None, timeout=10000)
    errors = [r for r in caplog.records if r.levelno >= logging.ERROR]
    assert len(errors) == 1 and "camera device 7" in errors[0].getMessage() and errors[0].exc_info is None
    assert "\n" not in errors[0].getMessage()
    assert cam.last_image() is None and cam.placeholder.isVisible()
