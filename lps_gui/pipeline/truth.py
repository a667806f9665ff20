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
    """Arrays index (K,), axis_mm (K,), straightness_um (K, 2), angles_urad (K, 3), or None."""
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
