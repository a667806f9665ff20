"""`lps capture` checks everything before it creates anything, and never starts on a locked stage silently."""
from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from lps_gui.cli import main as lps_main
from lps_gui.hardware.grbl.emulator import GrblEmulator
from lps_gui.hardware.sim_stage import SimulatedStage

SIM_PLAN = ["--start", "0", "--stop", "2", "--step", "2", "--settle", "0"]


def _last_error(capsys) -> str:
    return capsys.readouterr().err.strip().splitlines()[-1]


def test_a_stage_that_does_not_open_with_the_simulated_camera_is_refused_before_the_session_exists(tmp_path, capsys):
    out = tmp_path / "s"
    assert lps_main(["capture", "--out", str(out), "--stage", "nonsense:1", *SIM_PLAN]) == 2
    assert "not understood" in _last_error(capsys)
    assert lps_main(["capture", "--out", str(out), "--stage", "grbl:/dev/nonexistent-port", *SIM_PLAN]) != 0
    assert "/dev/nonexistent-port" in _last_error(capsys)
    assert not out.exists()
    assert lps_main(["capture", "--out", str(out), *SIM_PLAN]) == 0  # the retry is not "already holds a session"


def test_unusable_image_format_is_refused_before_the_session_exists(tmp_path, capsys):
    out = tmp_path / "s"
    assert lps_main(["capture", "--out", str(out), "--encode", ".nope", *SIM_PLAN]) == 2
    assert ".nope" in _last_error(capsys) and not out.exists()


@pytest.fixture
def locked_grbl(tmp_path):
    """Stock GRBL 1.1h with $22=1 on a pty (powers up in Alarm), a folder of frames and a board file."""
    frames = tmp_path / "frames"
    frames.mkdir()
    for i in range(2):
        cv2.imwrite(str(frames / f"f{i}.png"), np.full((24, 32), 10 * i, np.uint8))
    board = tmp_path / "board.json"
    board.write_text(json.dumps({"type": "chessboard", "inner_corners": [9, 6], "square_mm": 20}))
    with GrblEmulator(SimulatedStage(travel_mm=(-5.0, 50.0)), time_scale=50.0, homing_init_lock=True) as emu:
        argv = ["capture", "--stage", f"grbl:{emu.path}", "--camera", str(frames), "--board", str(board),
                "--targets", "0,1", "--settle", "0", "--feed", "3000"]
        yield emu, argv


def test_capture_on_a_grbl_in_power_up_alarm_asks_for_home_or_unlock(tmp_path, capsys, locked_grbl):
    emu, argv = locked_grbl
    out = tmp_path / "s"
    assert lps_main([*argv, "--out", str(out)]) == 2
    line = _last_error(capsys)
    assert "locked in Alarm" in line and "--home or --unlock" in line
    assert not out.exists() and emu.firmware.alarm_code == 0  # nothing created, nothing moved
    assert lps_main([*argv, "--out", str(out), "--unlock"]) == 0
    assert "unlocked it" in capsys.readouterr().err and not emu.stage.homed


def test_capture_with_home_homes_a_locked_grbl_first(tmp_path, capsys, locked_grbl):
    emu, argv = locked_grbl
    assert lps_main([*argv, "--out", str(tmp_path / "s"), "--home"]) == 0
    assert "homed it" in capsys.readouterr().err and emu.stage.homed


def test_the_simulated_camera_follows_a_grbl_stage_end_to_end(tmp_path, capsys):
    """`lps emulate-grbl` (here in-process) and `lps capture --stage grbl:PTY --camera sim`: no camera needed."""
    out = tmp_path / "s"
    with GrblEmulator(SimulatedStage(travel_mm=(-5.0, 50.0)), time_scale=50.0) as emu:
        assert lps_main(["capture", "--out", str(out), "--stage", f"grbl:{emu.path}", "--camera", "sim",
                         "--start", "0", "--stop", "4", "--step", "2", "--settle", "0", "--feed", "3000"]) == 0
    meta = json.loads((out / "session.json").read_text())
    assert meta["stage"]["spec"] == f"grbl:{emu.path}" and meta["camera"]["spec"] == "sim"
    records = [json.loads(line) for line in (out / "captures.jsonl").read_text().splitlines()]
    assert [r["target_mm"] for r in records] == [0, 2, 4]
    # the simulated rig goes where GRBL reported the carriage (sim/follow.py); its truth is that move through
    # the rig's own stage errors (micrometres), recorded beside each frame
    truth = meta["truth"]["axis_mm"]
    assert len(truth) == 3 and max(abs(t - r["reported_mm"]) for t, r in zip(truth, records)) < 0.01
    assert lps_main(["detect", str(out), "--workers", "1"]) == 0
