"""Helpers for capture tests: start a simulated capture, compare sessions, check listed files."""
from __future__ import annotations

import signal
import subprocess
from dataclasses import asdict, replace
from pathlib import Path
from typing import Callable, Iterable

import cv2
import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.planning.plan import Plan
from lps_gui.io.atomic import sha256_file
from lps_gui.io.session import Session
from lps_gui.sim.rig import spec_for_plan
from lps_gui.sim.session import create_simulated_session, simulated_engine

PLAN20 = Plan(start_mm=0.0, stop_mm=38.0, step_mm=2.0, directions="both", runs=2, overshoot_mm=1.0, settle_s=0.1, feed_mm_min=1200.0)
SEED = 7


def tiny_spec(plan: Plan = PLAN20, seed: int = SEED):
    """The "small" preset at half resolution (320x240): a quarter of the rendering time for engine tests."""
    spec = spec_for_plan("small", plan, seed=seed)
    k = spec.rig.intrinsics
    m = k.camera_matrix
    half = CameraIntrinsics.from_values((320, 240), m[0, 0] / 2, m[1, 1] / 2, m[0, 2] / 2, m[1, 2] / 2, dist=tuple(k.dist))
    return replace(spec, rig=replace(spec.rig, intrinsics=half))


def start_capture(folder, plan: Plan = PLAN20, seed: int = SEED, full_size: bool = False, **kwargs):
    """A fresh simulated session, its connected rig and its engine (320x240 unless ``full_size``)."""
    spec = spec_for_plan("small", plan, seed=seed) if full_size else tiny_spec(plan, seed)
    session, stage, camera = create_simulated_session(folder, spec, **kwargs)
    stage.connect()
    return session, stage, camera, simulated_engine(session, stage, camera)


def records_without_time(session: Session) -> list[dict]:
    out = []
    for r in session.records():
        d = asdict(r)
        d.pop("time")
        d.pop("since_move_s")  # a time too: through the emulator's real-time clock it differs run to run
        out.append(d)
    return out


def image_bytes(session: Session) -> dict[int, bytes]:
    return {r.index: (session.folder / r.file).read_bytes() for r in session.records()}


def assert_listed_frames_intact(session: Session) -> None:
    """Every listed frame exists with its sha256 and no index or file is listed twice."""
    records = session.records()
    indices = [r.index for r in records]
    assert len(indices) == len(set(indices)), "a capture index is listed twice"
    assert len({r.file for r in records}) == len(records), "a file is listed twice"
    for r in records:
        path = session.folder / r.file
        assert path.is_file(), f"{r.file} is listed but missing"
        assert sha256_file(path) == r.sha256, f"{r.file} does not match its sha256"


def replay_frames(tmp_path: Path, n: int = 3) -> tuple[Path, Path]:
    """``n`` small grey frames for the folder-replay camera and a board.json: the non-simulated capture path."""
    frames = tmp_path / "frames"
    frames.mkdir()
    for i in range(n):
        cv2.imwrite(str(frames / f"f{i}.png"), np.full((24, 32), 10 * i, np.uint8))
    board = tmp_path / "board.json"
    board.write_text('{"type": "chessboard", "inner_corners": [9, 6], "square_mm": 20}')
    return frames, board


def kill_when(child: subprocess.Popen, lines: Iterable[str], reached: Callable[[str], bool]) -> None:
    """SIGKILL ``child`` at the first of its output ``lines`` that ``reached``; blocks on the output, never sleeps."""
    try:
        for line in lines:
            if reached(line):
                child.send_signal(signal.SIGKILL)  # mid-run: the child is already writing the next frames
                break
    finally:
        child.kill()
        child.wait(timeout=60)
    assert child.returncode == -signal.SIGKILL


def capture_through_emulator(folder: Path, spec, time_scale: float):
    """A simulated session captured through the GRBL driver and emulator serving the rig's stage: (session, summary)."""
    from lps_gui.sim.emulated import emulated_rig_stage

    session, rig_stage, camera = create_simulated_session(folder, spec)
    stage = emulated_rig_stage(rig_stage, time_scale=time_scale)
    try:
        summary = simulated_engine(session, stage, camera).run()
    finally:
        stage.disconnect()
    assert summary.state == "done", summary.error
    return session, summary
