"""SIGKILL a live capture (`lps capture --live`) at random moments, resume each time: nothing differs at the end.

The kills land anywhere: mid-render, mid-write of an image or its line,
mid-append of a corners block, mid-estimate, in the final rewrite. After
the last resume corners.vnl holds the corners of an uninterrupted live run
(and is byte for byte what `lps detect` writes on the killed session), and
the results are the uninterrupted run's.
"""
from __future__ import annotations

import json
import os
import random
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from lps_gui.cli import main as lps_main
from lps_gui.io.corners.vnl import read_corners_vnl
from lps_gui.io.session import Session
from lps_gui.pipeline.detect import detect_session
from tests.capture.helpers import assert_listed_frames_intact, kill_when

ROOT = Path(__file__).resolve().parents[2]
PLAN = ["--preset", "small", "--seed", "3", "--stop", "28"]  # the small preset's first 15 of its 30 stops
STOPS = 15

CHILD = """
import sys
from lps_gui.capture import engine as eng
emit = eng.CaptureEngine._emit
def printing(self, event):
    emit(self, event)
    if event.kind == "frame":
        print(event.index, flush=True)
    elif event.kind == "done":  # the last frame is listed: the final corners and estimate follow
        print("end", flush=True)
eng.CaptureEngine._emit = printing
from lps_gui.cli import main
sys.exit(main(sys.argv[1:]))
"""


def run_killed(folder: Path, resume: bool, kill_at: int | None, delay_s: float) -> None:
    """One `lps capture --live` child, killed ``delay_s`` after it printed frame ``kill_at`` (None: after the
    capture's end, in the final corners, estimate or exit), or run to its end."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}
    cmd = [sys.executable, "-c", CHILD, "capture", *(["--resume", str(folder)] if resume else ["--out", str(folder), *PLAN]),
           "--live"]
    child = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)

    def reached(line: str) -> bool:
        word = line.strip()
        if (word == "end" and kill_at is None) or (word.isdigit() and kill_at is not None and int(word) >= kill_at):
            time.sleep(delay_s)
            return True
        return False

    try:
        kill_when(child, child.stdout, reached)
    except AssertionError:  # it finished before the kill: a kill after the end changes nothing either
        assert child.returncode == 0


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    folder = tmp_path_factory.mktemp("live") / "ref"
    assert lps_main(["capture", "--out", str(folder), *PLAN, "--live"]) == 0
    return folder


def kill_and_resume(folder: Path, kills: int, seed: int) -> None:
    """``kills`` kills spread over the capture (random frames, random delays after them), the last after its end."""
    rng = random.Random(seed)
    targets: list[int | None] = [*sorted(rng.randrange(STOPS) for _ in range(kills - 1)), None]
    for kill_at in targets:
        run_killed(folder, resume=(folder / "session.json").exists(), kill_at=kill_at,
                   delay_s=rng.uniform(0.0, 0.4 if kill_at is None else 0.08))
        if (folder / "session.json").exists():
            assert_listed_frames_intact(Session.open(folder))
    assert lps_main(["capture", "--resume", str(folder), "--live"]) == 0


def assert_same_as_uninterrupted(folder: Path, ref: Path) -> None:
    n = Session.open(ref).board().n_corners
    got, want = read_corners_vnl(folder / "corners.vnl", n), read_corners_vnl(ref / "corners.vnl", n)
    assert got.names == want.names and got.failed == want.failed
    np.testing.assert_array_equal(got.corners_px, want.corners_px)
    assert got.meta["detection"] == want.meta["detection"]
    data = (folder / "corners.vnl").read_bytes()
    (folder / "corners.vnl").unlink()
    detect_session(folder)
    assert (folder / "corners.vnl").read_bytes() == data  # as a separate `lps detect` writes it
    pos = [json.loads((f / "results.json").read_text())["positions"] for f in (folder, ref)]
    np.testing.assert_allclose([p["measured_mm"] for p in pos[0]], [p["measured_mm"] for p in pos[1]], rtol=1e-9, atol=0)


@pytest.mark.parametrize("kills", [pytest.param(3, id="3-kills"), pytest.param(20, id="20-kills", marks=pytest.mark.slow)])
def test_sigkill_live_capture_then_resume_equals_uninterrupted(tmp_path, uninterrupted, kills):
    folder = tmp_path / "killed"
    kill_and_resume(folder, kills, seed=28 + kills)
    assert_same_as_uninterrupted(folder, uninterrupted)
