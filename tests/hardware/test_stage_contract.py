"""One Stage contract, two implementations: the simulated stage and GRBL (driver + emulator over a pty).

Capture, GUI and CLI call only the Stage interface, so the same sequence of
calls must mean the same thing whichever stage is underneath.
"""
from __future__ import annotations

import pytest

from lps_gui.errors import HardwareError
from lps_gui.hardware.grbl.codes import GrblError
from lps_gui.hardware.grbl.emulator import GrblEmulator
from lps_gui.hardware.machine_settings import NUMBER
from lps_gui.hardware.refusals import Alarm, Refusal
from lps_gui.hardware.sim_stage import SimulatedStage
from lps_gui.hardware.stage import Stage, StageEvent

from tests.hardware.grbl_port import stepped_stage

TRAVEL = (0.0, 100.0)


@pytest.fixture(params=["sim", "grbl-emulator"])
def stage(request):
    if request.param == "sim":
        st = SimulatedStage(travel_mm=TRAVEL, start_mm=10.0)
        st.connect()
        yield st
        st.disconnect()
        return
    with GrblEmulator(SimulatedStage(travel_mm=TRAVEL, start_mm=10.0), stepped=True) as emu:
        st = stepped_stage(emu, timeout_s=2.0, poll_interval_s=0.01)  # time passes only while a call waits
        st.connect()
        yield st
        st.disconnect()


def test_move_and_wait(stage: Stage):
    stage.move_to(42.5, 3000.0)
    st = stage.wait_idle(timeout_s=30.0)
    assert st.idle and st.work_mm[0] == pytest.approx(42.5)
    assert stage.position_mm() == pytest.approx(42.5)


def test_queued_moves_end_at_the_last(stage: Stage):
    for x in (20.0, 30.0, 25.0):
        stage.move_to(x, 3000.0)
    assert stage.wait_idle(timeout_s=30.0).work_mm[0] == pytest.approx(25.0)


def test_jog_cancel_stops_between_start_and_target(stage: Stage):
    stage.jog(50.0, 300.0)
    stage.jog_cancel()
    x = stage.wait_idle(timeout_s=30.0).work_mm[0]
    assert 10.0 <= x < 60.0


def test_hold_then_resume_reaches_the_target(stage: Stage):
    stage.move_to(80.0, 300.0)
    stage.feed_hold()
    with pytest.raises(HardwareError, match="Hold"):
        stage.wait_idle(timeout_s=0.3)
    stage.resume()
    assert stage.wait_idle(timeout_s=30.0).work_mm[0] == pytest.approx(80.0)


def test_soft_limit_alarm_then_reset_and_unlock(stage: Stage):
    """The same neutral reason on both; GRBL says it as ALARM:2 (the simulated stage speaks no protocol)."""
    events: list[StageEvent] = []
    stage.events.subscribe(events.append)
    with pytest.raises(HardwareError) as e:
        stage.move_to(150.0, 600.0)
    assert e.value.reason is Alarm.SOFT_LIMIT
    assert [ev.reason for ev in events if ev.kind == "alarm"] == [Alarm.SOFT_LIMIT]
    if isinstance(stage, SimulatedStage):
        assert "outside its travel 0..100 mm: alarm: a move's target is outside the travel" in str(e.value)
    else:
        assert isinstance(e.value, GrblError) and "ALARM:2 Soft limit" in str(e.value)
        assert e.value.kind == "alarm" and e.value.code == 2
        assert [ev.code for ev in events if ev.kind == "alarm"] == [2]
    assert stage.status().state == "Alarm"
    stage.soft_reset()
    stage.unlock()
    assert stage.status().state == "Idle"


def test_jog_beyond_travel_is_refused_without_alarm(stage: Stage):
    """Refused, not an alarm, on both; GRBL says error:15."""
    with pytest.raises(HardwareError) as e:
        stage.jog(500.0, 600.0)
    assert e.value.reason is Refusal.BEYOND_TRAVEL and stage.status().state == "Idle"
    if not isinstance(stage, SimulatedStage):
        assert isinstance(e.value, GrblError) and "error:15 Travel exceeded" in str(e.value) and e.value.kind == "error"


def test_settings_have_names_units_and_write_back(stage: Stage):
    """Each stage numbers its settings its own way (GRBL $130; the simulated machine by name)."""
    sim = isinstance(stage, SimulatedStage)
    travel, rate = (NUMBER["travel_mm.X"], NUMBER["max_rate_mm_min.X"]) if sim else (130, 110)
    settings = {s.number: s for s in stage.read_settings()}
    assert settings[travel].value == pytest.approx(100.0) and settings[travel].unit == ("mm" if sim else "millimeters")
    assert stage.setting_label(settings[rate]) == ("max_rate_mm_min.X" if sim else "$110")
    stage.write_setting(rate, 1500.0)
    assert {s.number: s.value for s in stage.read_settings()}[rate] == 1500.0
    with pytest.raises(HardwareError, match="no such setting" if sim else "error:3") as e:
        stage.write_setting(99, 1.0)
    assert e.value.reason is Refusal.UNKNOWN_SETTING


def test_home_goes_to_low_switch_plus_pull_off(stage: Stage):
    stage.home()
    assert stage.wait_idle(timeout_s=30.0).work_mm[0] == pytest.approx(TRAVEL[0] + 1.0)


def test_work_zero_follows_grbls_offset_model(stage: Stage):
    """Issue 26 item 7: work = machine - offset (GRBL's sign, as `$#` shows it) on both stages."""
    assert stage.work_system() == "G54" and "G59" in stage.work_systems
    stage.move_to(30.0, 3000.0)
    machine = stage.wait_idle(timeout_s=30.0).machine_mm[0]
    stage.set_work_zero("X")
    st = stage.status()
    assert st.work_mm[0] == pytest.approx(0.0, abs=1e-9) and st.machine_mm[0] == pytest.approx(machine)
    assert stage.work_offsets()["G54"][0] == pytest.approx(machine)
    stage.move_to(5.0, 3000.0)  # moves are in work coordinates
    st = stage.wait_idle(timeout_s=30.0)
    assert st.work_mm[0] == pytest.approx(5.0) and st.machine_mm[0] == pytest.approx(machine + 5.0)
    with pytest.raises(HardwareError):
        stage.select_work_system("G60")
