"""GrblStage against the GRBL emulator through a real pty: the whole protocol and every injected fault.

The emulator's clock is stepped: it moves only while the driver waits (wait_idle,
home, soft_reset drive it) or when a test calls ``emu.advance``.
"""
from __future__ import annotations

import pytest

from lps_gui.core.truth.stage_errors import StageErrorModel
from lps_gui.errors import HardwareError
from lps_gui.hardware import list_serial_ports, open_stage
from lps_gui.hardware.grbl.codes import GrblError
from lps_gui.hardware.grbl.driver import GrblStage
from lps_gui.hardware.grbl.emulator import Faults, GrblEmulator
from lps_gui.hardware.sim_stage import SimulatedStage
from tests.hardware.grbl_port import drive, stepped_stage

SCALE = 50.0  # simulated seconds per real second


@pytest.fixture
def rig():
    """(emulator, connected driver) over a fresh pty; the stage starts homing-locked at 10 mm."""
    sim = SimulatedStage(travel_mm=(0.0, 100.0), start_mm=10.0, homing_required=True,
                         errors=StageErrorModel(backlash_um=4.0))
    with GrblEmulator(sim, stepped=True) as emu:
        stage = stepped_stage(emu, timeout_s=2.0, poll_interval_s=0.01)
        events = []
        stage.events.subscribe(events.append)
        stage.connect()
        yield emu, stage, events
        stage.disconnect()


def test_connect_reads_build_info_and_settings(rig):
    emu, stage, events = rig
    assert stage.connected and stage.version == "1.1h"
    assert (stage.build_info.planner_blocks, stage.build_info.rx_buffer_bytes) == (15, 128)
    settings = {s.number: s for s in stage.read_settings()}
    assert settings[130].value == 100.0 and settings[130].name == "X-axis maximum travel"
    assert settings[110].value == emu.firmware.settings[110]
    assert any(e.kind == "message" and e.text == "'$H'|'$X' to unlock" for e in events)
    assert stage.status().state == "Alarm"  # homing lock at start-up


def test_home_move_and_wait_match_the_simulated_truth(rig):
    emu, stage, _ = rig
    stage.home()
    st = stage.status()
    assert st.state == "Idle" and st.work_mm[0] == pytest.approx(1.0)  # switch at 0 + 1 mm pull-off
    assert st.machine_mm[0] == pytest.approx(-99.0)  # GRBL machine space: -max_travel + pull-off
    stage.move_to(60.0, 3000.0)
    st = stage.wait_idle(timeout_s=60.0)
    assert st.work_mm[0] == pytest.approx(60.0)
    truth = emu.stage.true_pose().axis_mm[0]
    assert truth == pytest.approx(60.0 - 0.002)  # approached upward: half the 4 um backlash short


def test_jog_and_cancel(rig):
    emu, stage, _ = rig
    stage.unlock()
    stage.jog(80.0, 300.0)  # 16 simulated s
    emu.advance(2.0)
    assert stage.status().state == "Jog"
    stage.jog_cancel()
    st = stage.wait_idle(timeout_s=60.0)
    assert 10.0 < st.work_mm[0] < 90.0
    with pytest.raises(GrblError, match="error:15 Travel exceeded"):
        stage.jog(500.0, 600.0)


def test_feed_hold_and_resume(rig):
    emu, stage, _ = rig
    stage.unlock()
    stage.move_to(90.0, 300.0)
    emu.advance(2.0)
    stage.feed_hold()
    emu.advance(3.0)  # the controlled stop
    held = stage.status()
    assert (held.state, held.substate) == ("Hold", 0) and held.work_mm[0] < 90.0
    stage.resume()
    assert stage.wait_idle(timeout_s=60.0).work_mm[0] == pytest.approx(90.0)


def test_soft_limit_alarm_reset_and_unlock(rig):
    emu, stage, events = rig
    stage.unlock()
    with pytest.raises(GrblError, match="ALARM:2 Soft limit"):
        stage.move_to(150.0, 600.0)
    assert stage.status().state == "Alarm"
    assert any(e.kind == "alarm" and e.code == 2 for e in events)
    stage.soft_reset()
    assert stage.status().state == "Alarm"
    stage.unlock()
    stage.move_to(20.0, 3000.0)
    assert stage.wait_idle(timeout_s=60.0).work_mm[0] == pytest.approx(20.0)


def test_streaming_many_moves_never_overflows_rx_buffer(rig):
    emu, stage, _ = rig
    stage.unlock()
    stage.write_setting(110, 6000.0)
    lines = [f"G1 X{20 + (i % 7)}.000 F6000" for i in range(40)]  # more than planner + RX can hold
    drive(emu, lambda: stage.stream(lines, timeout_s=3.0))
    st = stage.wait_idle(timeout_s=60.0)
    assert st.work_mm[0] == pytest.approx(20 + 39 % 7)
    assert emu.rx_overflow_bytes == 0 and emu.lines_received >= 40


def test_fault_alarm_mid_move(rig):
    emu, stage, events = rig
    stage.unlock()
    emu.faults.alarm_mid_move = 1
    stage.move_to(90.0, 3000.0)
    emu.advance(5.0)
    with pytest.raises(GrblError, match="ALARM:1 Hard limit.*Re-homing is highly recommended"):
        stage.wait_idle(timeout_s=60.0)
    assert stage.status().state == "Alarm"
    stage.soft_reset()
    stage.home()
    assert stage.wait_idle(timeout_s=60.0).work_mm[0] == pytest.approx(1.0)


def test_fault_error_replies(rig):
    emu, stage, events = rig
    stage.unlock()
    emu.faults.error_every = 1
    with pytest.raises(GrblError, match="error:20 Unsupported command"):
        stage.move_to(30.0, 600.0)
    assert any(e.kind == "error" and e.code == 20 for e in events)
    emu.faults.error_every = 0
    stage.move_to(30.0, 3000.0)
    assert stage.wait_idle(timeout_s=60.0).work_mm[0] == pytest.approx(30.0)


def test_settings_cache_follows_the_firmware_rule_for_homing_off(rig):
    emu, stage, _ = rig
    stage.home()
    assert stage.settings[20] == 1.0 and stage.settings[22] == 1.0
    stage.write_setting(22, 0)  # settings.c: homing off also clears soft limits
    assert stage.settings[20] == 0.0 and emu.firmware.settings[20] == 0.0
    before = dict(stage.settings)
    stage.read_settings()
    assert stage.settings == before  # the cache is what $$ says
    with pytest.raises(GrblError, match="error:10"):
        stage.write_setting(20, 1)  # soft limits need homing
    stage.write_setting(22, 1)
    assert stage.settings[20] == 0.0  # turning homing on does not bring soft limits back


def test_fault_slow_replies_within_and_beyond_the_timeout(rig):
    emu, stage, _ = rig
    emu.faults.reply_delay_s = 0.2
    assert stage.status().state == "Alarm"  # slow but within the 2 s timeout
    stage.timeout_s = 0.1
    emu.faults.reply_delay_s = 5.0  # beyond the timeout and the '?' asked after it (the reply is looked for again then)
    with pytest.raises(HardwareError, match=r"no reply to '\$X' within 0.1 s"):
        stage.unlock()


def test_fault_garbage_bytes_are_skipped(rig):
    emu, stage, _ = rig
    emu.faults.garbage_every = 2
    stage.unlock()
    stage.move_to(40.0, 3000.0)
    assert stage.wait_idle(timeout_s=60.0).work_mm[0] == pytest.approx(40.0)
    assert len(stage.read_settings()) == 34
    assert stage.garbage_lines > 0


def test_fault_dropped_connection_mid_wait(rig):
    emu, stage, events = rig
    stage.unlock()
    stage.move_to(90.0, 300.0)
    emu.drop()
    with pytest.raises(HardwareError, match="port vanished.*reconnect the stage"):
        stage.wait_idle(timeout_s=60.0)  # at once: no reply timeout, no wait_idle deadline
    assert not stage.connected and any(e.kind == "disconnected" for e in events)
    with pytest.raises(HardwareError, match="port vanished"):
        stage.move_to(1.0, 100.0)


def test_fault_dropped_connection_after_n_lines():
    with GrblEmulator(SimulatedStage(), faults=Faults(drop_after_lines=3), time_scale=SCALE) as emu:
        stage = GrblStage(emu.path, timeout_s=5.0)
        stage.connect()  # $I and $$ are lines 1 and 2
        with pytest.raises(HardwareError, match="port vanished"):
            stage.move_to(5.0, 600.0)
        assert emu.dropped


def test_open_stage_specs():
    sim = open_stage("sim")
    assert isinstance(sim, SimulatedStage) and sim.connected
    emulated = open_stage("emulator", time_scale=SCALE, travel_mm=(0.0, 50.0))
    try:
        emulated.move_to(5.0, 3000.0)
        assert emulated.wait_idle(timeout_s=60.0).work_mm[0] == pytest.approx(5.0)
    finally:
        emulated.disconnect()
    assert not emulated.emulator.running
    from lps_gui.errors import InputError

    with pytest.raises(InputError, match="sim \\| emulator \\| grbl:PORT"):
        open_stage("usb")
    with pytest.raises(HardwareError, match="cannot open port '/dev/no-such-tty'"):
        open_stage("grbl:/dev/no-such-tty")
    assert all(isinstance(p, str) for p in list_serial_ports())


def test_check_mode_waits_without_motion_and_sleep_is_reported(rig):
    emu, stage, _ = rig
    stage.unlock()
    stage.command("$C")
    stage.command("G0 X50")
    st = stage.wait_idle(timeout_s=1.0)
    assert st.state == "Check" and st.work_mm[0] == pytest.approx(10.0)
    stage.command("$C")  # leaves check mode with a reset (banner)
    stage.command("$SLP")
    with pytest.raises(HardwareError, match="asleep"):
        stage.wait_idle(timeout_s=1.0)


def test_stage_vanishing_under_the_emulator_drops_the_port(rig):
    emu, stage, _ = rig
    emu.stage.disconnect_fault()
    with pytest.raises(HardwareError, match="port vanished"):
        stage.wait_idle(timeout_s=60.0)
