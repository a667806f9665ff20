"""Zaber over the ASCII protocol: zaber-motion (Zaber's own library) drives the emulator through the calls it
uses on hardware, and the emulator answers as Zaber's ASCII Protocol Manual says."""
from __future__ import annotations

import re

import pytest

from lps_gui.errors import HardwareError, LpsError
from lps_gui.hardware.sim_stage import SimulatedStage
from lps_gui.hardware.zaber import ZaberStage
from lps_gui.hardware.zaber_emulator import ZaberEmulator

TRAVEL = (0.0, 100.0)
STEP_MM = 3.048 / 64 / 1000.0  # X-LSM microstep at the default resolution


@pytest.fixture()
def rig():
    with ZaberEmulator(SimulatedStage(travel_mm=TRAVEL, start_mm=10.0), time_scale=200.0) as emu:
        stage = ZaberStage(emu.path, timeout_s=5.0, poll_interval_s=0.002)
        stage.connect()
        yield emu, stage
        stage.disconnect()


def test_connect_exchange_is_what_the_library_sends(rig):
    """PyMeasure-style record: the driver reads the serial number (which also proves the device is there) and the
    resolution, asks the library to identify the device (its queries; the device database is out of reach here, so
    the manual's units stay), then the travel limits; message ids and checksums are the library's, WR until homed."""
    emu, stage = rig
    assert emu.device.log == [
        ("/1 0 00 get system.serial:2C", "@01 0 00 OK IDLE WR 36036"),
        ("/1 1 01 get resolution:29", "@01 1 01 OK IDLE WR 64"),
        ("/1 0 02 get deviceid:40", "@01 0 02 OK IDLE WR 50081"),
        ("/1 0 03 get system.serial:29", "@01 0 03 OK IDLE WR 36036"),
        ("/1 0 04 get version:75", "@01 0 04 OK IDLE WR 7.38"),
        ("/1 0 05 get version.build:36", "@01 0 05 OK IDLE WR 17916"),
        ("/1 0 06 get device.hw.modified:8D", "@01 0 06 RJ IDLE WR BADCOMMAND"),
        ("/1 0 07 get comm.command.packets.max:32", "@01 0 07 RJ IDLE WR BADCOMMAND"),
        ("/1 0 08 get comm.word.size.max:84", "@01 0 08 RJ IDLE WR BADCOMMAND"),
        ("/1 0 09 get get.settings.max:23", "@01 0 09 RJ IDLE WR BADCOMMAND"),
        ("/1 0 10 get system.axiscount:CD", "@01 0 10 OK IDLE WR 1"),
        ("/1 1 11 get resolution:28", "@01 1 11 OK IDLE WR 64"),
        ("/1 1 12 get peripheralid:82", "@01 1 12 RJ IDLE WR BADCOMMAND"),
        ("/1 1 13 get limit.min:E9", "@01 1 13 OK IDLE WR 0"),
        ("/1 1 14 get limit.max:E6", "@01 1 14 OK IDLE WR 2099738"),
    ]
    assert stage.serial_number == 36036 and stage.microstep_mm == pytest.approx(STEP_MM, rel=1e-12)
    assert stage.travel_mm == pytest.approx((0.0, 2099738 * STEP_MM))
    assert stage.describe()["units_from"] == "manual"


def test_a_device_the_library_identifies_moves_by_the_librarys_scales(monkeypatch):
    """Where the device database is reachable, the library's unit conversion is the one used (here a stand-in
    scale, 2 % off the manual's, so the test sees which one went out)."""
    from zaber_motion.ascii import AxisSettings, Device

    per_mm = 1.0 / STEP_MM * 1.02
    scales = {"pos": per_mm, "maxspeed": per_mm * 1.6384, "accel": per_mm * 1.6384 / 10000.0}
    monkeypatch.setattr(Device, "identify", lambda self, assume_version=None: None)
    monkeypatch.setattr(AxisSettings, "convert_to_native_units",
                        lambda self, setting, value, unit, round=False: scales[setting] * value)
    with ZaberEmulator(SimulatedStage(travel_mm=TRAVEL, start_mm=10.0), time_scale=200.0) as emu:
        stage = ZaberStage(emu.path, timeout_s=5.0, poll_interval_s=0.002)
        stage.connect()
        try:
            assert stage.describe()["units_from"] == "zaber-motion"
            n = len(emu.device.log)
            stage.move_to(42.5, 3000.0)
            words = emu.device.log[n][0].split(":")[0].split()
            assert int(words[5]) == round(42.5 * per_mm)
            assert float(words[6]) == pytest.approx(50.0 * per_mm * 1.6384, rel=1e-6)
        finally:
            stage.disconnect()


def test_home_clears_wr_and_move_is_sent_in_microsteps_and_native_speed(rig):
    emu, stage = rig
    stage.home()
    assert "WR" not in emu.device.warnings
    n = len(emu.device.log)
    stage.move_to(42.5, 3000.0)
    sent, answer = emu.device.log[n]
    assert re.fullmatch(r"/1 1 \d\d move abs 892388 \d+(\.\d+)?:[0-9A-F]{2}", sent), sent
    speed = 3000.0 / 60.0 / STEP_MM * 1.6384  # microsteps/s x 1.6384
    assert float(sent.split()[6].split(":")[0]) == pytest.approx(speed, rel=1e-6)
    assert re.fullmatch(r"@01 1 \d\d OK BUSY -- 0", answer), answer
    assert stage.wait_idle(timeout_s=30.0).work_mm[0] == 892388 * STEP_MM

def test_every_command_is_checksummed_and_answered_by_id(rig):
    emu, stage = rig
    stage.move_to(20.0, 6000.0)
    stage.wait_idle(timeout_s=30.0)
    for sent, answer in emu.device.log:
        body, cc = sent[1:].rsplit(":", 1)
        assert cc == f"{(256 - sum(body.encode()) % 256) % 256:02X}"
        assert answer.split()[2] == body.split()[2]  # the reply carries the command's message id


def test_move_outside_travel_is_a_one_line_rejection(rig):
    emu, stage = rig
    with pytest.raises(HardwareError, match="rejected move abs to 150 mm: BADDATA") as e:
        stage.move_to(150.0, 3000.0)
    assert "\n" not in str(e.value)
    assert stage.wait_idle(timeout_s=5.0).work_mm[0] == pytest.approx(round(10.0 / STEP_MM) * STEP_MM, abs=1e-9)


def test_settings_read_in_mm_and_write_back(rig):
    emu, stage = rig
    settings = {s.number: s for s in stage.read_settings()}
    assert settings[4].name == "limit.max" and settings[4].value == pytest.approx(2099738 * STEP_MM)
    assert stage.setting_label(settings[1]) == "maxspeed"
    assert stage.travel_text(list(settings.values())).startswith("travel: 0 .. 100 mm")
    stage.write_setting(1, 1500.0)
    assert {s.number: s.value for s in stage.read_settings()}[1] == pytest.approx(1500.0, rel=1e-5)
    with pytest.raises(HardwareError, match="no setting 9"):
        stage.write_setting(9, 1.0)


def test_wrong_device_number_is_named():
    with ZaberEmulator(SimulatedStage(travel_mm=TRAVEL), time_scale=200.0) as emu:
        stage = ZaberStage(emu.path, device=3, timeout_s=0.5)
        with pytest.raises(HardwareError, match=r"no device 3 \(found \[1\]\)"):
            stage.connect()


def test_an_axis_the_device_does_not_have_is_a_one_line_rejection():
    with ZaberEmulator(SimulatedStage(travel_mm=TRAVEL), time_scale=200.0) as emu:
        stage = ZaberStage(emu.path, axis_number=2, timeout_s=1.0)
        with pytest.raises(HardwareError, match="axis 2 rejected reading the device: BADAXIS") as e:
            stage.connect()
        assert "\n" not in str(e.value) and not stage.connected
