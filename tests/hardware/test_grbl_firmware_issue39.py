"""The emulator differences of issue 39 (R1-R17) that were closed, with the firmware's bytes.

Each row is what gnea/grbl 1.1h prints, read in the function named in the
row's comment, on the rig of ``test_grbl_firmware_source.py`` (stock build with
HOMING_INIT_LOCK, ``$22=1 $20=1``, travel -5..500 mm, the carriage at machine
0, G54 at -500) without its homing fault. Steps as there: ``("ask", sent, lines)``
exactly these lines and nothing more; ``("silent", sent)`` nothing answered;
``("wait", seconds, lines)`` simulated time passes and exactly these lines come;
``("status", prefix)``; ``("settings", {n: "$n=v"})``. Differences kept by
design are listed in docs/hardware.md.
"""
from __future__ import annotations

import pytest

from lps_gui.hardware.grbl.emulator import GrblEmulator
from lps_gui.hardware.sim_stage import SimulatedStage

from tests.hardware.grbl_port import SteppedPort
from tests.hardware.test_grbl_firmware_source import BANNER, RESET_TO_CONTINUE, UNLOCK, UNLOCKED, _run

ZERO_IN = "0.0000,0.0000,0.0000"

EXCHANGES = {
    # R1 report.c report_realtime_status(): Pn: probe pin then limit pins; $5=1 inverts unwired (open) limit inputs
    "R1_inverted_limit_pins_read_triggered": UNLOCKED + [
        ("ask", b"$5=1\n", ["ok"]),
        ("status", "<Idle|MPos:0.000,-500.000,-500.000|FS:0,0|Pn:XYZ|"),
        ("ask", b"$6=1\n", ["ok"]), ("status", "<Idle|MPos:0.000,-500.000,-500.000|FS:0,0|Pn:PXYZ")],
    # R2 limits.c ISR(LIMIT_INT_vect): with $21=1 reaching a switch is mc_reset() + ALARM:1 (critical, report.c's
    # 500 ms, [MSG:Reset to continue], no '?' answered); protocol.c CHECK_LIMITS_AT_INIT: the switch still pressed
    # at the reset -> [MSG:Check Limits] and Alarm; report.c Pn:X
    "R2_hard_limit_switch_at_the_end_of_the_travel": UNLOCKED + [
        ("ask", b"G91 G0 X-10\n", ["ok"]), ("wait", 2.0, []), ("ask", b"$20=0\n", ["ok"]), ("ask", b"$21=1\n", ["ok"]),
        ("ask", b"G0 X20\n", ["ok"]), ("wait", 2.0, ["ALARM:1", RESET_TO_CONTINUE]), ("silent", b"?"),
        ("ask", b"\x18", BANNER + ["[MSG:Check Limits]", UNLOCK]),
        ("status", "<Alarm|MPos:0.000,-500.000,-500.000|FS:0,0|Pn:X|WCO:")],
    # R3 system.c case 'H': sys.state = STATE_HOMING before line[2] is checked -> error:3, the state stays Home;
    # '$X' only acts in Alarm (ok, no effect); '$#' needs Idle or Alarm; motion_control.c mc_reset(): a reset in STATE_HOMING is EXEC_ALARM_HOMING_FAIL_RESET (ALARM:6)
    "R3_dollar_hx_stays_in_home_and_a_reset_is_alarm_6": UNLOCKED + [
        ("ask", b"$HX\n", ["error:3"]), ("status", "<Home|"), ("ask", b"$X\n", ["ok"]), ("ask", b"$#\n", ["error:8"]),
        ("ask", b"\x18", ["ALARM:6"]), ("wait", 0.6, BANNER + [UNLOCK]), ("status", "<Alarm|")],
    # R4 motion_control.c mc_probe_cycle(): no contact -> ALARM:5 (report.c's 500 ms), [PRB:] (MESSAGE_PROBE_COORDINATES)
    # with the last probe position and 0, then gc_execute_line()'s ok; G38.3 stores where it stopped
    "R4_probe_toward_without_contact": UNLOCKED + [
        ("silent", b"G91 G38.2 X-10 F1000\n"), ("wait", 1.0, ["ALARM:5"]),
        ("wait", 0.6, ["[PRB:0.000,0.000,0.000:0]", "ok"]), ("status", "<Alarm|MPos:-10.000,")],
    "R4_probe_toward_no_error_reports_where_it_stopped": UNLOCKED + [
        ("silent", b"G91 G38.3 X-10 F1000\n"), ("wait", 1.0, ["[PRB:-10.000,-500.000,-500.000:0]", "ok"]),
        ("status", "<Idle|MPos:-10.000,")],
    # R5 mc_probe_cycle(): probing away inverts the pin, an unwired probe then reads triggered: PROBE_FAIL_INITIAL
    "R5_probe_away_without_a_probe_fails_at_once": UNLOCKED + [
        ("ask", b"G91 G38.4 X-10 F1000\n", ["ALARM:4"]), ("wait", 0.6, ["ok"]),
        ("status", "<Alarm|MPos:0.000,"), ("ask", b"$X\n", ["[MSG:Caution: Unlocked]", "ok"]),
        ("ask", b"G91 G38.5 X-10 F1000\n", ["ALARM:4"]), ("wait", 0.6, ["ok"])],
    # R6 gcode.c [21] PROGRAM_FLOW_PAUSED: EXEC_FEED_HOLD then protocol_execute_realtime() suspends until '~'
    "R6_m0_answers_after_cycle_start": UNLOCKED + [
        ("silent", b"M0\n"), ("status", "<Hold:0|"), ("ask", b"~", ["ok"]), ("status", "<Idle|")],
    # R7 spindle_control.c spindle_set_state(): report_ovr_counter = 0 on every change; report.c: Ov: (one report
    # after a WCO), A:S only while spindle_get_state() sees the PWM on (S0 is off); FS: sys.spindle_speed ($30 clamp)
    "R7_spindle_reports_ov_and_accessories_at_once": UNLOCKED + [
        ("ask", b"M3 S2000\n", ["ok"]),
        ("status", "<Idle|MPos:0.000,-500.000,-500.000|FS:0,1000|WCO:-500.000,-500.000,-500.000>"),
        ("status", "<Idle|MPos:0.000,-500.000,-500.000|FS:0,1000|Ov:100,100,100|A:S>"),
        ("ask", b"S0\n", ["ok"]), ("status", "<Idle|MPos:0.000,-500.000,-500.000|FS:0,0|Ov:100,100,100>")],
    # R8 protocol.c protocol_exec_rt_system(): overrides change sys.f_override / r_override (FS: is the real rate),
    # report_ovr_counter = 0; 0xA0 toggles flood in gc_state.modal.coolant (coolant_set_state())
    "R8_overrides_and_coolant_toggle": UNLOCKED + [
        ("silent", b"\x91"), ("status", "<Idle|MPos:0.000,-500.000,-500.000|FS:0,0|WCO:"),
        ("status", "<Idle|MPos:0.000,-500.000,-500.000|FS:0,0|Ov:110,100,100>"),
        ("ask", b"G91 G1 X-50 F1000\n", ["ok"]), ("wait", 1.0, []), ("report", "|FS:1100,0"),
        ("wait", 3.0, []), ("silent", b"\x96"), ("ask", b"G91 G0 X-100\n", ["ok"]), ("wait", 0.5, []),
        ("report", "|FS:1500,0"), ("wait", 5.0, []), ("silent", b"\xa0"),
        ("ask", b"$G\n", ["[GC:G0 G54 G17 G21 G91 G94 M5 M8 T0 F1000 S0]", "ok"]), ("report", "|Ov:110,50,100|A:F>")],
    # R9 protocol.c EXEC_SAFETY_DOOR: [MSG:Check Door], state Door; protocol_exec_rt_suspend(): no door switch wired,
    # so the door reads closed (Door:0) and no line is read until '~'
    "R9_safety_door_command": UNLOCKED + [
        ("ask", b"\x84", ["[MSG:Check Door]"]), ("status", "<Door:0|MPos:0.000,"), ("silent", b"$G\n"),
        ("ask", b"~", ["[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]", "ok"]), ("status", "<Idle|")],
    # R10 system.c '$Nx=line': runs the line through gc_execute_line(), stores it; '$N' lists it (report_startup_line());
    # protocol_main_loop() runs it after the banner: report_execute_startup_message() '>G21:ok'
    "R10_startup_lines_are_stored_and_run_after_a_reset": UNLOCKED + [
        ("ask", b"$N0=g21\n", ["ok"]), ("ask", b"$N\n", ["$N0=G21", "$N1=", "ok"]),
        ("ask", b"$N1=G5\n", ["error:20"]), ("ask", b"\x18", BANNER + [">G21:ok"]),
        ("ask", b"$G\n", ["[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]", "ok"])],
    # R11 settings.c settings_restore(): settings = defaults (defaults.h DEFAULTS_GENERIC), then mc_reset()
    "R11_restore_writes_the_defaults_h_values": UNLOCKED + [
        ("ask", b"$RST=$\n", ["[MSG:Restoring defaults]", "ok"] + BANNER),
        ("settings", {10: "$10=1", 20: "$20=0", 22: "$22=0", 25: "$25=500.000", 110: "$110=500.000",
                      120: "$120=10.000", 130: "$130=200.000"})],
    # R12 report.c report_probe_parameters(): report_util_axis_values() prints inches with $13=1
    "R12_probe_position_in_inches": UNLOCKED + [
        ("ask", b"$13=1\n", ["ok"]),
        ("ask", b"$#\n", ["[G54:-19.6850,-19.6850,-19.6850]"] + [f"[{n}:{ZERO_IN}]" for n in
                         ("G55", "G56", "G57", "G58", "G59", "G28", "G30", "G92")]
         + ["[TLO:0.0000]", f"[PRB:{ZERO_IN}:0]", "ok"])],
    # R13 serial.c ISR + protocol_main_loop(): the loop reads each byte as it arrives, so a 192-byte burst of 16
    # moves does not overflow the 128-byte RX buffer: 15 fill the planner, the 16th waits for a free block
    "R13_a_burst_over_127_bytes_is_read_as_it_arrives": UNLOCKED + [
        ("ask", b"G91\n", ["ok"]), ("ask", b"G1 X-1 F100\n" * 16, ["ok"] * 15), ("wait", 1.0, ["ok"])],
    # R14 protocol_main_loop(): comment characters are dropped as they are read, never buffered
    "R14_a_150_byte_line_with_a_comment": UNLOCKED + [
        ("ask", b"G4 P0 (" + b"x" * 140 + b")\n", ["ok"]), ("ask", b"$G\n", ["[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]", "ok"])],
    # R15 gcode.c: a jog's target is never filled without axis words: a jog to machine zero
    "R15_jog_without_axis_words_goes_to_machine_zero": UNLOCKED + [
        ("ask", b"G91 G0 X-50\n", ["ok"]), ("wait", 5.0, []), ("status", "<Idle|MPos:-50.000,-500.000,-500.000"),
        ("ask", b"$J=F3000\n", ["ok"]), ("wait", 25.0, []), ("status", "<Idle|MPos:0.000,0.000,0.000")],
    # R16 limits.c limits_go_home(): a reset in the pull-off sets ALARM:6, then the still-engaged switch
    # EXEC_ALARM_HOMING_FAIL_PULLOFF replaces it; report.c's 500 ms, system.c's ok of $H, main()'s re-init
    "R16_reset_during_the_homing_pull_off_is_alarm_8": [
        ("silent", b"$H\n"), ("wait", 10.4, []), ("ask", b"\x18", ["ALARM:8"]),
        ("wait", 0.6, ["ok"] + BANNER + [UNLOCK]), ("status", "<Alarm|")],
    # R17 motion_control.c mc_reset(): in a cycle EXEC_ALARM_ABORT_CYCLE; protocol_exec_rt_system() prints ALARM:3 and
    # waits report.c's 500 ms before it acts on the reset; main() then clears the '?' flag and flushes RX
    "R17_reset_in_motion_alarm_3_then_the_banner_500_ms_later": UNLOCKED + [
        ("ask", b"G91 G0 X-100\n", ["ok"]), ("wait", 0.5, []), ("ask", b"\x18", ["ALARM:3"]),
        ("silent", b"?$G\n"), ("wait", 0.45, []), ("wait", 0.1, BANNER + [UNLOCK]), ("status", "<Alarm|")],
}


def _steps(port: SteppedPort, steps: list[tuple]) -> None:
    """test_grbl_firmware_source's steps, and ``("report", text)``: a ``?`` answered with a report containing ``text``."""
    for step in steps:
        if step[0] == "report":
            report = port.ask(b"?")[0]
            assert step[1] in report, (step, report)
            assert port.pending() == [], step
        else:
            _run(port, [step])


def _rig() -> GrblEmulator:
    stage = SimulatedStage(travel_mm=(-5.0, 500.0), start_mm=500.0, max_rate_mm_min=3000.0)
    return GrblEmulator(stage, homing_init_lock=True, stepped=True)


@pytest.mark.parametrize("name", sorted(EXCHANGES))
def test_exchange_answers_as_grbl_1_1h_source(name):
    with _rig() as emu:
        port = SteppedPort(emu)
        try:
            _steps(port, EXCHANGES[name])
        finally:
            port.close()
