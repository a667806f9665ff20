"""A capture on a simulated stage that rings after each move, and its position errors against the resting truth."""
from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from lps_gui.camera.detection import detect_chessboard
from lps_gui.capture.engine import CaptureEngine
from lps_gui.capture.settle import SettleOptions
from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.stage_errors import TruePose
from lps_gui.hardware.sim_stage import Vibration
from lps_gui.sim.session import create_simulated_session
from tests.capture.helpers import tiny_spec

VIB_PLAN = Plan(start_mm=0.0, stop_mm=32.0, step_mm=8.0, directions="+", runs=1, overshoot_mm=1.0, settle_s=0.0,
                feed_mm_min=1200.0)
RINGING = Vibration(amplitude_um=150.0, frequency_hz=8.0, decay_s=0.25)
FRAME_S = 0.04  # the simulated camera's frame time (25 fps): settle grabs advance the simulated clock


def vibrating_capture(folder, settle: SettleOptions | None, plan: Plan = VIB_PLAN, seed: int = 3):
    """Capture ``plan`` on the ringing stage; (session, spec, resting truth per capture index)."""
    spec = tiny_spec(plan, seed)
    session, stage, camera = create_simulated_session(folder, spec, vibration=RINGING, exposure_s=FRAME_S, noise_grey=1.0)
    stage.connect()
    engine = CaptureEngine(stage, camera, session, settle=settle)
    resting: dict[int, TruePose] = {}
    engine.subscribe(lambda e: resting.__setitem__(e.index, stage.resting_pose()) if e.kind == "frame" else None)
    summary = engine.run()
    assert summary.state == "done", summary.error
    return session, spec, resting


def position_errors_mm(session, spec, resting) -> np.ndarray:
    """Per frame: the board's displacement in the image from where the resting carriage shows it, in mm of travel."""
    rig, board = spec.rig, spec.rig.board
    pts = board.flat_points()
    out = []
    for r in session.records():
        image = cv2.imread(str(session.folder / r.file), cv2.IMREAD_GRAYSCALE)
        found = detect_chessboard(image, board)
        assert found is not None, f"board not found in {r.file}"
        pose = resting[r.index]
        shifted = replace(pose, axis_mm=pose.axis_mm + 0.01)
        at_rest = project_board(*[a[0] for a in rig.camera_poses(pose)], pts, rig.intrinsics)
        moved = project_board(*[a[0] for a in rig.camera_poses(shifted)], pts, rig.intrinsics)
        per_mm = np.mean(moved - at_rest, axis=0) / 0.01  # px per mm of travel in the image
        residual = np.mean(found - at_rest, axis=0)
        out.append(float(residual @ per_mm / (per_mm @ per_mm)))
    return np.array(out)
