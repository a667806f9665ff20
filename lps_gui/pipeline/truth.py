"""Ground truth of a simulated session, wherever the simulator put it.

The point and image simulators store per-capture truth in session.json
(``truth.axis_mm`` etc., in capture-index order); the capture engine on a
simulated rig appends one line per frame to ``truth.jsonl`` because the
truth is only known as the stage moves. Both become the same arrays here.
"""
from __future__ import annotations

import json
from typing import Any

import numpy as np

from lps_gui.io.session import Session

TRUTH_SIDECAR = "truth.jsonl"


def session_truth(session: Session) -> dict[str, Any] | None:
    """Arrays index (K,), axis_mm (K,), straightness_um (K, 2), angles_urad (K, 3), or None.

    With the rig's geometry recorded, also ``plane_mm`` (K,): the positions a
    constant-orientation model sees (see core.simulate.board_plane_positions),
    ``plane_straightness_um`` (K, 2) and ``image_rotation_urad`` (K,) (see
    core.simulate.board_plane_straightness).
    """
    out = _per_capture_truth(session)
    if out is not None:
        plane = _board_plane(session, out)
        if plane is not None:
            out["plane_mm"], out["plane_straightness_um"], out["image_rotation_urad"] = plane
    return out


def _board_plane(session: Session, truth: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    from lps_gui.core.rig import Rig
    from lps_gui.core.simulate import board_plane_positions, board_plane_straightness
    from lps_gui.core.stage_errors import StageErrorModel, TruePose
    from lps_gui.io.board_file import board_from_dict
    from lps_gui.io.intrinsics_file import intrinsics_from_dict

    meta = session.meta.get("truth") or {}
    if not all(k in meta for k in ("R_cam_board", "C0_board", "u_board")):
        return None
    K = truth["axis_mm"].size
    board = board_from_dict(meta["board"]) if "board" in meta else session.board()
    intr = intrinsics_from_dict(meta["intrinsics"]) if "intrinsics" in meta else session.intrinsics()
    rig = Rig(board, intr, np.asarray(meta["R_cam_board"], float), np.asarray(meta["C0_board"], float),
              np.asarray(meta["u_board"], float), StageErrorModel())
    pose = TruePose(truth["axis_mm"], truth.get("straightness_um", np.zeros((K, 2))), truth.get("angles_urad", np.zeros((K, 3))))
    return (board_plane_positions(rig, pose), *board_plane_straightness(rig, pose))


def _per_capture_truth(session: Session) -> dict[str, Any] | None:
    meta = session.meta.get("truth") or {}
    sidecar = session.folder / TRUTH_SIDECAR
    if sidecar.exists():
        lines = []
        for text in sidecar.read_text().splitlines():
            try:
                lines.append(json.loads(text))
            except json.JSONDecodeError:  # torn by a crash mid-append: that frame is not listed either
                continue
        if lines:
            out: dict[str, Any] = {
                "index": np.array([l["index"] for l in lines], dtype=int),
                "axis_mm": np.array([l["axis_mm"] for l in lines], dtype=float),
            }
            if all("straightness_um" in l for l in lines):
                out["straightness_um"] = np.array([l["straightness_um"] for l in lines], dtype=float).reshape(-1, 2)
            if all("angles_urad" in l for l in lines):
                out["angles_urad"] = np.array([l["angles_urad"] for l in lines], dtype=float).reshape(-1, 3)
            out["replaced_views"] = meta.get("replaced_views", [])
            out["bumped_views"] = meta.get("bumped_views", [])
            return out
    axis = meta.get("axis_mm")
    if axis is None:
        return None
    K = len(axis)
    out = {
        "index": np.array(meta.get("index", range(K)), dtype=int),
        "axis_mm": np.asarray(axis, dtype=float),
        "replaced_views": meta.get("replaced_views", []),
        "bumped_views": meta.get("bumped_views", []),
    }
    if meta.get("straightness_um") is not None:
        out["straightness_um"] = np.asarray(meta["straightness_um"], dtype=float).reshape(K, 2)
    if meta.get("angles_urad") is not None:
        out["angles_urad"] = np.asarray(meta["angles_urad"], dtype=float).reshape(K, 3)
    return out
