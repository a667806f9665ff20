"""Source strings of the SDK families, missing extras, V4L2 nodes with their controls (a fake OpenCV device)."""
from __future__ import annotations

import sys

import cv2
import numpy as np
import pytest

from lps_gui.camera import controls, open_camera
from lps_gui.camera.sdk_sources import family_of, list_devices, sdk_camera
from lps_gui.camera.v4l2_camera import V4L2Camera, node_index
from lps_gui.errors import InputError
from tests.camera.test_controls_and_frame_watch import FakeCapture


@pytest.mark.parametrize("spec,family", [("genicam:123", "genicam"), ("pylon:0815-0000", "pylon"), ("gphoto2:", "gphoto2"),
                                         ("v4l2:/dev/video0", "v4l2"), ("0", None), ("rtsp://cam/x", None),
                                         ("sim", None), ("C:/videos/a.avi", None)])
def test_the_family_is_the_prefix(spec, family):
    assert family_of(spec) == family


@pytest.mark.parametrize("spec,module,extra", [("genicam:1", "harvesters", "genicam"), ("pylon:1", "pypylon", "basler"),
                                               ("gphoto2:", "gphoto2", "gphoto2")])
def test_a_missing_sdk_is_one_line_naming_the_extra(monkeypatch, spec, module, extra, tmp_path):
    for name in [m for m in sys.modules if m == module or m.startswith(module + ".")] + [module, module + ".core", module + ".pylon"]:
        monkeypatch.setitem(sys.modules, name, None)
    cti = tmp_path / "x.cti"
    cti.write_bytes(b"")
    with pytest.raises(InputError) as exc:
        open_camera(spec, cti=str(cti))
    assert str(exc.value) == f"camera {spec}: the {module} package is not installed; pip install lps-calib[{extra}]"


def test_the_core_install_imports_no_sdk():
    import subprocess

    code = ("import sys, lps_gui.camera, lps_gui.capture.engine, lps_gui.cli.capture.command; "
            "print(sorted(m for m in ('pypylon', 'harvesters', 'genicam', 'gphoto2') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout.strip() == "[]", out.stderr


class FakeV4L2(FakeCapture):
    opened: list = []

    def __init__(self, index, backend):
        super().__init__()
        FakeV4L2.opened.append((index, backend))

    def isOpened(self):
        return True

    def read(self):
        return True, np.full((48, 64, 3), 90, np.uint8)

    def release(self):
        pass

    def getBackendName(self):
        return "V4L2"


def test_a_v4l2_node_opens_its_index_on_the_v4l2_back_end_with_controls(monkeypatch, tmp_path):
    monkeypatch.setattr("lps_gui.camera.opencv_camera.cv2.VideoCapture", FakeV4L2)
    link = tmp_path / "usb-Logitech-video-index0"
    link.symlink_to("/dev/video3")  # what /dev/v4l/by-id holds
    assert node_index(str(link)) == 3
    cam = open_camera(f"v4l2:{link}")
    assert isinstance(cam, V4L2Camera) and FakeV4L2.opened[-1] == (3, cv2.CAP_V4L2)
    assert controls.available(cam) == {"exposure": 156.0, "gain": 4.0}  # a device: its controls are offered
    assert cam.grab().image.shape == (48, 64)
    assert cam.properties()["driver"] == "V4L2Camera" and cam.properties()["source"] == f"v4l2:{link}"
    with pytest.raises(InputError, match=r"^camera v4l2:video0: not a /dev/videoN node"):
        sdk_camera("v4l2:video0")
    with pytest.raises(InputError, match=r"^camera v4l2:/dev/null: not a /dev/videoN node"):
        open_camera("v4l2:/dev/null")


def test_listing_asks_every_installed_sdk(monkeypatch):
    found = list_devices()  # pylon's emulated cameras are on in the tests; no GenTL producer configured
    assert ("Basler Emulation (0815-0000)", "pylon:0815-0000") in found
    assert not any(s.startswith("genicam:") for _, s in found)
