"""GenICam cameras through harvesters and the demo GenTL producer bundled with the genicam wheel (viky.cti)."""
from __future__ import annotations

import sys

import numpy as np
import pytest

from lps_gui.camera import controls, open_camera
from lps_gui.camera.genicam_camera import GENTL_ENV, GenICamCamera, demo_producer, list_genicam_devices
from lps_gui.camera.sdk_sources import list_devices
from lps_gui.errors import HardwareError, InputError


@pytest.fixture(scope="module")
def cti():
    path = demo_producer()
    assert path is not None, "the genicam wheel (test extra) bundles viky.cti"
    return path


def test_the_demo_producer_lists_its_three_devices(cti, monkeypatch):
    assert [s for _, s in list_genicam_devices(cti)] == ["genicam:0", "genicam:1", "genicam:2"]
    monkeypatch.setenv(GENTL_ENV, str(__import__("pathlib").Path(cti).parent))
    assert ("genicam:2" in [s for _, s in list_devices()])  # found through GENICAM_GENTL64_PATH


def test_frames_are_grabbed_and_controls_read_and_set_through_the_node_map(cti):
    cam = open_camera("genicam:1", cti=cti)
    try:
        assert isinstance(cam, GenICamCamera)
        nm = cam.node_map
        assert controls.choice_controls(cam)["pixel format"] == ("RGBa8", ("RGBa8", "Mono8"))
        assert controls.available(cam) == {"frame rate": 20.0}  # viky has no exposure or gain features
        assert controls.set_control(cam, "frame rate", 50.0) and nm.AcquisitionFrameRate.value == 50.0
        first = cam.grab()  # RGBa8: a per-pixel grey sum, full size
        assert first.image.shape == (400, 400) and first.image.dtype == np.uint8
        cam.close()
        cam.open()
        assert controls.surface_of(cam).set("pixel format", "Mono8") and cam.node_map.PixelFormat.value == "Mono8"
        cam.node_map.Width.value = 320
        frames = [cam.grab() for _ in range(3)]
        assert all(f.image.shape == (400, 320) and f.meta["pixel_format"] == "Mono8" for f in frames)
        assert not cam._handle.is_acquiring()  # each capture frame is its own acquisition
        cam.set_streaming(True)
        assert cam.grab().image.shape == (400, 320) and cam._handle.is_acquiring()  # the preview keeps it running
        cam.set_streaming(False)
        assert not cam._handle.is_acquiring()
        assert cam.properties()["width"] == 320 and cam.properties()["controls"]["pixel format"] == "Mono8"
        assert controls.lock(cam) == {"pixel format": "Mono8", "frame rate": float(cam.node_map.AcquisitionFrameRate.value)}
    finally:
        cam.close()
    assert not cam.is_open


def test_a_missing_producer_is_one_line(monkeypatch, tmp_path):
    monkeypatch.delenv(GENTL_ENV, raising=False)
    with pytest.raises(InputError, match=r"^camera genicam:0: no GenTL producer; give --cti PATH .* or set GENICAM_GENTL64_PATH$"):
        open_camera("genicam:0")
    monkeypatch.setenv(GENTL_ENV, str(tmp_path))  # a folder without any .cti
    with pytest.raises(InputError, match="no GenTL producer"):
        open_camera("genicam:0")
    with pytest.raises(InputError, match=r"^camera genicam:0: GenTL producer .*nope.cti not found"):
        open_camera("genicam:0", cti=str(tmp_path / "nope.cti"))
    assert list_genicam_devices() == []


def test_an_unknown_serial_names_the_serials_found(cti):
    with pytest.raises(HardwareError, match=r"^camera genicam:9: cannot open .*serials found: 0, 1, 2$"):
        open_camera("genicam:9", cti=cti)


def test_a_missing_harvesters_names_the_extra(cti, monkeypatch):
    monkeypatch.setitem(sys.modules, "harvesters", None)
    monkeypatch.setitem(sys.modules, "harvesters.core", None)
    with pytest.raises(InputError, match=r"pip install lps-calib\[genicam\]$"):
        GenICamCamera("0", cti=cti).open()


def test_a_pixel_format_not_handled_leaves_no_acquisition_running(cti, monkeypatch):
    from lps_gui.camera import genicam_camera
    cam = open_camera("genicam:0", cti=cti)
    try:
        monkeypatch.setattr(genicam_camera, "is_supported", lambda fmt: False)
        with pytest.raises(HardwareError, match=r"^camera genicam:0: pixel format RGBa8 is not handled"):
            cam.grab()
        assert cam.is_open and not cam._handle.is_acquiring()  # no frame buffered during the next move
    finally:
        cam.close()
