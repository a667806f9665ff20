"""`lps capture --planar`: plans from the switches, errors before anything is made, the GRBL emulator,
and a SIGKILLed capture process resumed with `lps capture --resume` equal to an uninterrupted run."""
from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from lps_gui.cli import main as lps_main
from lps_gui.cli.capture import command as capture_cli
from lps_gui.cli.capture.plan import build_planar_plan
from lps_gui.io.session import Session
from tests.capture.helpers import (
    assert_listed_frames_intact,
    image_bytes,
    kill_when,
    records_without_time,
    replay_frames,
)

ROOT = Path(__file__).resolve().parents[2]
GRID = ["--planar", "--grid", "0,0:40,20:10,10", "--directions", "both", "--settle", "0.05", "--feed", "3000",
        "--seed", "5"]


def parse(argv: list[str]) -> argparse.Namespace:
    p = argparse.ArgumentParser()
    capture_cli.add_arguments(p)
    return p.parse_args(argv)


def test_grid_switches_make_the_planar_plan():
    plan = build_planar_plan(parse(["--grid", "0,0:40,20:10,10", "--pattern", "raster", "--runs", "2",
                                    "--directions", "both", "--overshoot", "2"]))
    assert plan.planar and plan.pattern == "raster" and plan.runs == 2 and plan.overshoot_mm == 2
    t = plan.targets()
    assert t.shape == (15, 2) and tuple(t[5]) == (0.0, 10.0)  # raster: each row starts at X0
    assert plan.n_frames() == 60


def test_targets_xy_are_visited_as_listed():
    plan = build_planar_plan(parse(["--targets-xy", "0,0; 20,0; 20,10;0,10"]))
    assert plan.targets().tolist() == [[0, 0], [20, 0], [20, 10], [0, 10]]


def test_iso_lines_preset_runs_lines_along_each_axis_both_ways_five_times():
    plan = build_planar_plan(parse(["--iso-lines", "--grid", "0,0:40,20:10,10"]))
    t = plan.targets()
    along_x = t[:15].reshape(3, 5, 2)  # 5 X targets at Y 0, 10, 20
    assert np.all(along_x[..., 1] == np.array([[0.0], [10.0], [20.0]]))
    along_y = t[15:].reshape(3, 3, 2)  # 3 Y targets at X 0, 20, 40
    assert np.all(along_y[..., 0] == np.array([[0.0], [20.0], [40.0]]))
    assert plan.directions == "both" and plan.runs == 5 and plan.n_frames() == 24 * 2 * 5


@pytest.mark.parametrize("argv, message", [
    (["--grid", "0,0:40"], "X0,Y0:X1,Y1:DX,DY"),
    (["--targets-xy", "1,2;3"], "is not X,Y"),
    (["--planar", "--start", "0"], "takes --grid"),
    (["--planar", "--targets", "0,1,2"], "--targets-xy"),
    (["--grid", "0,0:4,4:2,2", "--targets-xy", "0,0;1,0;1,1"], "either --grid or --targets-xy"),
    (["--planar", "--preset", "paper-rig"], "presets paper-planar, small-planar"),
    (["--grid", "0,0:40,20:0,10"], "must be positive"),
    (["--planar", "--runs", "0"], "at least 1"),
    (["--grid", "0,0:400,20:10,10"], "board leaves the simulated camera's view"),
    (["--planar", "--board", "b.json"], "drop --board"),
    (["--planar", "--stage", "grbl:/dev/nonexistent"], "rides only --stage sim or emulator"),
])
def test_bad_planar_input_is_one_line_and_creates_nothing(tmp_path, capsys, argv, message):
    out = tmp_path / "s"
    assert lps_main(["capture", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1, err
    assert not out.exists()


def test_planar_capture_through_the_grbl_emulator(tmp_path):
    out = tmp_path / "emu"
    assert lps_main(["capture", "--targets-xy", "0,0;10,0;10,10;0,10", "--stage", "emulator", "--time-scale", "20",
                     "--settle", "0.05", "--feed", "6000", "--out", str(out)]) == 0
    session = Session.open(out)
    assert session.planar and session.meta["stage"]["spec"] == "emulator"
    recs = session.records()
    assert [r.target_mm for r in recs] == [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)]
    for r in recs:
        assert np.allclose(r.reported_mm, r.target_mm, atol=1e-3)
    assert len(session.truth["plane_mm"]) == 4


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    folder = tmp_path_factory.mktemp("planar-cli") / "ref"
    assert lps_main(["capture", *GRID, "--out", str(folder)]) == 0
    return Session.open(folder)


def test_resume_keeps_the_session_plan(reference, capsys):
    assert lps_main(["capture", "--resume", str(reference.folder), "--grid", "0,0:10,10:5,5"]) == 2
    assert "keeps its own plan" in capsys.readouterr().err


def test_sigkill_mid_run_then_resume_equals_uninterrupted(tmp_path, reference):
    folder = tmp_path / "killed"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-c", "import sys; from lps_gui.cli import main; sys.exit(main())",
           "capture", *GRID, "--out", str(folder)]
    child = subprocess.Popen(cmd, cwd=ROOT, env=env, stderr=subprocess.PIPE, text=True)
    # the progress bar: a line per 10 % on a pipe
    kill_when(child, child.stderr, lambda line: (m := re.search(r"\] (\d+)/30", line)) is not None
              and int(m.group(1)) >= 12)
    killed = Session.open(folder)
    assert 12 <= len(killed.records()) < 30
    assert_listed_frames_intact(killed)

    assert lps_main(["capture", "--resume", str(folder)]) == 0

    resumed = Session.open(folder)
    assert_listed_frames_intact(resumed)
    assert records_without_time(resumed) == records_without_time(reference)
    assert image_bytes(resumed) == image_bytes(reference)
    assert resumed.truth["plane_mm"] == reference.truth["plane_mm"]
    assert resumed.truth["board_plane_mm"] == reference.truth["board_plane_mm"]


def test_planar_plan_on_real_devices_moves_both_axes_and_resumes_from_the_session(tmp_path, capsys):
    """Stage "sim" + a folder-replay camera: the non-simulated planar path, X and Y moves, resumed on named devices."""
    import cv2

    frames, board = replay_frames(tmp_path)
    out = tmp_path / "s"
    assert lps_main(["capture", "--targets-xy", "0,0;5,0;5,5;0,5", "--stage", "sim", "--camera", str(frames),
                     "--board", str(board), "--settle", "0", "--out", str(out)]) == 3  # the replay runs out
    assert "lps capture --resume" in capsys.readouterr().err
    session = Session.open(out)
    assert session.planar and session.meta["stage"]["axes"] == ["X", "Y"] and "truth" not in session.meta
    recs = session.records()
    assert [r.target_mm for r in recs] == [(0.0, 0.0), (5.0, 0.0), (5.0, 5.0)]
    assert all(np.allclose(r.reported_mm, r.target_mm, atol=1e-6) for r in recs)
    cv2.imwrite(str(frames / "f3.png"), np.full((24, 32), 40, np.uint8))
    # a resume opens only the devices the operator names (issue 17), never those session.json recorded
    assert lps_main(["capture", "--resume", str(out), "--stage", "sim", "--camera", str(frames)]) == 0
    assert [r.target_mm for r in Session.open(out).records()][-1] == (0.0, 5.0)


def test_a_planar_plan_file_makes_a_planar_capture(tmp_path):
    plan = tmp_path / "plan.json"
    plan.write_text('{"axes": ["X", "Y"], "targets_mm": [[0, 0], [10, 0], [10, 10]], "settle_s": 0, "feed_mm_min": 3000}')
    out = tmp_path / "s"
    assert lps_main(["capture", "--plan", str(plan), "--out", str(out)]) == 0
    assert [r.target_mm for r in Session.open(out).records()] == [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0)]
