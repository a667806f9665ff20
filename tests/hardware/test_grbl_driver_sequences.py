"""GrblStage against the sequences GRBL 1.1h's own source produces (see docs/hardware.md).

Each test replays what real firmware does and the first driver got wrong (issue 13):
the ``ok`` of a line that an alarm cut short arrives after the alarm (failed homing:
ALARM:8, ok, banner; soft limit: ALARM:2, reset, ok, banner), a ``?`` sent in the
500 ms after an alarm is lost in the self-reset, lines sent during a feed hold are
answered only after ``~``, and a critical alarm needs a reset, not ``$X``.
"""
from __future__ import annotations

import contextlib
import threading
import time

import pytest

from lps_gui.errors import HardwareError
from lps_gui.hardware.grbl.codes import GrblError
from lps_gui.hardware.grbl.driver import GrblStage
from lps_gui.hardware.grbl.emulator import GrblEmulator
from lps_gui.hardware.sim_stage import SimulatedStage


@contextlib.contextmanager
def _rig(time_scale: float, timeout_s: float = 1.0):
    """Stock GRBL 1.1h (homing lock, $22=1) on a pty and a connected driver."""
    emu = GrblEmulator(SimulatedStage(travel_mm=(0.0, 100.0), start_mm=10.0), time_scale=time_scale, homing_init_lock=True)
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
    with _rig(50.0) as rig:
        yield rig


@pytest.fixture
def stock_real_time():
    """GRBL's own timing (homing, report.c's 500 ms after an alarm) on a short travel."""
    with _rig(1.0) as rig:
        yield rig


def test_power_up_alarm_is_reported_as_locked(stock):
    emu, stage = stock
    assert stage.status().state == "Alarm" and stage.locked
    stage.unlock()
    assert stage.status().state == "Idle" and not stage.locked


def test_failed_homing_ok_is_not_credited_to_the_next_command(stock_real_time):
    emu, stage = stock_real_time
    emu.faults.fail_homing = 8
    with pytest.raises(GrblError, match="ALARM:8"):
        stage.home()
    emu.faults.fail_homing = None
    stage.unlock()  # must get its own ok, after the self-reset, not the stray ok of $H
    assert emu.stage.alarm_code is None
    assert stage.status().state == "Idle"
    stage.move_to(20.0, 3000.0)
    assert stage.wait_idle(timeout_s=3.0).work_mm[0] == pytest.approx(20.0)


def test_status_right_after_a_failed_homing_is_answered(stock_real_time):
    emu, stage = stock_real_time
    emu.faults.fail_homing = 9
    with pytest.raises(GrblError, match="ALARM:9"):
        stage.home()
    t0 = time.monotonic()
    assert stage.status().state == "Alarm"  # the first '?' falls into the reset and is lost
    assert time.monotonic() - t0 < stage.timeout_s


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
    stage.soft_reset()  # ok of the G0 X150, banner, unlock message
    assert stage.status().state == "Alarm" and stage.link.in_flight == 0
    stage.unlock()
    assert emu.stage.alarm_code is None
    stage.move_to(20.0, 3000.0)
    assert stage.wait_idle(timeout_s=2.0).work_mm[0] == pytest.approx(20.0)


def _hold(stage: GrblStage) -> None:
    stage.feed_hold()
    deadline = time.monotonic() + 2.0
    while stage.status().substate != 0 and time.monotonic() < deadline:
        time.sleep(0.01)


def test_a_line_during_a_feed_hold_is_refused_not_a_cable_fault(stock):
    emu, stage = stock
    stage.unlock()
    stage.move_to(90.0, 300.0)
    _hold(stage)
    t0 = time.monotonic()
    with pytest.raises(HardwareError, match="feed hold") as exc:
        stage.move_to(20.0, 3000.0)
    assert "cable" not in str(exc.value) and time.monotonic() - t0 < stage.timeout_s
    assert stage.link.in_flight == 0
    stage.resume()
    assert stage.wait_idle(timeout_s=3.0).work_mm[0] == pytest.approx(90.0)  # the refused line never ran


def test_lines_in_flight_wait_through_a_hold_longer_than_the_timeout():
    with _rig(50.0, timeout_s=0.3) as (emu, stage):
        stage.unlock()
        stage.write_setting(110, 600.0)
        errors: list[BaseException] = []

        def stream() -> None:
            try:
                stage.stream([f"G1 X{20 + (i % 5)} F600" for i in range(30)])  # planner full: lines wait
            except BaseException as exc:  # noqa: BLE001 - reported by the assertion below
                errors.append(exc)

        worker = threading.Thread(target=stream)
        worker.start()
        time.sleep(0.05)
        _hold(stage)
        time.sleep(3 * stage.timeout_s)  # held longer than any reply deadline
        assert worker.is_alive() and not errors
        stage.resume()
        worker.join(timeout=10.0)
        assert not worker.is_alive() and not errors, errors
        assert stage.wait_idle(timeout_s=10.0).work_mm[0] == pytest.approx(20 + 29 % 5)


def test_set_work_zero_shifts_work_coordinates_not_machine(stock):
    emu, stage = stock
    stage.unlock()
    stage.move_to(30.0, 3000.0)
    before = stage.wait_idle(timeout_s=2.0)
    stage.set_work_zero("X")
    st = stage.status()
    assert st.work_mm[0] == pytest.approx(0.0) and st.machine_mm[0] == pytest.approx(before.machine_mm[0])
    stage.move_to(5.0, 3000.0)
    assert stage.wait_idle(timeout_s=2.0).work_mm[0] == pytest.approx(5.0)
    assert emu.stage.status().work_mm[0] == pytest.approx(35.0)  # the carriage is 5 mm past the new zero
