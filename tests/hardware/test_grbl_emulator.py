"""The GRBL emulator over a real pty, spoken to byte by byte with pyserial (what GRBL 1.1h would answer).

The emulator's clock is stepped: simulated time passes only in ``e.advance()``,
and every write is read and executed before :meth:`Port.ask` reads the answer,
so a move is still running (or over) exactly when the test says.
"""
from __future__ import annotations

import time

import pytest
import serial

from lps_gui.hardware.grbl.emulator import BANNER, GrblEmulator
from lps_gui.hardware.sim_stage import SimulatedStage


class Port:
    """Raw pyserial access to a stepped emulator: send bytes, let it execute them, read lines until one matches."""

    def __init__(self, emu: GrblEmulator) -> None:
        self.emu = emu
        self.ser = serial.Serial(emu.path, 115200, timeout=0.02)
        self.ser.reset_input_buffer()
        self.buf = b""
        self.sent = emu.bytes_in

    def write(self, data: bytes) -> None:
        """Write, then let the emulator read all of it and execute it (no simulated time passes)."""
        self.ser.write(data)
        self.ser.flush()
        self.sent += len(data)
        self.emu.settle(until_bytes=self.sent)

    def ask(self, data: bytes, until: str = "ok", timeout_s: float = 5.0) -> list[str]:
        self.write(data)
        return self.lines(until, timeout_s)

    def lines(self, until: str, timeout_s: float = 5.0) -> list[str]:
        """Lines up to one starting with ``until``; the bound only stops a hang (answers are already sent)."""
        out: list[str] = []
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            self.buf += self.ser.read(256)
            while b"\r\n" in self.buf:
                raw, self.buf = self.buf.split(b"\r\n", 1)
                out.append(raw.decode("latin-1"))
                if out[-1].startswith(until) or (until == "ok" and out[-1].startswith("error:")):
                    return out
        raise AssertionError(f"no {until!r} within {timeout_s} s; got {out}")

    def close(self) -> None:
        self.ser.close()


@pytest.fixture
def emu():
    with GrblEmulator(SimulatedStage(travel_mm=(0.0, 100.0), start_mm=10.0), stepped=True) as e:
        port = Port(e)
        yield e, port
        port.close()


def test_reset_prints_banner_then_build_info_and_help(emu):
    e, port = emu
    assert port.ask(b"\x18", until="Grbl") == ["", "Grbl 1.1h ['$' for help]"]
    assert BANNER == "\r\nGrbl 1.1h ['$' for help]\r\n"
    assert port.ask(b"$I\n") == ["[VER:1.1h.20190830:]", "[OPT:VL,15,128]", "ok"]  # built without HOMING_INIT_LOCK
    assert port.ask(b"$\n") == ["[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]", "ok"]
    assert port.ask(b"$G\n") == ["[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]", "ok"]
    assert port.ask(b"$I=rig 1\n") == ["ok"]
    assert port.ask(b"$I\n")[0] == "[VER:1.1h.20190830:RIG1]"  # GRBL upper-cases and strips spaces


def test_settings_listing_order_and_format(emu):
    _, port = emu
    lines = port.ask(b"$$\n")
    numbers = [int(ln[1:].split("=")[0]) for ln in lines[:-1]]
    assert numbers == [0, 1, 2, 3, 4, 5, 6, 10, 11, 12, 13, 20, 21, 22, 23, 24, 25, 26, 27, 30, 31, 32,
                       100, 101, 102, 110, 111, 112, 120, 121, 122, 130, 131, 132]
    assert "$10=1" in lines and "$11=0.010" in lines and "$130=100.000" in lines
    assert port.ask(b"$110=1200\n") == ["ok"]
    assert "$110=1200.000" in port.ask(b"$$\n")
    assert port.ask(b"$999=1\n") == ["error:3"]
    assert port.ask(b"$110=-5\n") == ["error:4"]
    assert port.ask(b"$0=2\n") == ["error:6"]
    assert port.ask(b"$100=100000\n") == ["ok"]  # settings.c: no step-rate check without MAX_STEP_RATE_HZ
    assert port.ask(b"$Q\n") == ["error:2"]  # system.c: read_float() fails on 'Q'
    assert port.ask(b"$10=\n") == ["error:2"] and port.ask(b"$10\n") == ["error:3"]


def test_status_report_fields_follow_mask_and_refresh_counters(emu):
    e, port = emu
    port.ask(b"\x18", until="Grbl")
    first = port.ask(b"?", until="<")[-1]
    assert first == "<Idle|MPos:-90.000,-100.000,-100.000|FS:0,0|WCO:-100.000,-100.000,-100.000>"
    assert port.ask(b"?", until="<")[-1] == "<Idle|MPos:-90.000,-100.000,-100.000|FS:0,0|Ov:100,100,100>"
    assert port.ask(b"?", until="<")[-1] == "<Idle|MPos:-90.000,-100.000,-100.000|FS:0,0>"
    port.ask(b"$10=2\n")  # WPos and buffer state
    assert port.ask(b"?", until="<")[-1] == "<Idle|WPos:10.000,0.000,0.000|Bf:15,128|FS:0,0>"


def test_motion_states_and_error_codes(emu):
    e, port = emu
    assert port.ask(b"G1 X50\n") == ["error:22"]  # no feed rate yet
    assert port.ask(b"G1 X50 F300\n") == ["ok"]  # 8 simulated s
    e.advance(1.0)
    assert port.ask(b"?", until="<")[-1].startswith("<Run|")
    port.write(b"G4 P0\n")  # waits for the move to end
    with pytest.raises(AssertionError, match=r"got \[\]"):
        port.lines("ok", timeout_s=0.05)
    e.advance(8.0)
    assert port.lines("ok") == ["ok"]
    assert port.ask(b"?", until="<")[-1].startswith("<Idle|MPos:-50.000")
    port.write(b"G91 G0 X-5\nG4 P0\n")
    e.advance(2.0)
    assert port.lines("ok") == ["ok"] and port.lines("ok") == ["ok"]
    assert e.stage.status().work_mm[0] == pytest.approx(45.0)
    assert port.ask(b"G2 X1 Y1\n") == ["error:35"]  # an arc needs R or I/J in the XY plane
    assert port.ask(b"G0 G1 X1\n") == ["error:24"]  # two commands that use axis words
    assert port.ask(b"G17 G18\n") == ["error:21"]
    assert port.ask(b"(comment only)\n") == ["ok"]
    assert port.ask(b"G1 X" + b"1" * 90 + b"\n") == ["error:11"]


def test_jog_rules_and_cancel(emu):
    e, port = emu
    assert port.ask(b"$J=G91 X500 F1000\n") == ["error:15"]
    assert port.ask(b"$J=G91 X5\n") == ["error:22"]
    assert port.ask(b"$J=X5 F100 S3\n") == ["error:36"]
    assert port.ask(b"$J=G91 X80 F300\n") == ["ok"]  # 16 simulated s
    e.advance(2.0)
    assert port.ask(b"?", until="<")[-1].startswith("<Jog|")
    assert port.ask(b"G1 X1 F100\n") == ["error:9"]  # G-code locked while jogging
    assert port.ask(b"$H\n") == ["error:8"]
    port.write(b"\x85")
    e.advance(2.0)  # the controlled stop
    assert e.stage.status().state == "Idle" and 10.0 < e.stage.status().work_mm[0] < 90.0


def test_soft_limit_alarm_is_critical_until_reset_then_locked(emu):
    e, port = emu
    assert port.ask(b"G0 X500\n", until="ALARM") == ["ALARM:2"]
    e.advance(0.5)  # report.c's delay
    assert port.lines(until="[MSG") == ["[MSG:Reset to continue]"]
    port.write(b"?$I\n")
    e.advance(1.0)
    with pytest.raises(AssertionError, match=r"got \[\]"):
        port.lines(until="<", timeout_s=0.05)  # '?' and lines are ignored in a critical alarm
    reply = port.ask(b"\x18", until="[MSG")
    assert reply[-2:] == ["Grbl 1.1h ['$' for help]", "[MSG:'$H'|'$X' to unlock]"]
    assert port.ask(b"G0 X1\n") == ["error:9"]
    assert port.ask(b"$X\n") == ["[MSG:Caution: Unlocked]", "ok"]
    assert port.ask(b"?", until="<")[-1].startswith("<Idle|")


def test_homing_and_reset_during_motion(emu):
    e, port = emu
    port.write(b"$H\n")
    e.advance(60.0)
    assert port.lines("ok") == ["ok"]
    assert e.stage.homed and e.stage.status().work_mm[0] == pytest.approx(1.0)
    port.ask(b"G1 X90 F300\n")
    e.advance(1.0)
    assert port.ask(b"\x18", until="ALARM") == ["ALARM:3"]  # report.c: 500 ms before the reset acts
    e.advance(0.6)
    reply = port.lines("[MSG")
    assert reply[-1] == "[MSG:'$H'|'$X' to unlock]"


def test_rx_buffer_overflow_is_detected_when_host_ignores_counting(emu):
    e, port = emu
    port.ask(b"$110=60\n")  # slow moves keep the planner full
    lines = b"".join(f"G1 X{20 + i}.000 F60\n".encode() for i in range(30))  # 30 * 15 bytes
    port.write(lines)
    assert e.rx_overflow_bytes > 0


def test_check_mode_and_sleep(emu):
    e, port = emu
    assert port.ask(b"$C\n") == ["[MSG:Enabled]", "ok"]
    assert port.ask(b"G0 X50\n") == ["ok"]
    assert port.ask(b"?", until="<")[-1].startswith("<Check|MPos:-90.000")
    assert port.ask(b"$J=G91 X1 F100\n") == ["error:8"]  # jogging needs Idle or Jog, not Check
    assert port.ask(b"$C\n", until="Grbl") == ["[MSG:Disabled]", "ok", "", "Grbl 1.1h ['$' for help]"]
    assert port.ask(b"$SLP\n") == ["ok"] and port.lines("[MSG") == ["[MSG:Sleeping]"]
    assert port.ask(b"?", until="<")[-1].startswith("<Sleep|")
    assert port.ask(b"\x18", until="[MSG")[-1] == "[MSG:'$H'|'$X' to unlock]"


# ---------------------------------------------------------------------------------------------
# Sequences of GRBL 1.1h's own source (main.c, protocol.c, system.c, limits.c, motion_control.c)


@pytest.fixture
def stock():
    """Stock 1.1h (HOMING_INIT_LOCK) with $22=1, as it powers up; port opened before the banner."""
    e = GrblEmulator(SimulatedStage(travel_mm=(0.0, 100.0), start_mm=10.0), homing_init_lock=True, stepped=True)
    e.start()
    port = Port(e)
    yield e, port
    port.close()
    e.stop()


def test_power_up_with_homing_enabled_is_alarm_with_unlock_message(stock):
    e, port = stock
    assert e.firmware.settings[22] == 1.0
    assert port.ask(b"?", until="<")[-1].startswith("<Alarm|")
    assert port.ask(b"$I\n") == ["[VER:1.1h.20190830:]", "[OPT:V,15,128]", "ok"]
    assert port.ask(b"G0 X1\n") == ["error:9"]
    assert port.ask(b"$X\n") == ["[MSG:Caution: Unlocked]", "ok"]
    # a soft reset out of Idle keeps Idle (main.c keeps prior_state): banner without the unlock message
    assert port.ask(b"\x18", until="Grbl") == ["", "Grbl 1.1h ['$' for help]"]
    assert port.ask(b"?", until="<")[-1].startswith("<Idle|")


def test_failed_homing_is_alarm_then_the_ok_of_H_then_the_reset_banner(stock):
    e, port = stock
    e.faults.fail_homing = 8
    port.write(b"$H\n")
    e.advance(2.0)  # fails half-way; report.c's 500 ms; then the ok of $H and main()'s reset
    assert port.lines(until="[MSG") == ["ALARM:8", "ok", "", "Grbl 1.1h ['$' for help]", "[MSG:'$H'|'$X' to unlock]"]
    assert not e.stage.homed and port.ask(b"?", until="<")[-1].startswith("<Alarm|")
    e.faults.fail_homing = 9
    port.write(b"$H\n")
    e.advance(2.0)
    assert port.lines(until="[MSG")[:2] == ["ALARM:9", "ok"]
    e.faults.fail_homing = None
    port.write(b"$H\n")
    e.advance(10.0)
    assert port.lines(until="ok") == ["ok"] and e.stage.homed


def test_status_asked_during_homing_is_answered_when_the_cycle_ends(stock):
    e, port = stock
    port.write(b"$H\n")
    assert e.stage.status().state == "Home"  # the cycle runs: the next '?' arrives during it
    port.write(b"?")
    with pytest.raises(AssertionError, match=r"got \[\]"):
        port.lines(until="<", timeout_s=0.05)  # limits_go_home() never reports: the flag waits
    e.advance(10.0)
    reply = port.lines(until="ok")
    assert reply[0].startswith("<Home|MPos:-99.000,") and reply[1:] == ["ok"]


def test_soft_limit_is_alarm_2_and_the_line_ok_comes_after_the_reset(stock):
    e, port = stock
    port.ask(b"$X\n")
    assert port.ask(b"G0 X500\n", until="ALARM") == ["ALARM:2"]
    e.advance(0.5)
    assert port.lines(until="[MSG") == ["[MSG:Reset to continue]"]
    port.write(b"$X\n")  # ignored: the critical loop reads nothing, the reset flushes RX
    e.advance(1.0)
    with pytest.raises(AssertionError, match=r"got \[\]"):
        port.lines(until="ok", timeout_s=0.05)
    assert port.ask(b"\x18", until="[MSG") == ["ok", "", "Grbl 1.1h ['$' for help]", "[MSG:'$H'|'$X' to unlock]"]


def test_lines_during_a_feed_hold_are_answered_only_after_resume(stock):
    e, port = stock
    port.ask(b"$X\n")
    assert port.ask(b"G1 X90 F300\n") == ["ok"]
    e.advance(2.0)
    port.write(b"!")
    e.advance(2.0)  # the controlled stop
    port.write(b"G1 X20 F3000\n$$\n")  # received, not executed: protocol_exec_rt_suspend()
    e.advance(5.0)
    with pytest.raises(AssertionError, match=r"got \[\]"):
        port.lines(until="ok", timeout_s=0.05)
    assert port.ask(b"?", until="<")[-1].startswith("<Hold:0|")  # status still answered
    port.write(b"~")
    e.advance(0.1)
    assert port.lines(until="ok") == ["ok"]  # the G1
    assert port.lines(until="ok")[-1] == "error:8"  # $$ during the resumed cycle (system.c: not in CYCLE)


def test_idle_feed_hold_also_holds_back_lines(stock):
    e, port = stock
    port.ask(b"$X\n")
    port.write(b"!")
    assert port.ask(b"?", until="<")[-1].startswith("<Hold:0|")
    port.write(b"\n")
    e.advance(1.0)
    with pytest.raises(AssertionError, match=r"got \[\]"):
        port.lines(until="ok", timeout_s=0.05)
    port.write(b"~")
    assert port.lines(until="ok") == ["ok"]


def test_g10_l20_sets_the_work_offset_reported_as_wco_and_kept_over_a_reset(stock):
    e, port = stock
    port.ask(b"$X\n")
    assert port.ask(b"G0 X30\n") == ["ok"]
    port.write(b"G10 L20 P1 X0\n")  # waits for the move to end (FORCE_BUFFER_SYNC_DURING_EEPROM_WRITE)
    e.advance(5.0)
    assert port.lines("ok") == ["ok"]
    report = port.ask(b"?", until="<")[-1]
    assert "MPos:-70.000" in report and "WCO:-70.000,-100.000,-100.000" in report  # sent at once after the change
    assert port.ask(b"G0 X5\n") == ["ok"]  # work 5 = stage 35
    e.advance(5.0)
    assert e.stage.status().work_mm[0] == pytest.approx(35.0)
    port.ask(b"\x18", until="Grbl")
    assert "WCO:-70.000,-100.000,-100.000" in port.ask(b"?", until="<")[-1]  # G54 is in EEPROM
    assert port.ask(b"G10 L2 P1 X-100\n") == ["ok"]  # back to the power-up offset
    assert port.ask(b"G10 X0\n") == ["error:28"] and port.ask(b"G10 L20 P7 X0\n") == ["error:29"]
    assert port.ask(b"G10 L3 P1 X0\n") == ["error:20"]
    assert port.ask(b"G0 L2 X1\n") == ["error:36"]


def test_work_coordinate_systems_g92_and_rst_hash(stock):
    e, port = stock
    port.ask(b"$X\n")
    assert port.ask(b"G10 L2 P3 X-60 Y-100 Z-100\n") == ["ok"]  # G56: stage 40 is work 0
    assert port.ask(b"G56 G0 X5\n") == ["ok"]
    e.advance(5.0)
    assert e.stage.status().work_mm[0] == pytest.approx(45.0)
    assert port.ask(b"G92 X0\n") == ["ok"]  # here is 0 now: G92 = MPos - G56 - 0
    assert port.ask(b"$#\n")[8] == "[G92:5.000,0.000,0.000]"
    assert "WCO:-55.000,-100.000,-100.000" in port.ask(b"?", until="<")[-1]
    assert port.ask(b"G91 G0 X-5\n") == ["ok"]
    e.advance(5.0)
    assert e.stage.status().work_mm[0] == pytest.approx(40.0)
    port.ask(b"\x18", until="Grbl")  # a reset clears G92 and selects G54 again (gc_init)
    assert port.ask(b"$G\n")[0] == "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]"
    assert port.ask(b"$#\n")[2] == "[G56:-60.000,-100.000,-100.000]"
    assert port.ask(b"$RST=#\n", until="Grbl")[:2] == ["[MSG:Restoring defaults]", "ok"]
    lines = port.ask(b"$#\n")
    assert lines[0] == "[G54:-100.000,-100.000,-100.000]"  # by design: G54 stays at the base
    assert lines[2] == "[G56:0.000,0.000,0.000]"


def test_the_stage_s_neutral_reasons_all_have_a_grbl_code_and_back():
    """GRBL's numbers live in grbl/codes.py only: every neutral refusal and alarm is said as one, and read back."""
    from lps_gui.hardware.grbl.codes import ALARMS, ERRORS, GrblError, as_grbl
    from lps_gui.hardware.refusals import Alarm, Refusal, StageAlarm, StageRefused

    for alarm in Alarm:
        g = as_grbl(StageAlarm(alarm))
        assert g.kind == "alarm" and (g.code == 0 or g.code in ALARMS) and g.reason is alarm
    for reason in Refusal:
        g = as_grbl(StageRefused(reason))
        assert g.kind == "error" and g.code in ERRORS
        assert g.reason is (None if g.code == 20 else reason)  # error:20 is any unsupported word, not one reason
    assert GrblError("error", 15).reason is Refusal.BEYOND_TRAVEL and GrblError("alarm", 2).reason is Alarm.SOFT_LIMIT


def test_dollar_settings_are_the_stage_s_named_ones_and_grbl_s_rules(emu):
    """$110/$22/$20 write the simulated machine's named settings; settings.c's refusals are GRBL's codes."""
    e, port = emu
    assert port.ask(b"$110=1200\n") == ["ok"] and e.stage.machine["max_rate_mm_min.X"] == 1200.0
    assert port.ask(b"$130=90\n") == ["ok"] and e.stage.travel_mm == (0.0, 90.0)
    assert port.ask(b"$23=1\n") == ["ok"] and e.firmware.settings[23] == 1.0  # GRBL's own: not the machine's
    assert port.ask(b"$22=0\n") == ["ok"] and e.stage.machine["homing"] == 0.0 and e.stage.machine["soft_limits"] == 0.0
    assert port.ask(b"$20=1\n") == ["error:10"]  # soft limits need homing
    assert port.ask(b"$H\n") == ["error:5"]  # homing not enabled


def test_status_reports_the_stage_s_planner_and_grbl_s_own_rx_buffer(emu):
    """Bf: the simulated stage's free planner blocks, then GRBL's 128-byte RX buffer (the firmware's, not the stage's)."""
    e, port = emu
    assert port.ask(b"$10=3\n") == ["ok"]  # MPos and Bf
    assert port.ask(b"G1 X50 F300\n") == ["ok"]
    assert e.stage.planner_free() == 14
    assert "|Bf:14,128|" in port.ask(b"?", until="<")[-1]
