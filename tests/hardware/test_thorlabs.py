"""Thorlabs KDC101 over APT: thorlabs-apt-device (the client library) drives the emulator through the calls it
uses on hardware; the emulator answers as Thorlabs' APT Communications Protocol manual says."""
from __future__ import annotations

import struct

import pytest

from lps_gui.errors import HardwareError, LpsError
from lps_gui.hardware.sim_stage import SimulatedStage
from lps_gui.hardware.thorlabs import ThorlabsStage
from lps_gui.hardware.thorlabs_emulator import AptKdc101, ThorlabsEmulator

TRAVEL = (0.0, 50.0)
COUNTS = 34304  # per mm, MTS/Z8 (APT manual)
POLL = 0x0490  # MOT_REQ_DCSTATUSUPDATE, sent by the library every 10 ms


def msg(msg_id: int, p1: int = 0, p2: int = 0, dest: int = 0x50, src: int = 0x01, data: bytes = b"") -> bytes:
    """An APT message as the manual lays it out (6-byte little-endian header, then data)."""
    if data:
        return struct.pack("<HHBB", msg_id, len(data), dest | 0x80, src) + data
    return struct.pack("<HBBBB", msg_id, p1, p2, dest, src)


def exchange(emu, start: int = 0) -> list[tuple[int, bytes, bytes]]:
    """(message id, bytes the host sent or b'' when the controller spoke first, answer) without status polls."""
    out = []
    for sent, answer in emu.device.log[start:]:
        mid = struct.unpack("<H", (sent or answer)[:2])[0]
        if sent and mid == POLL:
            continue
        out.append((mid, sent, answer))
    return out


@pytest.fixture()
def rig():
    with ThorlabsEmulator(SimulatedStage(travel_mm=TRAVEL, start_mm=10.0), time_scale=200.0) as emu:
        stage = ThorlabsStage(emu.path, timeout_s=5.0)
        stage.connect()
        yield emu, stage
        stage.disconnect()


def test_connect_exchange_is_what_the_library_sends(rig):
    """PyMeasure-style record of the connect: the library asks for its parameter sets, the driver adds
    HW_NO_FLASH_PROGRAMMING, HW_REQ_INFO and MOD_SET_CHANENABLESTATE."""
    emu, stage = rig
    info = exchange(emu)[5][2]
    assert [(mid, sent) for mid, sent, _ in exchange(emu)] == [
        (0x0414, msg(0x0414, 1)), (0x043B, msg(0x043B, 1)), (0x0417, msg(0x0417, 1)), (0x0441, msg(0x0441, 1)),
        (0x0018, msg(0x0018)), (0x0005, msg(0x0005)), (0x0210, msg(0x0210, 1, 0x01)),
    ]
    assert len(info) == 6 + 84 and info[:6] == struct.pack("<HHBB", 0x0006, 84, 0x81, 0x50)
    assert info[10:16] == b"KDC101" and stage.model == "KDC101" and stage.serial_number == 27000036
    assert emu.device.enabled


def test_move_exchange_and_counts(rig):
    emu, stage = rig
    n = len(emu.device.log)
    stage.move_to(42.5, 600.0)
    st = stage.wait_idle(timeout_s=10.0)
    target = round(42.5 * COUNTS)
    vel = round(600.0 / 60.0 * COUNTS * 2048 / 6e6 * 65536)
    acc = round(1.5 * COUNTS * (2048 / 6e6) ** 2 * 65536)
    ex = exchange(emu, n)
    assert [(mid, sent) for mid, sent, _ in ex[:3]] == [
        (0x0413, msg(0x0413, data=struct.pack("<Hlll", 1, 0, acc, vel))),
        (0x0414, msg(0x0414, 1)),
        (0x0453, msg(0x0453, data=struct.pack("<Hl", 1, target))),
    ]
    done_id, sent, done = ex[-1]
    assert done_id == 0x0464 and sent == b""  # MOT_MOVE_COMPLETED, the controller's own message
    assert struct.unpack("<Hl", done[6:12]) == (1, target)
    assert st.idle and st.work_mm[0] == target / COUNTS == emu.stage.status().work_mm[0]



def test_home_is_announced_by_move_homed(rig):
    emu, stage = rig
    stage.home()
    assert emu.device.homed and stage.status().idle
    assert ((0x0444, b"", msg(0x0444, 1, 0, dest=0x01, src=0x50)) in exchange(emu))  # the controller's own message

def test_settings_in_mm(rig):
    emu, stage = rig
    stage.move_to(20.0, 600.0)
    stage.wait_idle(timeout_s=10.0)
    s = {x.number: x for x in stage.read_settings()}
    assert s[1].value == pytest.approx(600.0, rel=1e-6) and s[3].value == pytest.approx(0.02, abs=1 / COUNTS)
    with pytest.raises(HardwareError, match="not writable"):
        stage.write_setting(1, 100.0)


def test_emulator_frames_split_messages_and_ignores_moves_while_disabled():
    sim = SimulatedStage(travel_mm=TRAVEL, start_mm=10.0)
    sim.connect()
    dev = AptKdc101(sim)
    req = msg(0x0005)
    assert dev.receive(req[:4]) == b""  # half a header: nothing yet
    assert dev.receive(req[4:])[:2] == struct.pack("<H", 0x0006)
    dev.receive(msg(0x0453, data=struct.pack("<Hl", 1, 20 * COUNTS)))
    assert not dev.busy() and dev.position() == 10 * COUNTS  # channel disabled: the motor is not driven
    dev.receive(msg(0x0210, 1, 0x01) + msg(0x0453, data=struct.pack("<Hl", 1, 20 * COUNTS)))
    assert dev.busy()


def test_a_port_with_no_controller_is_one_line_and_leaves_no_thread():
    import os
    import pty
    import threading

    master, slave = pty.openpty()  # a serial port where nothing answers
    try:
        stage = ThorlabsStage(os.ttyname(slave), timeout_s=0.5)
        before = threading.active_count()
        with pytest.raises(HardwareError, match="no answer to HW_REQ_INFO") as e:
            stage.connect()
        assert "\n" not in str(e.value) and not stage.connected
        assert threading.active_count() <= before  # the library's event-loop thread ended with the failure
    finally:
        os.close(master)
        os.close(slave)
