"""Camera panel controls (a fake OpenCV device), locking during capture, and "Grab view" for intrinsics."""
from __future__ import annotations

import pytest

pytestmark = pytest.mark.gui


def test_device_controls_are_shown_locked_during_capture_and_set_on_the_device(qtbot, window):
    import cv2

    from lps_gui.camera.opencv_camera import OpenCVCamera
    from tests.camera.test_controls_and_frame_watch import FakeCapture

    cam = window.camera_panel
    device = OpenCVCamera(0)
    device._cap = FakeCapture()
    cam.show_controls(device)
    cam.camera = device
    assert set(cam.control_widgets) == {"exposure", "gain"}  # no focus / white balance on this device
    spin, auto = cam.control_widgets["exposure"]
    assert auto is not None and auto.isChecked() and not spin.isEnabled()  # auto exposure: the value is the camera's
    auto.setChecked(False)
    assert device._cap.props[cv2.CAP_PROP_AUTO_EXPOSURE] == 1.0 and spin.isEnabled()
    spin.setValue(42.0)
    assert device._cap.props[cv2.CAP_PROP_EXPOSURE] == 42.0
    cam.lock_controls(True)  # a capture borrowed the camera
    assert not spin.isEnabled() and not auto.isEnabled() and not cam.control_widgets["gain"][0].isEnabled()
    cam.lock_controls(False)
    assert spin.isEnabled()
    cam.camera = None


def test_grab_view_stores_the_live_frame_for_the_intrinsics_panel(qtbot, window, tmp_path):
    from tests.gui.conftest import connect_sim

    connect_sim(qtbot, window)
    cam = window.camera_panel
    assert cam.start()
    qtbot.waitUntil(lambda: cam.frames_shown > 0 and cam.grab_btn.isEnabled(), timeout=15000)
    cam.set_views_folder(tmp_path / "views")
    with qtbot.waitSignal(cam.view_grabbed, timeout=5000) as sig:
        cam.grab_btn.click()
    path = sig.args[0]
    assert path.name == "view_000.png" and path.exists()
    assert cam.grab_view().name == "view_001.png"
    cam.pause(True)
    assert not cam.grab_btn.isEnabled()
    cam.pause(False)
    cam.stop()


def test_the_source_list_has_the_sdk_devices_and_their_controls_show(qtbot, window):
    """pylon's emulated cameras (PYLON_CAMEMU in tests/conftest.py) are listed; a preview shows their controls."""
    cam = window.camera_panel
    specs = [cam.source.itemData(i) for i in range(cam.source.count())]
    assert "pylon:0815-0000" in specs and "pylon:0815-0001" in specs
    cam.source.setCurrentIndex(specs.index("pylon:0815-0001"))
    assert cam.start()
    try:
        qtbot.waitUntil(lambda: cam.frames_shown > 0 and cam.camera is not None, timeout=20000)
        assert {"exposure", "gain", "frame rate"} <= set(cam.control_widgets)
        assert set(cam.choice_widgets) == {"pixel format", "trigger"}
        spin, auto = cam.control_widgets["exposure"]
        spin.setValue(3000.0)
        assert cam.camera.device.ExposureTime.GetValue() == 3000.0
        assert cam.camera.streaming  # the preview runs at the device's rate
        cam.pause(True)  # lent to a capture: locked, fresh frames
        assert not cam.choice_widgets["pixel format"].isEnabled() and not spin.isEnabled() and not cam.camera.streaming
        cam.pause(False)
        assert cam.choice_widgets["pixel format"].isEnabled() and cam.camera.streaming
    finally:
        cam.stop()
