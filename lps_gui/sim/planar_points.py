"""A point-level simulated planar (XY) session: corners with known truth, no images.

The planar counterpart of :mod:`lps_gui.sim.points`, through the same session
writer: session.json (``plan.axes`` and ``stage.axes`` ["X", "Y"], SPEC 10,
and the truth), captures.jsonl with [x, y] targets, corners.vnl, board.json,
intrinsics.json.
"""
from __future__ import annotations

from pathlib import Path

from lps_gui.core.planar_simulate import PlanarSimulationSpec, simulate_planar_views
from lps_gui.io.session import Session
from lps_gui.sim.points import write_point_session


def simulate_planar_point_session(spec: PlanarSimulationSpec, out: Path | str) -> Session:
    """Simulate ``spec`` at the corner level into a new session folder ``out``."""
    views = simulate_planar_views(spec)
    board = spec.rig.board
    truth = {**views.truth, "board": {"type": board.type, "inner_corners": [board.cols, board.rows],
                                      "square_mm": board.square_mm}}
    return write_point_session(out, spec, views.stops, views.corners_px, truth,
                               {"driver": "simulated", "axes": ["X", "Y"], "errors": spec.rig.errors.to_dict()})
