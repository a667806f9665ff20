"""`lps capture`: simulated rig, a real-camera path (stage sim + folder replay), errors, and SIGKILL + --resume."""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from lps_gui.cli import main as lps_main
from lps_gui.io.atomic import sha256_file
from lps_gui.io.session import Session
from tests.capture.helpers import kill_when, replay_frames

ROOT = Path(__file__).resolve().parents[2]
LPS = [str(Path(sys.executable).with_name("lps"))] if Path(sys.executable).with_name("lps").exists() else [
    sys.executable, "-c", "import sys; from lps_gui.cli import main; sys.exit(main())"
]
PLAN_ARGS = ["--start", "0", "--stop", "18", "--step", "2", "--directions", "both", "--settle", "0.05", "--feed", "1200", "--seed", "3"]


def _records(folder):
    return [{k: v for k, v in json.loads(line).items() if k != "time"} for line in (Path(folder) / "captures.jsonl").read_text().splitlines()]


def _images(folder):
    s = Session.open(folder)
    return {r.index: (s.folder / r.file).read_bytes() for r in s.records()}


def test_help_lists_the_switches(capsys):
    with pytest.raises(SystemExit) as exc:
        lps_main(["capture", "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    for switch in ("--stage", "--camera", "--plan", "--resume", "--preset", "--overshoot", "--settle"):
        assert switch in out


def test_simulated_capture_records_the_setup_and_truth(tmp_path):
    out = tmp_path / "s"
    assert lps_main(["capture", "--out", str(out), "--start", "0", "--stop", "4", "--step", "2", "--directions", "both", "--settle", "0"]) == 0
    session = Session.open(out)
    assert len(session.records()) == 6 and session.remaining_stops() == []
    meta = session.meta
    assert meta["camera"]["driver"] == "RigCamera" or "Simulated" in meta["camera"]["driver"]
    assert meta["stage"]["driver"] == "RigStage" and meta["stage"]["errors"] == meta["truth"]["stage_errors"]
    assert meta["plan"]["directions"] == "both" and meta["board"]["inner_corners"] == [9, 6]
    assert meta["intrinsics"]["image_size"] == [640, 480]
    assert meta["truth"]["simulated"] and len(meta["truth"]["axis_mm"]) == 6


def test_plan_file_and_switch_override(tmp_path):
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps({"targets_mm": [0, 3, 5], "settle_s": 0.0, "runs": 1}))
    out = tmp_path / "s"
    assert lps_main(["capture", "--out", str(out), "--plan", str(plan), "--runs", "2"]) == 0
    targets = [r["target_mm"] for r in _records(out)]
    assert targets == [0, 3, 5, 0, 3, 5]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["capture"], "either --out SESSION"),
        (["capture", "--out", "X", "--resume", "Y"], "either --out SESSION"),
        (["capture", "--out", "{tmp}/s", "--board", "b.json", "--start", "0", "--stop", "2", "--step", "1"], "drop --board"),
        (["capture", "--out", "{tmp}/s", "--camera", "{tmp}", "--board", "{tmp}/b.json"], "no plan"),
        (["capture", "--out", "{tmp}/s", "--stage", "grbl", "--start", "0", "--stop", "2", "--step", "1"], "not understood"),
        (["capture", "--out", "{tmp}/s", "--stage", "grbl:/dev/nonexistent-port", "--start", "0", "--stop", "2", "--step", "1"], "cannot open port"),
        (["capture", "--resume", "{tmp}/missing"], "not found"),
    ],
)
def test_bad_input_is_one_clear_line(tmp_path, capsys, argv, message):
    (tmp_path / "b.json").write_text(json.dumps({"type": "chessboard", "inner_corners": [9, 6], "square_mm": 20}))
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert lps_main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert message in err[-1] and err[-1].startswith("lps capture: error:")


def test_existing_session_is_never_overwritten(tmp_path, capsys):
    out = tmp_path / "s"
    args = ["capture", "--out", str(out), "--start", "0", "--stop", "2", "--step", "2", "--settle", "0"]
    assert lps_main(args) == 0
    before = sha256_file(out / "captures.jsonl")
    assert lps_main(args) == 2
    assert "use --resume" in capsys.readouterr().err
    assert sha256_file(out / "captures.jsonl") == before


def test_real_camera_path_pauses_when_images_run_out_and_resumes(tmp_path, capsys):
    """Stage "sim" + a folder-replay camera: the non-simulated code path, resumed with the devices named again."""
    frames, board = replay_frames(tmp_path)
    out = tmp_path / "s"
    args = ["capture", "--out", str(out), "--stage", "sim", "--camera", str(frames), "--board", str(board), "--targets", "0,1,2,3", "--settle", "0"]
    assert lps_main(args) == 3
    err = capsys.readouterr().err
    assert "all 3 images replayed" in err and f"lps capture --resume {out}" in err
    assert len(_records(out)) == 3
    meta = Session.open(out).meta
    assert meta["camera"]["spec"] == str(frames) and meta["stage"]["spec"] == "sim" and "truth" not in meta
    cv2.imwrite(str(frames / "f3.png"), np.full((24, 32), 30, np.uint8))
    assert lps_main(["capture", "--resume", str(out)]) == 2  # devices from session.json are never opened by themselves
    err = capsys.readouterr().err
    assert "give --stage and --camera" in err and f"--camera {frames}" in err and len(err.strip().splitlines()) == 1
    assert lps_main(["capture", "--resume", str(out), "--stage", "sim", "--camera", str(frames)]) == 0
    records = _records(out)
    assert [r["index"] for r in records] == [0, 1, 2, 3]
    assert [r["reported_mm"] for r in records] == [0.0, 1.0, 2.0, 3.0]


def test_sigkill_of_lps_capture_then_resume_equals_uninterrupted(tmp_path):
    ref = tmp_path / "ref"
    assert lps_main(["capture", "--out", str(ref), *PLAN_ARGS]) == 0
    out = tmp_path / "killed"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [*LPS, "capture", "--out", str(out), *PLAN_ARGS]
    child = subprocess.Popen(cmd, cwd=ROOT, env=env, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
    # the progress bar writes a line per 10 % when not on a terminal
    kill_when(child, child.stderr, lambda line: (m := re.search(r"\] (\d+)/(\d+)", line)) is not None
              and int(m.group(1)) >= 4)
    assert 4 <= len(_records(out)) < 20
    resumed = subprocess.run([*LPS, "capture", "--resume", str(out)], cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    assert resumed.returncode == 0, resumed.stderr
    assert _records(out) == _records(ref)
    assert _images(out) == _images(ref)
    session = Session.open(out)
    for r in session.records():
        assert sha256_file(session.folder / r.file) == r.sha256
    assert session.truth["axis_mm"] == Session.open(ref).truth["axis_mm"]


def test_guided_intrinsics_mode_on_the_simulated_hand_held_board(tmp_path, capsys):
    out = tmp_path / "intr"
    assert lps_main(["capture", "--intrinsics-views", "6", "--out", str(out)]) == 0
    lines = [json.loads(line) for line in (out / "intrinsics_captures.jsonl").read_text().splitlines()]
    assert len(lines) == 6 and all(d["ok"] for d in lines)
    assert all(sha256_file(out / d["file"]) == d["sha256"] for d in lines)
    assert json.loads((out / "board.json").read_text())["inner_corners"] == [9, 6]
    assert f"lps intrinsics {out}" in capsys.readouterr().out


def test_guided_intrinsics_mode_with_a_real_camera_takes_skips_and_quits(tmp_path, capsys, monkeypatch):
    import io

    sim = tmp_path / "sim"
    assert lps_main(["capture", "--intrinsics-views", "6", "--out", str(sim)]) == 0
    frames = tmp_path / "frames"
    frames.mkdir()
    for p in sorted(sim.glob("intr_*.png")):
        (frames / p.name).write_bytes(p.read_bytes())
    out = tmp_path / "real"
    monkeypatch.setattr(sys, "stdin", io.StringIO("\n\ns\nq\n"))
    args = ["capture", "--intrinsics-views", "6", "--camera", str(frames), "--board", str(sim / "board.json"), "--out", str(out)]
    assert lps_main(args) == 3
    lines = [json.loads(line) for line in (out / "intrinsics_captures.jsonl").read_text().splitlines()]
    assert [bool(d["file"]) for d in lines] == [True, True, False]
    assert "run the same command again" in capsys.readouterr().err
