"""Camera controls through OpenCV properties (a fake device), and the brightness / sharpness jump warning."""
from __future__ import annotations

import cv2
import numpy as np

from lps_gui.camera import controls
from lps_gui.camera.frame_watch import FrameWatch
from lps_gui.camera.opencv_camera import OpenCVCamera


class FakeCapture:
    """A device with exposure (auto, V4L2 style) and gain but no focus or white balance."""

    def __init__(self) -> None:
        self.props = {cv2.CAP_PROP_EXPOSURE: 156.0, cv2.CAP_PROP_AUTO_EXPOSURE: 3.0, cv2.CAP_PROP_GAIN: 4.0}

    def get(self, prop: int) -> float:
        return self.props.get(prop, -1.0)

    def set(self, prop: int, value: float) -> bool:
        if prop not in self.props:
            return False
        self.props[prop] = value
        return True


def test_only_the_controls_the_device_reports_are_offered_and_set_switches_to_manual():
    cam = OpenCVCamera(0)
    assert controls.available(cam) == {}  # closed
    cam._cap = FakeCapture()
    assert controls.available(cam) == {"exposure": 156.0, "gain": 4.0}
    assert controls.auto_modes(cam) == {"exposure": True}
    assert controls.set_control(cam, "exposure", 80.0)
    assert controls.available(cam)["exposure"] == 80.0 and controls.auto_modes(cam) == {"exposure": False}
    assert not controls.set_control(cam, "focus", 10.0)
    assert controls.set_auto(cam, "exposure", True) and controls.auto_modes(cam) == {"exposure": True}
    assert controls.available(OpenCVCamera("video.avi")) == {}


def test_frame_watch_warns_on_brightness_and_sharpness_jumps_only():
    rng = np.random.default_rng(0)
    base = (rng.random((60, 80)) * 100 + 60).astype(np.uint8)
    watch = FrameWatch()
    assert watch.check(base) is None
    assert watch.check(np.clip(base.astype(int) + 2, 0, 255).astype(np.uint8)) is None  # noise-sized change
    brighter = np.clip(base.astype(int) * 1.3, 0, 255).astype(np.uint8)
    msg = watch.check(brighter)
    assert msg is not None and "brightness jumped +" in msg and "exposure" in msg
    watch.reset()
    watch.check(base)
    blurred = cv2.GaussianBlur(base, (0, 0), 2.0)
    msg = watch.check(blurred)
    assert msg is not None and "sharpness jumped -" in msg and "focus" in msg
