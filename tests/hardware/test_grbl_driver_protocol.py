"""GrblStage against scripted (sent, reply) pairs: every command's exact bytes and its answer handling."""
from __future__ import annotations

import threading
import time

import pytest

from lps_gui.errors import HardwareError
from lps_gui.hardware.grbl.codes import GrblError
from lps_gui.hardware.grbl.driver import GrblStage
from tests.hardware.scripted import BANNER, CONNECT, IDLE, ScriptedSerial, expected_protocol


def test_connect_reads_banner_build_info_settings_and_status():
    with expected_protocol([]) as (stage, _):
        assert stage.version == "1.1h"
        assert stage.build_info.planner_blocks == 15 and stage.build_info.rx_buffer_bytes == 128
        assert stage.settings[110] == 3000.0
        st = stage._status  # the report read during connect (no further "?" is scripted)
        assert st.machine_mm == (-500.0, 0.0, 0.0) and st.work_mm == (0.0, 0.0, 0.0)
        assert stage.describe()["version"] == "1.1h"


def test_connect_without_reset_only_asks():
    script = [(b"$I\n", b"[VER:1.1h.20190830:]\r\n[OPT:V,15,128]\r\nok\r\n"), (b"$$\n", b"$10=1\r\nok\r\n"), (b"?", IDLE)]
    with expected_protocol(script, connect=False, reset_on_connect=False) as (stage, _):
        stage.connect()
        assert stage.connected


def test_status_combines_wco_from_earlier_report_and_wpos():
    script = [
        (b"?", b"<Run|MPos:-400.000,0.000,0.000|Bf:14,100|FS:1500,0|Ov:110,100,100>\r\n"),
        (b"?", b"<Hold:0|WPos:120.000,0.000,0.000|FS:0,0|Pn:X>\r\n"),
    ]
    with expected_protocol(script) as (stage, _):
        run = stage.status()
        assert run.state == "Run" and run.work_mm[0] == pytest.approx(100.0)
        assert run.buffer == (14, 100) and run.feed_mm_min == 1500.0 and run.overrides == (110, 100, 100)
        hold = stage.status()
        assert (hold.state, hold.substate, hold.pins) == ("Hold", 0, "X")
        assert hold.machine_mm[0] == pytest.approx(-380.0) and hold.overrides == (110, 100, 100)


def test_move_to_sends_absolute_metric_feed_move():
    with expected_protocol([(b"G90 G21 G1 X12.5 F600\n", b"ok\r\n")]) as (stage, _):
        stage.move_to(12.5, 600.0)


def test_jog_and_jog_cancel():
    with expected_protocol([(b"$J=G91 G21 X-2 F1000\n", b"ok\r\n"), (b"\x85", b"")]) as (stage, _):
        stage.jog(-2.0, 1000.0)
        stage.jog_cancel()


def test_wait_idle_polls_until_idle_after_motion():
    script = [
        (b"?", b"<Run|MPos:-450.000,0.000,0.000|FS:3000,0>\r\n"),
        (b"?", b"<Run|MPos:-420.000,0.000,0.000|FS:3000,0>\r\n"),
        (b"?", b"<Idle|MPos:-400.000,0.000,0.000|Bf:15,128|FS:0,0>\r\n"),
    ]
    with expected_protocol(script) as (stage, _):
        st = stage.wait_idle(timeout_s=1.0)
        assert st.idle and st.work_mm[0] == pytest.approx(100.0)


def test_home_unlock_hold_resume_reset():
    script = [
        (b"$H\n", b"ok\r\n"),
        (b"$X\n", b"[MSG:Caution: Unlocked]\r\nok\r\n"),
        (b"!", b""),
        (b"?", b"<Hold:1|MPos:-500.000,0.000,0.000|FS:0,0>\r\n"),  # feed_hold() waits until the hold is reported
        (b"?", b"<Hold:1|MPos:-500.000,0.000,0.000|FS:0,0>\r\n"),  # resume() waits until it is complete...
        (b"?", b"<Hold:0|MPos:-500.000,0.000,0.000|FS:0,0>\r\n"),
        (b"~", b""),
        (b"?", b"<Hold:0|MPos:-500.000,0.000,0.000|FS:0,0>\r\n"),  # ...and until a report has left it
        (b"?", IDLE),
        (b"\x18", b"ALARM:3\r\n" + BANNER + b"[MSG:'$H'|'$X' to unlock]\r\n"),
    ]
    messages = []
    with expected_protocol(script) as (stage, _):
        stage.events.subscribe(messages.append)
        stage.home()
        stage.unlock()
        stage.feed_hold()
        stage.resume()
        stage.soft_reset()
    kinds = [(e.kind, e.code) for e in messages]
    assert ("message", None) in kinds and ("alarm", 3) in kinds
    assert any(e.text == "Caution: Unlocked" for e in messages)


def test_read_and_write_settings_with_names_and_units():
    script = [(b"$$\n", b"$10=1\r\n$110=3000.000\r\n$120=200.000\r\nok\r\n"), (b"$110=1500.000\n", b"ok\r\n")]
    with expected_protocol(script) as (stage, _):
        s = {x.number: x for x in stage.read_settings()}
        assert s[110].name == "X-axis maximum rate" and s[110].unit == "mm/min" and s[120].value == 200.0
        stage.write_setting(110, 1500.0)
        assert stage.settings[110] == 1500.0


def test_error_reply_raises_with_official_text_and_event():
    errors = []
    with expected_protocol([(b"$J=G91 G21 X900 F1000\n", b"error:15\r\n")]) as (stage, _):
        stage.events.subscribe(lambda e: e.kind == "error" and errors.append(e.code))
        with pytest.raises(GrblError, match=r"\$J=G91 G21 X900 F1000.*error:15 Travel exceeded: Jog target exceeds machine travel"):
            stage.jog(900.0, 1000.0)
    assert errors == [15]


def test_soft_limit_alarm_push_fails_the_move_and_status_is_not_queried():
    script = [(b"G90 G21 G1 X900 F600\n", b"ALARM:2\r\n[MSG:Reset to continue]\r\n")]
    with expected_protocol(script) as (stage, _):
        with pytest.raises(GrblError, match="ALARM:2 Soft limit"):
            stage.move_to(900.0, 600.0)
        assert stage.status().state == "Alarm"  # GRBL ignores '?' now: nothing is sent
        with pytest.raises(GrblError, match="ALARM:2"):
            stage.wait_idle(timeout_s=0.5)


def test_garbage_and_stray_lines_are_skipped():
    script = [(b"?", b"\x00\xff#junk\r\n<Idle|MPos:-500.000,0.000,0.000|FS:0,0>\r\n")]
    with expected_protocol(script) as (stage, _):
        assert stage.status().idle
        assert stage.garbage_lines == 1


def test_endless_noise_without_line_ends_is_dropped_not_hoarded():
    fake = ScriptedSerial([(b"\x18", b"\xaa" * 2000)])  # e.g. a wrong baud rate
    stage = GrblStage(fake, timeout_s=0.2)
    with pytest.raises(HardwareError, match="at 115200 baud"):
        stage.connect()
    assert stage.garbage_lines >= 1


def test_silent_controller_times_out_with_a_clear_message():
    # the overdue reply makes the driver ask '?' (a feed hold would explain it); silence again
    with expected_protocol([(b"G90 G21 G1 X1 F600\n", b""), (b"?", b"")], timeout_s=0.2) as (stage, _):
        with pytest.raises(HardwareError, match=r"no reply to 'G90 G21 G1 X1 F600' within 0.2 s"):
            stage.move_to(1.0, 600.0)
        stage.link.fail_pending(None)


def test_no_banner_means_wrong_port_or_baud():
    fake = ScriptedSerial([(b"\x18", b"")])
    stage = GrblStage(fake, timeout_s=0.2)
    with pytest.raises(HardwareError, match="no GRBL startup banner within 0.2 s"):
        stage.connect()
    assert not stage.connected


def test_character_counting_keeps_unanswered_bytes_within_rx_buffer():
    lines = [f"G1 X{i:02d}.000 F1000" for i in range(12)]  # 17 bytes each with \n: 7 fit in 127
    fake = ScriptedSerial(CONNECT + [(f"{ln}\n".encode(), b"") for ln in lines])
    stage = GrblStage(fake, timeout_s=30.0)  # a deadline the test never reaches: no '?' enters the script
    stage.connect()
    t = threading.Thread(target=stage.stream, args=(lines,))
    t.start()
    deadline = time.monotonic() + 10.0
    while len(fake.written) < len(CONNECT) + 7 and time.monotonic() < deadline:
        time.sleep(0.005)
    time.sleep(0.05)
    assert len(fake.written) == len(CONNECT) + 7  # 7 * 17 = 119 <= 127 < 8 * 17
    assert stage.link.rx_used == 7 * 17
    for _ in range(12):
        fake.push(b"ok\r\n")
        time.sleep(0.01)
    t.join(10.0)
    assert not t.is_alive() and stage.link.rx_used == 0 and not fake.pairs
    stage.link.close()


def test_vanished_port_fails_fast_and_reconnect_starts_over():
    fake = ScriptedSerial(CONNECT)
    stage = GrblStage(fake, timeout_s=30.0)
    events = []
    stage.events.subscribe(events.append)
    stage.connect()
    fake.fail()
    with pytest.raises(HardwareError, match="port vanished.*reconnect the stage and resume"):
        stage.status()  # the read error, long before the 30 s reply timeout could say "no status report"
    assert not stage.connected
    assert any(e.kind == "disconnected" for e in events)
    fake.broken = False
    fake.pairs = list(CONNECT)
    stage.connect()
    assert stage.connected and not fake.pairs
    stage.link.close()
    assert not fake.errors


def test_unopenable_port_is_a_clear_error():
    with pytest.raises(HardwareError, match="cannot open port '/dev/does-not-exist'"):
        GrblStage("/dev/does-not-exist").connect()


def test_soft_reset_after_alarm_2_waits_for_reset_to_continue():
    script = [(b"G90 G21 G1 X600 F600\n", b"ALARM:2\r\n"), (b"\x18", b"ok\r\n" + BANNER + b"[MSG:'$H'|'$X' to unlock]\r\n")]
    with expected_protocol(script, timeout_s=30.0) as (stage, fake):  # a deadline the test never reaches
        with pytest.raises(GrblError, match="ALARM:2"):
            stage.move_to(600.0, 600.0)
        resetting = threading.Thread(target=stage.soft_reset)
        resetting.start()
        resetting.join(0.3)
        assert resetting.is_alive() and fake.written[-1] != b"\x18"  # protocol.c would clear a reset sent now
        fake.push(b"[MSG:Reset to continue]\r\n")
        resetting.join(10.0)
        assert not resetting.is_alive() and fake.written[-1] == b"\x18"


def test_soft_reset_resends_once_when_reset_to_continue_never_came():
    script = [(b"G90 G21 G1 X600 F600\n", b"ALARM:2\r\n"), (b"\x18", b""), (b"\x18", b"ok\r\n" + BANNER)]
    with expected_protocol(script, timeout_s=0.2) as (stage, fake):
        with pytest.raises(GrblError, match="ALARM:2"):
            stage.move_to(600.0, 600.0)
        stage.soft_reset()  # no message within the timeout: a reset, no banner, one more reset
        assert fake.written[-2:] == [b"\x18", b"\x18"]
