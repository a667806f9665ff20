"""`lps capture` with the SDK cameras (--camera genicam:/pylon:, --cti) and the settle / averaging switches."""
from __future__ import annotations

import json

import pytest

from lps_gui.camera.genicam_camera import GENTL_ENV, demo_producer
from lps_gui.cli import main as lps_main
from lps_gui.io.session import Session

BOARD = {"type": "chessboard", "inner_corners": [9, 6], "square_mm": 20}


def test_a_capture_through_the_genicam_demo_producer_records_the_locked_controls(tmp_path):
    (tmp_path / "b.json").write_text(json.dumps(BOARD))
    out = tmp_path / "s"
    argv = ["capture", "--out", str(out), "--stage", "sim", "--camera", "genicam:2", "--cti", demo_producer(),
            "--board", str(tmp_path / "b.json"), "--targets", "0,1,2", "--settle", "0"]
    assert lps_main(argv) == 0
    session = Session.open(out)
    cam = session.meta["camera"]
    assert cam["driver"] == "GenICamCamera" and cam["spec"] == "genicam:2" and cam["cti"] == demo_producer()
    assert cam["controls_locked"] == {"pixel format": "RGBa8", "frame rate": 20.0}
    assert [r.index for r in session.records()] == [0, 1, 2]
    assert all("settle_s" not in line for line in (out / "captures.jsonl").read_text().splitlines())


def test_no_producer_is_one_line_before_anything_is_created(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv(GENTL_ENV, raising=False)
    (tmp_path / "b.json").write_text(json.dumps(BOARD))
    argv = ["capture", "--out", str(tmp_path / "s"), "--stage", "sim", "--camera", "genicam:0",
            "--board", str(tmp_path / "b.json"), "--targets", "0,1"]
    assert lps_main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == ("lps capture: error: camera genicam:0: no GenTL producer; give --cti PATH (the vendor's .cti file) "
                       "or set GENICAM_GENTL64_PATH")
    assert not (tmp_path / "s" / "session.json").exists()


def test_settle_and_averaging_switches_reach_the_session(tmp_path):
    out = tmp_path / "s"
    argv = ["capture", "--out", str(out), "--start", "0", "--stop", "4", "--step", "2", "--settle", "0",
            "--settle-px", "0.05", "--settle-timeout-s", "2", "--average-frames", "2"]
    assert lps_main(argv) == 0
    session = Session.open(out)
    assert session.meta["acquisition"] == {"average_frames": 2, "settle_px": 0.05, "settle_timeout_s": 2.0, "settle_frames": 3}
    assert all(r.settle_s is not None for r in session.records())


@pytest.mark.parametrize("switch,value", [("--settle-px", "-1"), ("--average-frames", "0"), ("--settle-frames", "1")])
def test_bad_settle_switches_are_one_line(tmp_path, capsys, switch, value):
    argv = ["capture", "--out", str(tmp_path / "s"), "--start", "0", "--stop", "2", "--step", "2", switch, value]
    with pytest.raises(SystemExit) as exc:  # refused by argparse (cli/option_types)
        lps_main(argv)
    assert exc.value.code == 2
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert line.startswith("lps capture: error:") and switch in line  # refused while the command line is parsed
    assert not (tmp_path / "s").exists()
