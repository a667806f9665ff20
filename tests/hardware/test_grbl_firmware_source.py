"""The 16 exchanges where the emulator answered unlike GRBL 1.1h (issue 30), with the firmware's bytes.

Each row is what gnea/grbl 1.1h prints (the function that prints it is named
in the row), on the rig of the issue's 136-step differential: stock build
(HOMING_INIT_LOCK), ``$22=1 $20=1 $23=7 $24=100 $25=3000``, travel -5..500 mm
(``$130=505``), the carriage at 500 (machine 0), G54 at -500. The emulator's
clock is stepped by the test, so no row depends on how fast the machine runs.
Steps: ``("ask", sent, lines)`` the exact lines answered and nothing more;
``("silent", sent)`` nothing answered; ``("wait", seconds, lines)`` simulated
time passes and exactly these lines come; ``("status", prefix)`` a ``?``
answered with a report starting so.
"""
from __future__ import annotations

import pytest

from lps_gui.hardware.grbl.emulator import Faults, GrblEmulator
from lps_gui.hardware.sim_stage import SimulatedStage

from tests.hardware.grbl_port import SteppedPort

BANNER = ["", "Grbl 1.1h ['$' for help]"]
UNLOCK = "[MSG:'$H'|'$X' to unlock]"
RESET_TO_CONTINUE = "[MSG:Reset to continue]"
UNLOCKED = [("ask", b"$X\n", ["[MSG:Caution: Unlocked]", "ok"])]
SETTINGS_LINES = 34  # $$: one line per setting, then ok

EXCHANGES = {
    # system.c system_execute_line(): '$Q' reaches the setting branch, read_float() fails -> STATUS_BAD_NUMBER_FORMAT
    "dollar_q_bad_number": UNLOCKED + [("ask", b"$Q\n", ["error:2"])],
    # settings.c settings_store_global_setting(): the step-rate check is inside #ifdef MAX_STEP_RATE_HZ (off in config.h)
    "max_rate_without_step_rate_check": UNLOCKED + [("ask", b"$110=100000\n", ["ok"])],
    # gcode.c [15. coordinate system select] and G10 L2 P2: G55 reads its own EEPROM data; report.c WCO
    "g55_work_coordinate_system": UNLOCKED + [
        ("ask", b"G10 L2 P2 X-400\n", ["ok"]), ("ask", b"G55\n", ["ok"]),
        ("ask", b"$G\n", ["[GC:G0 G55 G17 G21 G90 G94 M5 M9 T0 F0 S0]", "ok"]),
        ("status", "<Idle|MPos:0.000,-500.000,-500.000|FS:0,0|WCO:-400.000,0.000,0.000>")],
    # gcode.c NON_MODAL_SET_COORDINATE_OFFSET: G92 = MPos - WCS - WPos; report.c report_ngc_parameters() [G92:]
    "g92_offset": UNLOCKED + [
        ("ask", b"G92 X0\n", ["ok"]),
        ("ask", b"$#\n", ["[G54:-500.000,-500.000,-500.000]", "[G55:0.000,0.000,0.000]", "[G56:0.000,0.000,0.000]",
                          "[G57:0.000,0.000,0.000]", "[G58:0.000,0.000,0.000]", "[G59:0.000,0.000,0.000]",
                          "[G28:0.000,0.000,0.000]", "[G30:0.000,0.000,0.000]", "[G92:500.000,0.000,0.000]",
                          "[TLO:0.000]", "[PRB:0.000,0.000,0.000:0]", "ok"])],
    # gcode.c NON_MODAL_RESET_COORDINATE_OFFSET: G92.1 zeroes the offset (the next report carries WCO)
    "g92_1_clears_the_offset": UNLOCKED + [
        ("ask", b"G92 X0\n", ["ok"]), ("ask", b"G92.1\n", ["ok"]),
        ("status", "<Idle|MPos:0.000,-500.000,-500.000|FS:0,0|WCO:-500.000,-500.000,-500.000>")],
    # gcode.c step 2: G1 after G0 finds axis_command set -> STATUS_GCODE_AXIS_COMMAND_CONFLICT, before the modal check
    "g0_g1_axis_command_conflict": UNLOCKED + [("ask", b"G0 G1 X450\n", ["error:24"])],
    # gcode.c step 2, 'M': mantissa > 0 -> STATUS_GCODE_COMMAND_VALUE_NOT_INTEGER
    "m5_5_not_integer": UNLOCKED + [("ask", b"M5.5\n", ["error:23"])],
    # gcode.c [20. motion modes] G2/G3: no R, no I/J in the XY plane -> STATUS_GCODE_NO_OFFSETS_IN_PLANE
    "g2_without_offsets": UNLOCKED + [("ask", b"G2 X450 F100\n", ["error:35"])],
    # gcode.c step 2: G0 after G10 (axis_command non-modal) -> error:24; the offset is not applied
    "g10_l20_with_a_motion_word": UNLOCKED + [
        ("ask", b"G10 L20 P1 G0 X450\n", ["error:24"]),
        ("status", "<Idle|MPos:0.000,-500.000,-500.000|FS:0,0|WCO:-500.000,-500.000,-500.000>")],
    # gcode.c: axis words with G4 are the modal motion's (G0): [10. dwell] then [20. motion], no error:31
    "g4_with_axis_words_dwells_then_moves": UNLOCKED + [
        ("ask", b"G4 P0 X441\n", ["ok"]), ("wait", 10.0, []),
        ("status", "<Idle|MPos:-59.000,-500.000,-500.000|FS:0,0|WCO:-500.000,-500.000,-500.000>")],
    # gcode.c [4. set spindle speed] keeps S; report.c report_gcode_modes() prints M3 and S100
    "g_modes_keep_spindle_speed": UNLOCKED + [
        ("ask", b"M3 S100\n", ["ok"]), ("ask", b"$G\n", ["[GC:G0 G54 G17 G21 G90 G94 M3 M9 T0 F0 S100]", "ok"])],
    # settings.c case 22: homing off also clears BITFLAG_SOFT_LIMIT_ENABLE
    "homing_off_clears_soft_limits": UNLOCKED + [
        ("ask", b"$22=0\n", ["ok"]), ("settings", {20: "$20=0", 22: "$22=0"})],
    # protocol.c protocol_exec_rt_suspend(): asleep, only protocol_exec_rt_system() runs: no line is read
    "no_line_read_asleep": UNLOCKED + [
        ("ask", b"$SLP\n", ["ok", "[MSG:Sleeping]"]), ("silent", b"$$\n"), ("status", "<Sleep|"),
        ("ask", b"\x18", BANNER + [UNLOCK])],
    # limits.c limits_go_home() -> ALARM:8, report.c's 500 ms, system.c's ok, main.c's reset flushes RX
    "lines_sent_during_a_failing_homing_are_discarded": [
        ("silent", b"$H\n"), ("silent", b"$$\nG0 X1\n$X\n"),
        ("wait", 6.0, ["ALARM:8", "ok"] + BANNER + [UNLOCK]), ("wait", 1.0, []), ("status", "<Alarm|")],
    # motion_control.c mc_line(): limits_soft_check() runs before the check-mode return -> ALARM:2, reset needed
    "check_mode_keeps_soft_limits": UNLOCKED + [
        ("ask", b"$C\n", ["[MSG:Enabled]", "ok"]), ("ask", b"G0 X1000\n", ["ALARM:2"]),
        ("wait", 0.6, [RESET_TO_CONTINUE]), ("ask", b"\x18", ["ok"] + BANNER + [UNLOCK])],
    # protocol.c protocol_exec_rt_system(): ALARM:2, delay_ms(500), [MSG:Reset to continue], then the reset
    # flag is cleared: a reset in the delay is lost, '?' is not answered, a reset after it works
    "critical_alarm_delay_and_lost_reset": UNLOCKED + [
        ("ask", b"G0 X1000\n", ["ALARM:2"]), ("silent", b"\x18"), ("wait", 0.49, []),
        ("wait", 0.02, [RESET_TO_CONTINUE]), ("silent", b"?"), ("wait", 1.0, []),
        ("ask", b"\x18", ["ok"] + BANNER + [UNLOCK])],
}


def _rig() -> GrblEmulator:
    stage = SimulatedStage(travel_mm=(-5.0, 500.0), start_mm=500.0, max_rate_mm_min=3000.0)
    return GrblEmulator(stage, faults=Faults(fail_homing=8), homing_init_lock=True, stepped=True)


def _run(port: SteppedPort, steps: list[tuple]) -> None:
    for step in steps:
        kind = step[0]
        if kind == "ask":
            assert port.ask(step[1], len(step[2])) == step[2], step
        elif kind == "silent":
            port.send(step[1])
            assert port.pending() == [], step
            continue
        elif kind == "wait":
            port.advance(step[1])
            assert port.pending() == step[2], step
            continue
        elif kind == "status":
            report = port.ask(b"?")[0]
            assert report.startswith(step[1]), (step, report)
        elif kind == "settings":
            lines = port.ask(b"$$\n", SETTINGS_LINES + 1)
            assert lines[-1] == "ok" and all(v in lines for v in step[1].values()), lines
        assert port.pending() == [], step  # nothing more than the firmware prints


def test_the_rig_is_the_differentials():
    with _rig() as emu:
        port = SteppedPort(emu)
        try:
            assert port.ask(b"?")[0].startswith("<Alarm|MPos:0.000,")  # power-up: HOMING_INIT_LOCK and $22=1
            lines = port.ask(b"$$\n", SETTINGS_LINES + 1)
            for text in ("$20=1", "$22=1", "$23=7", "$24=100.000", "$25=3000.000", "$130=505.000"):
                assert text in lines
            assert port.ask(b"$#\n", 12)[0] == "[G54:-500.000,-500.000,-500.000]"
        finally:
            port.close()


@pytest.mark.parametrize("name", sorted(EXCHANGES))
def test_exchange_answers_as_grbl_1_1h_source(name):
    with _rig() as emu:
        port = SteppedPort(emu)
        try:
            assert port.pending() == []  # the power-up banner went out before the port opened
            _run(port, EXCHANGES[name])
        finally:
            port.close()


def test_there_are_sixteen_exchanges():
    assert len(EXCHANGES) == 16
