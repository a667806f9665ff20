"""GRBL message parsing and formatting, G-code checks, and the code tables (against GRBL's docs)."""
from __future__ import annotations

import pytest

from lps_gui.hardware.grbl import codes
from lps_gui.hardware.grbl.gcode import CodeError, ParserState, check_block, clean_line
from lps_gui.hardware.grbl.protocol import (
    StatusReport,
    classify,
    format_status,
    jog_line,
    move_line,
    parse_build_info,
    parse_settings,
    parse_status,
)


def test_status_report_full_example_from_interface_md():
    r = parse_status("<Idle|MPos:0.000,0.000,0.000|FS:500,8000|Bf:15,128|WCO:0.000,1.551,5.664|Ov:100,100,100|Pn:XZ|A:SFM|Ln:99999>")
    assert r.state == "Idle" and r.substate is None
    assert r.mpos == (0.0, 0.0, 0.0) and r.wpos is None
    assert r.wco == (0.0, 1.551, 5.664)
    assert (r.feed, r.spindle) == (500.0, 8000.0)
    assert r.buffer == (15, 128) and r.overrides == (100, 100, 100)
    assert r.pins == "XZ" and r.accessories == "SFM" and r.line_number == 99999


def test_status_report_substates_wpos_and_plain_feed():
    r = parse_status("<Hold:1|WPos:-1.5,2.25,3.000|F:0>")
    assert (r.state, r.substate, r.wpos, r.feed, r.mpos) == ("Hold", 1, (-1.5, 2.25, 3.0), 0.0, None)
    assert parse_status("<Door:2|MPos:1,2,3|FS:0,0>").substate == 2


@pytest.mark.parametrize("bad", ["<Flying|MPos:0,0,0>", "<Idle|FS:0,0>", "Idle|MPos:0,0,0", "<Idle|MPos>"])
def test_malformed_status_reports_are_rejected(bad):
    with pytest.raises(ValueError):
        parse_status(bad)


def test_status_format_round_trip_in_report_c_field_order():
    r = StatusReport("Run", None, mpos=(1.0, 2.0, 3.0), buffer=(14, 120), feed=1500.0, spindle=0.0,
                     pins="X", wco=(0.0, 0.0, -1.0), overrides=(100, 100, 100))
    line = format_status(r)
    assert line == "<Run|MPos:1.000,2.000,3.000|Bf:14,120|FS:1500,0|Pn:X|WCO:0.000,0.000,-1.000|Ov:100,100,100>"
    assert parse_status(line) == r
    inch = format_status(StatusReport("Idle", mpos=(25.4, 0.0, 0.0), feed=254.0), inches=True)
    assert inch == "<Idle|MPos:1.0000,0.0000,0.0000|FS:10.0,0>"


@pytest.mark.parametrize(
    "line,kind,code,text",
    [
        ("ok", "ok", None, ""),
        ("error:15", "error", 15, ""),
        ("ALARM:2", "alarm", 2, ""),
        ("Grbl 1.1h ['$' for help]", "banner", None, "1.1h"),
        ("[MSG:'$H'|'$X' to unlock]", "msg", None, "'$H'|'$X' to unlock"),
        ("[MSG:Caution: Unlocked]", "msg", None, "Caution: Unlocked"),
        ("[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]", "feedback", None, "GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0"),
        ("[VER:1.1h.20190830:]", "feedback", None, "VER:1.1h.20190830:"),
        ("$110=3000.000", "setting", 110, "3000.000"),
        (">G54G20:ok", "startup", None, "G54G20:ok"),
        ("\x00\ufffd#garbage", "unknown", None, "\x00\ufffd#garbage"),
        ("error:", "unknown", None, "error:"),
    ],
)
def test_classify_every_message_kind(line, kind, code, text):
    m = classify(line)
    assert (m.kind, m.code, m.text) == (kind, code, text)


def test_build_info_from_source_and_doc_forms():
    b = parse_build_info(["[VER:1.1h.20190830:]", "[OPT:V,15,128]"])
    assert (b.version, b.build, b.user, b.options, b.planner_blocks, b.rx_buffer_bytes) == ("1.1h", "20190830", "", "V", 15, 128)
    doc = parse_build_info(["[VER:v1.1f.20170131:Some string]", "[OPT:VL,16,128]"])
    assert (doc.version, doc.user, doc.options, doc.planner_blocks) == ("v1.1f", "Some string", "VL", 16)
    with pytest.raises(ValueError):
        parse_build_info(["[OPT:V,15,128]"])


def test_settings_lines_and_formatting():
    assert parse_settings(["$0=10", "$11=0.010", "junk", "$130=200.000"]) == {0: 10.0, 11: 0.01, 130: 200.0}
    assert codes.format_setting(10, 3) == "$10=3" and codes.format_setting(110, 500) == "$110=500.000"


def test_command_lines():
    assert move_line(12.5, 600, "X") == "G90 G21 G1 X12.5 F600"
    assert jog_line(-0.25, 1000, "Y") == "$J=G91 G21 Y-0.25 F1000"


def test_code_tables_are_complete_and_texts_official():
    assert sorted(codes.ERRORS) == list(range(1, 18)) + list(range(20, 39))
    assert sorted(codes.ALARMS) == list(range(1, 11))
    assert codes.ERRORS[15].name == "Travel exceeded"
    assert codes.error_text(9) == "error:9 G-code lock: G-code commands are locked out during alarm or jog state."
    assert codes.alarm_text(1).startswith("ALARM:1 Hard limit: Hard limit has been triggered.")
    assert codes.error_text(99) == "error:99 (unknown GRBL error code)"
    expected = [0, 1, 2, 3, 4, 5, 6, 10, 11, 12, 13, 20, 21, 22, 23, 24, 25, 26, 27, 30, 31, 32,
                100, 101, 102, 110, 111, 112, 120, 121, 122, 130, 131, 132]
    assert sorted(codes.SETTINGS) == expected
    assert codes.SETTINGS[120].unit == "mm/sec^2" and codes.SETTINGS[23].unit == "mask"
    assert codes.setting_info(200).name == "$200"
    e = codes.GrblError("alarm", 2, "move")
    assert str(e).startswith("move: ALARM:2 Soft limit") and "unlock ($X)" in str(e)


def test_clean_line_like_protocol_c():
    assert clean_line("g1 x10 (comment) y2 ; rest")[0] == "G1X10Y2"
    assert clean_line("$J=G91 G21 X0.5 F1000")[0] == "$J=G91G21X0.5F1000"
    assert clean_line("G1 X" + "1" * 100)[1] is True


def _check(text: str, jog: bool = False):
    """A block checked against the power-up parser state (G0 G54 G17 G21 G90 G94, at machine 0)."""
    block = check_block(text, ParserState(), [[0.0, 0.0, 0.0] for _ in range(8)], jog=jog)
    if jog:
        block.check_jog()
    return block


@pytest.mark.parametrize(
    "text,jog,code",
    [  # gcode.c gc_execute_line(): the first check that fails names the error
        ("1X", False, 1), ("GX", False, 2), ("G2X1Y1R1", False, 22), ("G2X1Y1F100", False, 35),
        ("G2Z1F100", False, 32), ("G2X0Y0R1F100", False, 33), ("G2X10R1F100", False, 34),
        ("G0G1X1", False, 24), ("G17G18", False, 21), ("M5.5", False, 23), ("M3M5", False, 21),
        ("G10L20P1G0X1", False, 24), ("G1X1X2", False, 25), ("G4", False, 28), ("G1X1I2F1", False, 36),
        ("G80X1", False, 31), ("G59.1", False, 23), ("G10L20P7X0", False, 29), ("G10P1X0", False, 20),
        ("G10L2X0R1", False, 20), ("G10L20P1", False, 26), ("G92", False, 26), ("G53G2X1", False, 30),
        ("T256", False, 38), ("N10000001", False, 27), ("F-1", False, 4), ("M7", False, 20),
        ("X1", True, 22), ("G1X1F100", True, 16), ("M3X1F10", True, 16),
        ("X1F10S5", True, 36), ("A1", False, 20), ("G43X1", False, 20), ("G43.1X1", False, 37),
    ],
)
def test_gcode_errors_match_grbl(text, jog, code):
    with pytest.raises(CodeError) as e:
        _check(text, jog=jog)
    assert e.value.code == code


def test_gcode_accepts_what_a_stage_needs():
    b = _check("G90G21G1X10.5F600")
    assert (b.modal.distance, b.modal.units, b.modal.motion) == (90, 21, 1) and b.axis_words == {0: 10.5}
    assert b.xyz == [10.5, 0.0, 0.0] and b.f == 600.0
    j = _check("G91G21X-0.5F1000", jog=True)
    assert j.axis_words == {0: -0.5} and j.f == 1000.0 and j.xyz == [-0.5, 0.0, 0.0]
    assert _check("G4P0.01").p == 0.01
    assert _check("G4P0X441").xyz == [441.0, 0.0, 0.0]  # a dwell and a move in one block (G0 modal)
    assert _check("G10L20P0X0").coord_index == 0 and _check("G10L20X0").coord_index == 0  # P0 / no P: the active system


def test_offsets_and_the_active_work_system_are_parsed():
    from lps_gui.hardware.grbl.protocol import parse_offsets, parse_work_system

    lines = ["[G54:-500.000,0.000,0.000]", "[G55:1.500,-2.000,0.000]", "[G92:0.000,0.000,0.000]", "[TLO:0.000]",
             "[PRB:0.000,0.000,0.000:0]"]
    assert parse_offsets(lines) == {"G54": (-500.0, 0.0, 0.0), "G55": (1.5, -2.0, 0.0), "G92": (0.0, 0.0, 0.0)}
    assert parse_work_system(["[GC:G0 G57 G17 G21 G90 G94 M5 M9 T0 F0 S0]"]) == "G57"
    assert parse_work_system(["ok"]) is None
