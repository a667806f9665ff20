"""GrblStage against the sequences GRBL 1.1h's own source produces (see docs/hardware.md).

Each test replays what real firmware does and a driver got wrong (issues 13, 29):
the ``ok`` of a line that an alarm cut short arrives after the alarm (failed homing:
ALARM:8, ok, banner; soft limit: ALARM:2, reset, ok, banner), a ``?`` sent in the
500 ms after an alarm is lost in the self-reset, a reset sent in the 500 ms after
ALARM:2 is lost, lines sent during a feed hold are answered only after ``~``, a line
behind a full planner or a dwell is answered late while GRBL reports it is busy, and
a critical alarm needs a reset, not ``$X``.

The emulator's clock is stepped: simulated time passes only in ``emu.advance`` or
while :func:`drive` runs a call, so nothing here depends on the machine's speed.
Where a test waits on the wall clock it is only to outlast the driver's own reply
timeout (a line must still be waiting after it), never a window something must fit in.
"""
from __future__ import annotations

import contextlib
import time

import pytest

from lps_gui.errors import HardwareError
from lps_gui.hardware.grbl.codes import GrblError
from lps_gui.hardware.grbl.driver import GrblStage
from lps_gui.hardware.grbl.emulator import GrblEmulator
from lps_gui.hardware.sim_stage import SimulatedStage

from tests.hardware.grbl_port import Background, drive

OUTLAST = 1.6  # wall seconds a waiting line is left alone, in units of the driver's reply timeout
TIMEOUT_S = 1.5  # the driver's reply timeout in the waiting tests: a loaded machine still answers '?' within it


@contextlib.contextmanager
def _rig(timeout_s: float = 2.0):
    """Stock GRBL 1.1h (homing lock, $22=1) on a pty with a stepped clock, and a connected driver."""
    emu = GrblEmulator(SimulatedStage(travel_mm=(0.0, 100.0), start_mm=10.0), homing_init_lock=True, stepped=True)
    emu.start()
    stage = GrblStage(emu.path, timeout_s=timeout_s, poll_interval_s=0.01)
    try:
        stage.connect()
        yield emu, stage
    finally:
        stage.disconnect()
        emu.stop()


@pytest.fixture
def stock():
    with _rig() as rig:
        yield rig


def test_power_up_alarm_is_reported_as_locked(stock):
    emu, stage = stock
    assert stage.status().state == "Alarm" and stage.locked
    stage.unlock()
    assert stage.status().state == "Idle" and not stage.locked


def test_failed_homing_ok_is_not_credited_to_the_next_command(stock):
    emu, stage = stock
    emu.faults.fail_homing = 8
    with pytest.raises(GrblError, match="ALARM:8"):
        drive(emu, stage.home)
    emu.faults.fail_homing = None
    drive(emu, stage.unlock)  # must get its own ok, after the self-reset, not the stray ok of $H
    assert emu.firmware.alarm_code is None
    assert stage.status().state == "Idle"
    stage.move_to(20.0, 3000.0)
    assert drive(emu, lambda: stage.wait_idle(timeout_s=60.0)).work_mm[0] == pytest.approx(20.0)


def test_status_right_after_a_failed_homing_is_answered(stock):
    emu, stage = stock
    emu.faults.fail_homing = 9
    homing = Background(stage.home)
    deadline = time.monotonic() + 30.0
    while emu.firmware.alarm_code != 9:  # time stops the moment the homing fails: report.c's 500 ms are still ahead
        assert time.monotonic() < deadline
        emu.advance(0.01)
    homing.thread.join(30.0)
    assert len(homing.errors) == 1 and "ALARM:9" in str(homing.errors[0])
    asked = Background(stage.status)
    time.sleep(0.3)  # the '?' (and its re-sends) fall into report.c's 500 ms before the reset and are lost
    assert asked.waiting() and emu.firmware.busy
    asked.finish(emu)
    assert asked.result[0].state == "Alarm"


def test_one_soft_reset_right_after_alarm_2_is_enough(stock):
    emu, stage = stock
    stage.unlock()
    with pytest.raises(GrblError, match="ALARM:2"):
        stage.move_to(150.0, 600.0)
    fw = emu.firmware
    before = fw.resets_received  # the driver's reset on connect
    resetting = Background(stage.soft_reset)  # at once, inside the firmware's 500 ms
    time.sleep(0.3)
    assert resetting.waiting() and fw.resets_received == before  # held back until the firmware can take it
    emu.advance(0.5)  # ALARM:2 ... [MSG:Reset to continue]: now a reset is not cleared
    resetting.finish(emu)
    assert (fw.resets_received - before, fw.resets_lost) == (1, 0)
    assert stage.status().state == "Alarm" and stage.link.in_flight == 0
    stage.unlock()
    stage.move_to(20.0, 3000.0)
    assert drive(emu, lambda: stage.wait_idle(timeout_s=60.0)).work_mm[0] == pytest.approx(20.0)


def test_soft_limit_then_reset_then_the_lines_get_their_own_answers(stock):
    emu, stage = stock
    stage.unlock()
    with pytest.raises(GrblError, match="ALARM:2"):
        stage.move_to(150.0, 600.0)
    with pytest.raises(HardwareError, match="needs a reset") as exc:
        stage.unlock()  # GRBL would never answer: its critical loop reads no line
    assert "check the cable" not in str(exc.value)
    with pytest.raises(HardwareError, match="needs a reset"):
        stage.command("G0 X5")
    drive(emu, stage.soft_reset)  # ok of the G0 X150, banner, unlock message
    assert stage.status().state == "Alarm" and stage.link.in_flight == 0
    stage.unlock()
    assert emu.firmware.alarm_code is None
    stage.move_to(20.0, 3000.0)
    assert drive(emu, lambda: stage.wait_idle(timeout_s=60.0)).work_mm[0] == pytest.approx(20.0)


def _hold(emu: GrblEmulator, stage: GrblStage) -> None:
    stage.feed_hold()
    emu.advance(3.0)  # the controlled stop: Hold:1, then Hold:0
    assert (stage.status().state, stage.status().substate) == ("Hold", 0)


def test_a_line_during_a_feed_hold_is_refused_not_a_cable_fault(stock):
    emu, stage = stock
    stage.unlock()
    stage.move_to(90.0, 300.0)
    emu.advance(1.0)
    _hold(emu, stage)
    with pytest.raises(HardwareError, match="feed hold") as exc:
        stage.move_to(20.0, 3000.0)
    assert "cable" not in str(exc.value)
    assert stage.link.in_flight == 0
    stage.resume()
    assert drive(emu, lambda: stage.wait_idle(timeout_s=60.0)).work_mm[0] == pytest.approx(90.0)  # the refused line never ran


def test_lines_in_flight_wait_through_a_hold_longer_than_the_timeout():
    with _rig(timeout_s=TIMEOUT_S) as (emu, stage):
        stage.unlock()
        stage.write_setting(110, 600.0)
        lines = [f"G1 X{20 + (i % 5)} F600" for i in range(30)]
        streaming = Background(lambda: stage.stream(lines))
        deadline = time.monotonic() + 10.0
        link = stage.link  # the planner fills, then RX: every line left is in flight or waits for RX room
        while emu.stage.planner_free() > 0 or link.rx_used + len(lines[-1]) + 1 <= link.rx_size - 1:
            assert streaming.waiting() and time.monotonic() < deadline
            time.sleep(0.01)
        _hold(emu, stage)  # simulated time stood still since: no line was answered, RX is still full
        time.sleep(OUTLAST * stage.timeout_s)  # held longer than any reply deadline
        assert streaming.waiting(), streaming.errors
        stage.resume()
        streaming.finish(emu)
        assert drive(emu, lambda: stage.wait_idle(timeout_s=60.0)).work_mm[0] == pytest.approx(20 + 29 % 5)


def test_a_stream_of_long_moves_waits_behind_the_full_planner():
    """Issue 29 item 16: 20 moves of 6 s each; the 15-block planner fills and RX stays full for minutes."""
    with _rig(timeout_s=TIMEOUT_S) as (emu, stage):
        stage.unlock()
        stage.write_setting(110, 600.0)
        lines = [f"G1 X{80 if i % 2 == 0 else 20} F600" for i in range(20)]  # 60 mm at 10 mm/s
        streaming = Background(lambda: stage.stream(lines))
        deadline = time.monotonic() + 10.0
        while emu.stage.planner_free() > 0:
            assert streaming.waiting() and time.monotonic() < deadline
            time.sleep(0.01)
        emu.advance(2.0)  # in the middle of the first move: Run, feed 600
        time.sleep(OUTLAST * stage.timeout_s)  # the lines behind the planner are overdue: GRBL says Run
        assert streaming.waiting(), streaming.errors
        streaming.finish(emu)
        assert emu.rx_overflow_bytes == 0
        assert drive(emu, lambda: stage.wait_idle(timeout_s=60.0)).work_mm[0] == pytest.approx(20.0)


def test_a_dwell_sent_during_a_long_move_waits_for_it():
    """Issue 29 item 16: ``G4 P0.1`` during a 16 s move is answered when the move is over."""
    with _rig(timeout_s=TIMEOUT_S) as (emu, stage):
        stage.unlock()
        stage.move_to(90.0, 300.0)
        emu.advance(1.0)
        dwell = Background(lambda: stage.command("G4 P0.1"))
        time.sleep(OUTLAST * stage.timeout_s)
        assert dwell.waiting(), dwell.errors
        dwell.finish(emu)
        assert stage.status().state == "Idle" and stage.status().work_mm[0] == pytest.approx(90.0)


def test_a_long_dwell_in_idle_waits_its_p():
    with _rig(timeout_s=TIMEOUT_S) as (emu, stage):
        stage.unlock()
        dwell = Background(lambda: stage.command("G4 P10"))  # GRBL reports Idle while it dwells
        time.sleep(OUTLAST * stage.timeout_s)
        assert dwell.waiting(), dwell.errors
        dwell.finish(emu)


def test_silence_to_status_while_a_line_waits_is_a_cable_fault():
    with _rig(timeout_s=0.3) as (emu, stage):
        stage.unlock()
        stage.move_to(90.0, 300.0)
        emu.advance(1.0)
        emu.faults.reply_delay_s = 60.0  # the controller goes silent: no '?' answered either
        with pytest.raises(HardwareError, match=r"no reply to 'G4 P0.1' within 0.3 s; check the cable"):
            stage.command("G4 P0.1")


def test_set_work_zero_shifts_work_coordinates_not_machine(stock):
    emu, stage = stock
    stage.unlock()
    stage.move_to(30.0, 3000.0)
    before = drive(emu, lambda: stage.wait_idle(timeout_s=60.0))
    stage.set_work_zero("X")
    st = stage.status()
    assert st.work_mm[0] == pytest.approx(0.0) and st.machine_mm[0] == pytest.approx(before.machine_mm[0])
    stage.move_to(5.0, 3000.0)
    assert drive(emu, lambda: stage.wait_idle(timeout_s=60.0)).work_mm[0] == pytest.approx(5.0)
    assert emu.stage.status().work_mm[0] == pytest.approx(35.0)  # the carriage is 5 mm past the new zero
