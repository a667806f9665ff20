"""Nothing is lost: SIGKILL a capture process mid-run, resume with `lps capture --resume`, compare."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from lps_gui.cli import main as lps_main
from lps_gui.io.session import Session
from tests.capture.helpers import assert_listed_frames_intact, image_bytes, kill_when, records_without_time

ROOT = Path(__file__).resolve().parents[2]

CHILD = """
import sys
from tests.capture.helpers import start_capture
session, stage, camera, engine = start_capture(sys.argv[1])
engine.subscribe(lambda e: print(e.index, flush=True) if e.kind == "frame" else None)
engine.run()
"""


def test_sigkill_mid_run_then_resume_equals_uninterrupted(tmp_path, reference_capture):
    folder = tmp_path / "killed"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(folder)], cwd=ROOT, env=env, stdout=subprocess.PIPE, text=True)
    kill_when(child, child.stdout, lambda line: int(line) >= 30)
    killed = Session.open(folder)
    listed = len(killed.records())
    assert 30 < listed + 1 < 80, listed
    assert_listed_frames_intact(killed)

    assert lps_main(["capture", "--resume", str(folder)]) == 0

    resumed = Session.open(folder)
    assert_listed_frames_intact(resumed)
    ref = reference_capture[0]
    assert records_without_time(resumed) == records_without_time(ref)
    assert image_bytes(resumed) == image_bytes(ref)
    assert resumed.truth["axis_mm"] == Session.open(ref.folder).truth["axis_mm"]
    sidecar = [json.loads(line)["index"] for line in (folder / "truth.jsonl").read_text().splitlines()]
    assert sidecar == list(range(80))  # one truth line per listed frame, none twice
