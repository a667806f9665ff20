"""A point-level simulated planar (XY) session: corners with known truth, no images.

The planar counterpart of :mod:`lps_gui.sim.points`, through the same session
writer: session.json (``plan.axes`` and ``stage.axes`` ["X", "Y"], SPEC 10,
and the truth), captures.jsonl with [x, y] targets, corners.vnl, board.json,
intrinsics.json.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from lps_gui.core.planar_simulate import PlanarSimulationSpec, simulate_planar_views
from lps_gui.io.board_file import write_board
from lps_gui.io.corners_vnl import CornerTable, write_corners_vnl
from lps_gui.io.intrinsics_file import write_intrinsics
from lps_gui.io.session import CaptureRecord, Session
from lps_gui.sim.points import calibrated_intrinsics
from lps_gui.sim.session import write_simulated_session


def simulate_planar_point_session(spec: PlanarSimulationSpec, out: Path | str) -> Session:
    """Simulate ``spec`` at the corner level into a new session folder ``out``."""
    out = Path(out)
    views = simulate_planar_views(spec)
    true = spec.rig.intrinsics
    intr = calibrated_intrinsics(true)
    truth = dict(views.truth)
    truth["index"] = [s.index for s in views.stops]
    truth["board"] = {"type": spec.rig.board.type, "inner_corners": [spec.rig.board.cols, spec.rig.board.rows],
                      "square_mm": spec.rig.board.square_mm}
    session = write_simulated_session(
        out, spec, "points", intrinsics=intr,
        camera={"driver": "simulated (points)", "image_size": list(true.image_size)},
        stage={"driver": "simulated", "axes": ["X", "Y"], "errors": spec.rig.errors.to_dict()},
        truth=truth, noise_px=spec.noise_px,
    )
    write_board(out / "board.json", spec.rig.board)
    write_intrinsics(out / "intrinsics.json", intr)
    names = [f"images/{s.index:06d}.png" for s in views.stops]
    now = time.time()
    for stop, name in zip(views.stops, names):
        session.append(CaptureRecord(stop.index, stop.run, stop.direction, stop.target_mm, stop.target_mm, name, None,
                                     now, stop.frame))
    write_corners_vnl(session.corners_path, CornerTable(names, views.corners_px, meta={"source": "simulated planar points"}))
    return session
