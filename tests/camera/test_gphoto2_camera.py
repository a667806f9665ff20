"""Tethered cameras through gphoto2: a recorded call sequence (with an unplug mid-capture), and libgphoto2's virtual camera."""
from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import cv2
import numpy as np
import pytest

from lps_gui.camera import controls, open_camera
from lps_gui.camera.gphoto2_camera import GPhoto2Camera, list_gphoto2_devices
from lps_gui.capture.engine import CaptureEngine
from lps_gui.core.planning.plan import Plan
from lps_gui.errors import HardwareError, InputError
from lps_gui.sim.rig import RigStage
from lps_gui.sim.session import SimulatedRigHook
from tests.camera.fake_gphoto2 import FakeGPhoto2
from tests.capture.helpers import assert_listed_frames_intact, start_capture

PLAN6 = Plan(start_mm=0.0, stop_mm=10.0, step_mm=2.0, directions="+", runs=1, overshoot_mm=1.0, settle_s=0.1, feed_mm_min=1200.0)
PER_FRAME = ["capture", "file_get", "file_delete", "get_config"]  # the last: exposure and ISO read for the frame


@pytest.fixture
def rig(tmp_path, monkeypatch):
    session, stage, sim, _ = start_capture(tmp_path / "session", plan=PLAN6)
    sim.open()
    delivered = []

    def picture():
        delivered.append(sim.grab().image)
        return delivered[-1]

    fake = FakeGPhoto2(picture)
    monkeypatch.setitem(sys.modules, "gphoto2", fake)
    camera = GPhoto2Camera()
    hook = SimulatedRigHook(session.plan(), stage if isinstance(stage, RigStage) else None, sim)
    engine = CaptureEngine(stage, camera, session, simulator=hook)
    return session, fake, camera, engine, delivered


def test_the_recorded_sequence_capture_download_delete_per_frame(rig):
    session, fake, camera, engine, delivered = rig
    summary = engine.run()
    assert summary.state == "done" and summary.listed == 6
    names = [c[0] for c in fake.calls]
    assert names[0] == "init"
    first = names.index("capture")
    assert names[first:] == PER_FRAME * 6
    gets = [c for c in fake.calls if c[0] in ("file_get", "file_delete")]
    assert gets[0] == ("file_get", "/store_00010001/DCIM/100GPHOT", "GPH_0099.JPG", 1)
    assert gets[1] == ("file_delete", "/store_00010001/DCIM/100GPHOT", "GPH_0099.JPG")
    for r, want in zip(session.records(), delivered):
        assert np.array_equal(cv2.imread(str(session.folder / r.file), cv2.IMREAD_GRAYSCALE), want)
    locked = session.meta["camera"]["controls_locked"]
    assert locked == {"exposure": "1/125", "gain": "100", "pixel format": "Large Fine JPEG", "white balance": "Daylight"}


@pytest.mark.parametrize("kind", ["capture", "file_get", "file_delete"])
def test_an_unplugged_camera_stops_the_capture_cleanly_and_it_resumes(rig, kind):
    session, fake, camera, engine, _ = rig
    fake.unplug_at = {kind: 4}  # the 4th frame
    summary = engine.run()
    assert summary.state == "paused" and summary.listed == 3
    assert summary.error.startswith("camera gphoto2:: lost during capture ([-52]") and "\n" not in summary.error
    assert "resume" in summary.error
    assert fake.calls[-1] == ("exit",) and not camera.is_open
    assert_listed_frames_intact(session)
    fake.replug()
    n = len(fake.calls)
    summary = engine.run()  # the engine reopens the camera and retakes frame 4
    assert summary.state == "done" and summary.listed == 6
    assert [c[0] for c in fake.calls[n:n + 1]] == ["init"]
    assert [r.index for r in session.records()] == list(range(6))
    assert_listed_frames_intact(session)


def test_a_frame_whose_exposure_changed_is_refused(rig):
    session, fake, camera, engine, _ = rig
    real_capture = fake._capture

    def capture_and_turn_the_dial(kind):
        if fake.counts["capture"] == 3:
            fake.config.widgets["shutterspeed"].value = "1/60"
        return real_capture(kind)

    fake._capture = capture_and_turn_the_dial
    summary = engine.run()
    assert summary.state == "paused" and summary.listed == 2
    assert summary.error == ("camera: frame 2 refused, exposure is 1/60 but was locked at 1/125; switch off the "
                             "automatic mode or the other program changing it, then resume")


def test_automatic_iso_is_refused_before_the_capture(rig):
    session, fake, camera, engine, _ = rig
    fake.config.widgets["iso"].value = "Auto"
    with pytest.raises(InputError, match=r"^camera gphoto2: gain is automatic; set a fixed value"):
        engine.run()
    assert session.records() == []


def test_listing_and_controls_through_the_recorded_module(monkeypatch):
    fake = FakeGPhoto2(lambda: np.zeros((4, 4), np.uint8))
    monkeypatch.setitem(sys.modules, "gphoto2", fake)
    assert list_gphoto2_devices() == [("Nikon DSC D750 (usb:001,001)", "gphoto2:usb:001,001")]
    cam = open_camera("gphoto2:")
    assert controls.choice_controls(cam)["exposure"] == ("1/125", ("1/60", "1/125", "1/250"))
    assert controls.set_control(cam, "exposure", "1/250") and fake.config.widgets["shutterspeed"].value == "1/250"
    assert not controls.set_control(cam, "exposure", "1/8000")  # not offered by the camera
    cam.close()


def test_no_camera_through_the_real_library_is_one_line():
    with pytest.raises(HardwareError, match=r"^camera gphoto2:: cannot open \(\[-105\] .*no camera found"):
        GPhoto2Camera().open()


VCAM = textwrap.dedent("""
    import json, os, sys
    import cv2, numpy as np
    import gphoto2
    os.environ["VCAMERADIR"] = sys.argv[1]
    os.environ["IOLIBS"] = os.environ["IOLIBS"].replace("iolibs", "vusb")
    from lps_gui.camera import open_camera
    from lps_gui.camera.sdk_sources import list_devices
    cam = open_camera("gphoto2:")
    frames = [cam.grab() for _ in range(2)]
    print(json.dumps({"devices": list_devices(), "shape": list(frames[0].image.shape), "files": [f.meta["file"] for f in frames],
                      "controls": cam.properties()["controls"]}))
    cam.close()
""")


def test_libgphoto2s_virtual_camera_through_the_real_sdk_path(tmp_path):
    """The wheel's libgphoto2 has a virtual PTP camera (vusb iolib): capture, download, delete for real."""
    picture = (np.random.default_rng(0).random((300, 400)) * 255).astype(np.uint8)
    cv2.imwrite(str(tmp_path / "img_0001.jpg"), picture)
    out = subprocess.run([sys.executable, "-c", VCAM, str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["shape"][0] > 0 and got["shape"][1] > 0
    assert len(set(got["files"])) == 2 and all(f.endswith(".JPG") for f in got["files"])
    assert ["Nikon DSC D750 (usb:001,001)", "gphoto2:usb:001,001"] in got["devices"]
    assert "exposure" in got["controls"]
