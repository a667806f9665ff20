"""A point-level simulated session (one axis or an XY gantry): corners with known truth, no images.

Writes what a real capture plus detection would: session.json (with
``truth``), captures.jsonl, corners.vnl, board.json and intrinsics.json. The
embedded intrinsics are the true ones with a typical calibration's standard
deviations, so the total sigma has something to propagate.
"""
from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from lps_gui.core.geometry.camera_model import INTRINSIC_NAMES, CameraIntrinsics
from lps_gui.core.geometry.targets import target_offsets
from lps_gui.core.truth.simulate import SimulationSpec, frame_since_move_s, simulate_views
from lps_gui.io.board_file import write_board
from lps_gui.io.corners.target_vnl import TargetCornerTable, write_target_corners
from lps_gui.io.corners.vnl import CornerTable, write_corners_vnl
from lps_gui.io.intrinsics_file import write_intrinsics
from lps_gui.io.session import CaptureRecord, Session
from lps_gui.sim.session import write_simulated_session

# 1-sigma of a good 20-view calibration (relative for focal lengths)
TYPICAL_CALIBRATION_STD = {"fx": 3e-4, "fy": 3e-4, "cx": 0.3, "cy": 0.3, "k1": 1e-3, "k2": 4e-3, "p1": 5e-5, "p2": 5e-5, "k3": 8e-3}


def typical_std(intrinsics: CameraIntrinsics) -> np.ndarray:
    std = np.array([TYPICAL_CALIBRATION_STD[n] for n in INTRINSIC_NAMES])
    std[:2] *= np.array([intrinsics.fx, intrinsics.fy])
    return std


def calibrated_intrinsics(true: CameraIntrinsics) -> CameraIntrinsics:
    """The true intrinsics with a typical calibration's covariance: what a point session embeds."""
    return CameraIntrinsics(true.image_size, true.camera_matrix, true.dist, covariance=np.diag(typical_std(true) ** 2))


def simulate_point_session(spec: SimulationSpec, out: Path | str) -> Session:
    """Simulate ``spec`` at the corner level into a new session folder ``out``.

    On a gantry (SPEC 10) session.json has ``plan.axes`` and ``stage.axes``
    ["X", "Y"] and captures.jsonl [x, y] targets.
    """
    views = simulate_views(spec)
    if not spec.plan.planar:
        return write_point_session(out, spec, views.stops, views.corners_px, views.truth,
                                   {"driver": "simulated", "errors": spec.rig.errors.to_dict()})
    board = spec.rig.board
    truth = {**views.truth, "board": {"type": board.type, "inner_corners": [board.cols, board.rows],
                                      "square_mm": board.square_mm}}
    return write_point_session(out, spec, views.stops, views.corners_px, truth,
                               {"driver": "simulated", "axes": ["X", "Y"], "errors": spec.rig.errors.to_dict()})


def write_point_session(out: Path | str, spec: Any, stops: Sequence[Any], corners_px: np.ndarray,
                        truth: dict[str, Any], stage: dict[str, Any]) -> Session:
    """The files a capture plus detection would leave, for simulated corners of a line or a planar plan.

    session.json (through the one simulated-session writer, with ``truth``),
    captures.jsonl, corners.vnl, board.json and intrinsics.json: the true
    intrinsics with a typical calibration's covariance, so the total sigma
    has something to propagate.
    """
    out = Path(out)
    true = spec.rig.intrinsics
    intr = calibrated_intrinsics(true)
    truth = {**truth, "index": [s.index for s in stops]}
    session = write_simulated_session(
        out, spec, "points", intrinsics=intr,
        camera={"driver": "simulated (points)", "image_size": list(true.image_size)},
        stage=stage, truth=truth, noise_px=spec.noise_px,
    )
    layout = None if getattr(spec, "stitched", False) else getattr(spec, "layout", None)  # stitched: one board
    if layout is None:
        write_board(out / "board.json", spec.rig.board)
    write_intrinsics(out / "intrinsics.json", intr)
    names = [f"images/{s.index:06d}.png" for s in stops]
    now = time.time()
    for stop, name in zip(stops, names):
        session.append(CaptureRecord(stop.index, stop.run, stop.direction, stop.target_mm, stop.target_mm, name, None,
                                     now, stop.frame, since_move_s=frame_since_move_s(spec, stop.frame),
                                     segment=stop.segment))
    meta = {"source": "simulated points"}
    if layout is None:
        write_corners_vnl(session.corners_path, CornerTable(names, corners_px, meta=meta))
    else:  # SPEC 13: one row per corner of each target seen
        targets = list(layout.targets)
        write_target_corners(session.corners_path, TargetCornerTable(names, [t.id for t in targets],
                                                                     target_offsets(targets), corners_px, meta=meta))
    return session
