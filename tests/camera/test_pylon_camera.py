"""Basler cameras through the real pypylon path, on pylon's emulated cameras (PYLON_CAMEMU, set in tests/conftest.py)."""
from __future__ import annotations

import json
import sys

import numpy as np
import pytest

from lps_gui.camera import controls, open_camera
from lps_gui.camera.pylon_camera import PylonCamera, list_pylon_devices
from lps_gui.capture.camera_lock import check_frame
from lps_gui.core.planning.plan import Plan
from lps_gui.errors import HardwareError, InputError
from lps_gui.io.corners.vnl import read_corners_vnl
from lps_gui.io.session import Session
from lps_gui.pipeline.detect import detect_session
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.rig import spec_for_plan
from lps_gui.sim.session import create_simulated_session, simulated_engine
from tests.camera.pylon_feed import FedPylonCamera


def test_the_emulated_devices_are_listed_and_open_by_serial():
    assert ("Basler Emulation (0815-0001)", "pylon:0815-0001") in list_pylon_devices()
    cam = open_camera("pylon:0815-0001")
    try:
        props = cam.properties()
        assert props["serial"] == "0815-0001" and props["model"] == "Emulation"
        frame = cam.grab()
        assert frame.image.dtype == np.uint8 and frame.image.shape == (props["height"], props["width"])
    finally:
        cam.close()
    with pytest.raises(HardwareError, match=r"^camera pylon:nope: cannot open .*check the serial") as exc:
        open_camera("pylon:nope")
    assert "\n" not in str(exc.value)


def test_controls_are_read_set_and_locked_through_the_node_map():
    cam = open_camera("pylon:0815-0000")
    try:
        dev = cam.device
        dev.ExposureAuto.SetValue("Continuous")
        assert controls.auto_modes(cam)["exposure"] is True
        assert controls.set_control(cam, "exposure", 2500.0)  # switches the automatic mode off
        assert dev.ExposureAuto.GetValue() == "Off" and dev.ExposureTime.GetValue() == 2500.0
        assert controls.set_control(cam, "gain", 6.0) and abs(dev.Gain.GetValue() - 6.0) < 0.1
        assert "BayerRG8" in controls.choice_controls(cam)["pixel format"][1]
        dev.GainAuto.SetValue("Continuous")
        locked = controls.lock(cam)
        assert dev.GainAuto.GetValue() == "Off" and locked["exposure"] == 2500.0 and locked["trigger"] == "Off"
        frame = cam.grab()
        check_frame(locked, frame, 0)  # unchanged: accepted
        dev.ExposureTime.SetValue(4000.0)  # another program (or an auto mode) changes it
        with pytest.raises(HardwareError, match=r"^camera: frame 7 refused, exposure is 4000.0 but was locked at 2500.0"):
            check_frame(locked, cam.grab(), 7)
    finally:
        cam.close()


def test_streaming_for_the_preview_and_fresh_frames_for_a_capture(tmp_path):
    from lps_gui.capture.camera_lock import lock_camera
    from tests.capture.helpers import start_capture

    cam = open_camera("pylon:0815-0000")
    try:
        cam.set_streaming(True)
        frames = [cam.grab() for _ in range(3)]
        assert cam.device.IsGrabbing() and len({f.meta["frame"] for f in frames}) == 3
        session, _, _, _ = start_capture(tmp_path / "s")
        lock_camera(cam, session)  # a capture borrows the previewed camera
        assert not cam.streaming and not cam.device.IsGrabbing()
        assert cam.grab().image.ndim == 2 and not cam.device.IsGrabbing()  # GrabOne: one acquisition per frame
    finally:
        cam.close()


def test_bayer_frames_come_full_size_and_grey():
    cam = open_camera("pylon:0815-0000")
    try:
        assert controls.surface_of(cam).set("pixel format", "BayerRG8")
        frame = cam.grab()
        assert frame.meta["pixel_format"] == "BayerRG8" and frame.image.ndim == 2
        assert frame.image.shape == (cam.properties()["height"], cam.properties()["width"])
    finally:
        cam.close()


def test_a_missing_pypylon_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "pypylon", None)
    monkeypatch.setitem(sys.modules, "pypylon.pylon", None)
    with pytest.raises(InputError, match=r"^camera pylon:1: the pypylon package is not installed; pip install lps-calib\[basler\]$"):
        PylonCamera("1").open()


PAPER_SHORT = Plan(start_mm=0.0, stop_mm=300.0, step_mm=100.0, directions="+", runs=1, overshoot_mm=1.0,
                   settle_s=0.1, feed_mm_min=3000.0)  # 4 of the paper rig's 1920x1080 frames (rendering is the cost)


def _capture(folder, fed_dir=None):
    spec = spec_for_plan("paper-rig", PAPER_SHORT, seed=5)
    session, stage, camera = create_simulated_session(folder, spec)
    stage.connect()
    if fed_dir is not None:
        fed_dir.mkdir()
        camera = FedPylonCamera(camera, fed_dir)
    summary = simulated_engine(session, stage, camera).run()
    camera.close()
    assert summary.state == "done", summary.error
    detect_session(session.folder, workers=1)
    results = estimate_session(session.folder)
    return session, read_corners_vnl(session.folder / "corners.vnl", spec.rig.board.n_corners), results


def test_paper_rig_through_the_emulated_basler_gives_the_simulated_cameras_corners(tmp_path):
    direct, direct_corners, direct_results = _capture(tmp_path / "sim")
    fed, fed_corners, fed_results = _capture(tmp_path / "pylon", tmp_path / "feed")
    assert fed.meta["camera"]["driver"] == "SimulatedCamera"  # the session is the rig's; the frames came through pylon:
    assert (tmp_path / "feed" / "feed_000004.png").is_file()
    assert fed_corners.names == direct_corners.names and len(fed_corners.names) == 4
    assert not np.isnan(direct_corners.corners_px).any()
    assert np.max(np.abs(fed_corners.corners_px - direct_corners.corners_px)) == 0.0  # 0 px
    a, b = Session.open(direct.folder).records(), Session.open(fed.folder).records()
    assert [(r.target_mm, r.reported_mm, r.sha256) for r in a] == [(r.target_mm, r.reported_mm, r.sha256) for r in b]
    # the same true positions at every grab, recorded in both sessions' truth
    t_direct, t_fed = (json.loads((s.folder / "session.json").read_text())["truth"] for s in (direct, fed))
    assert len(t_direct["axis_mm"]) == 4
    assert t_direct["axis_mm"] == t_fed["axis_mm"] and t_direct["positions_mm"] == t_fed["positions_mm"]
    # and `lps estimate` measures the same positions from both
    measured = [[p["measured_mm"] for p in r["positions"]] for r in (direct_results, fed_results)]
    assert len(measured[0]) == 4 and measured[0] == measured[1]


def test_locked_controls_are_recorded_and_put_back_when_a_capture_resumes(tmp_path):
    from lps_gui.capture.engine import CaptureEngine
    from tests.capture.helpers import start_capture

    plan = Plan(start_mm=0.0, stop_mm=6.0, step_mm=2.0, directions="+", runs=1, overshoot_mm=1.0, settle_s=0.1, feed_mm_min=1200.0)
    session, stage, _, _ = start_capture(tmp_path / "s", plan=plan)
    cam = PylonCamera("0815-0001")
    cam.open()
    try:
        cam.device.Width.SetValue(320)  # the session's intrinsics' size
        cam.device.Height.SetValue(240)
        cam.device.ExposureAuto.SetValue("Continuous")
        cam.device.ExposureTime.SetValue(1500.0)
        engine = CaptureEngine(stage, cam, session)
        engine.subscribe(lambda e: engine.abort() if e.kind == "frame" and e.index == 1 else None)
        assert engine.run().state == "aborted"
        locked = Session.open(session.folder).meta["camera"]["controls_locked"]
        assert locked["exposure"] == 1500.0 and cam.device.ExposureAuto.GetValue() == "Off"
        cam.device.ExposureTime.SetValue(8000.0)  # someone touched the camera between the runs
        assert CaptureEngine(stage, cam, session).run().state == "done"
        assert cam.device.ExposureTime.GetValue() == 1500.0  # the recorded value, put back before the first frame
        assert len(session.records()) == 4
    finally:
        cam.close()


@pytest.mark.parametrize("pixel_format", ["BGRA8Packed", "RGB16Packed"])
def test_colour_formats_getarray_refuses_are_read_from_the_buffer(pixel_format):
    cam = open_camera("pylon:0815-0001")
    try:
        assert controls.surface_of(cam).set("pixel format", pixel_format)
        frame = cam.grab()  # pypylon's GetArray: "ValueError: Pixel format currently not supported"
        assert frame.meta["pixel_format"] == pixel_format and frame.image.dtype == np.uint8
        assert frame.image.shape == (cam.properties()["height"], cam.properties()["width"])
        assert frame.image.any()
    finally:
        cam.close()


class _LostAfterGrab:
    """An InstantCamera that is unplugged right after a successful GrabOne (every node read then fails)."""

    def __init__(self, cam):
        self._cam = cam

    def __getattr__(self, name):
        return getattr(self._cam, name)

    def GrabOne(self, timeout_ms):
        result = self._cam.GrabOne(timeout_ms)
        self._cam.Close()
        return result


def test_a_camera_lost_right_after_its_grab_is_one_line_with_the_resume_hint():
    cam = open_camera("pylon:0815-0001")
    try:
        cam._handle = _LostAfterGrab(cam._handle)
        with pytest.raises(HardwareError, match=r"^camera pylon:0815-0001: lost after the grab \(.*\); check the cable, "
                                                r"then resume$") as exc:
            cam.grab()
        assert "\n" not in str(exc.value) and not cam.is_open  # the next run reopens it
    finally:
        cam.close()


def _small_plan():
    return Plan(start_mm=0.0, stop_mm=6.0, step_mm=2.0, directions="+", runs=1, overshoot_mm=1.0, settle_s=0.1,
                feed_mm_min=1200.0)


def test_frames_of_another_size_than_the_intrinsics_are_refused_at_the_first(tmp_path):
    from lps_gui.capture.engine import CaptureEngine
    from tests.capture.helpers import start_capture

    session, stage, _, _ = start_capture(tmp_path / "s", plan=_small_plan())  # intrinsics 320x240
    cam = PylonCamera("0815-0001")  # the emulator's 1024x1040
    try:
        summary = CaptureEngine(stage, cam, session).run()
        assert summary.state == "paused" and summary.listed == 0
        assert summary.error == ("camera: frame 0 refused, it is 1024x1040 but the intrinsics are for 320x240; set the "
                                 "camera's width, height and binning as when it was calibrated (or calibrate at this "
                                 "size), then resume")
        assert not list((session.folder / "images").glob("*.png"))
    finally:
        cam.close()


def test_bayer_gains_are_recorded_and_a_resumed_capture_reuses_them(tmp_path):
    from lps_gui.capture.engine import CaptureEngine
    from tests.capture.helpers import start_capture

    session, stage, _, _ = start_capture(tmp_path / "s", plan=_small_plan())
    cam = PylonCamera("0815-0001")
    cam.open()
    try:
        cam.device.Width.SetValue(320)
        cam.device.Height.SetValue(240)
        cam.device.PixelFormat.SetValue("BayerRG12")
        engine = CaptureEngine(stage, cam, session)
        engine.subscribe(lambda e: engine.abort() if e.kind == "frame" and e.index == 1 else None)
        assert engine.run().state == "aborted"
        recorded = Session.open(session.folder).meta["camera"]["bayer_gains"]
        assert recorded == cam.bayer_gains and np.shape(recorded) == (2, 2)
    finally:
        cam.close()
    meta = json.loads((session.folder / "session.json").read_text())
    meta["camera"]["bayer_gains"] = [[1.25, 1.0], [1.0, 0.75]]  # those the first frames had (the scene changed since)
    (session.folder / "session.json").write_text(json.dumps(meta))
    cam = PylonCamera("0815-0001")  # a new process: no gains in memory
    cam.open()
    try:
        cam.device.Width.SetValue(320)
        cam.device.Height.SetValue(240)
        cam.device.PixelFormat.SetValue("BayerRG12")
        session = Session.open(session.folder)
        assert CaptureEngine(stage, cam, session).run().state == "done"
        assert cam.bayer_gains == [[1.25, 1.0], [1.0, 0.75]]  # not estimated again from another frame
    finally:
        cam.close()
