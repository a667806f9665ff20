"""Whether two estimated sessions measured one stage on one rig over one travel (`lps compare` asks first).

An as-found / as-left comparison of two different rigs or travels prints numbers that compare nothing;
the rig is what session.json records of the stage, the camera and the board (not the stage's errors,
which compensation changes, nor its settings), the travel the span of the targets.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

from lps_gui.errors import InputError
from lps_gui.io.results.model import Results

STAGE_KEYS = ("driver", "port", "device", "axis_number", "serial_number", "travel_mm")
CAMERA_KEYS = ("driver", "model", "serial", "source", "width", "height", "image_size")
BOARD_KEYS = ("type", "inner_corners", "square_mm")
TRAVEL_TOLERANCE_MM = 1e-3


def rig_of(results: Results) -> dict[str, Any]:
    """What identifies the rig of an estimated session: the stage, camera and board fields session.json recorded."""
    meta: Mapping[str, Any] = results.session_meta or {}
    stage, camera = meta.get("stage") or {}, meta.get("camera") or {}
    board = results.raw.get("board") or {}
    return {**{f"stage {k}": stage[k] for k in STAGE_KEYS if k in stage},
            **{f"camera {k}": camera[k] for k in CAMERA_KEYS if k in camera},
            **{f"board {k}": board[k] for k in BOARD_KEYS if k in board}}


def travel_of(results: Results) -> tuple[float, float] | None:
    """(first, last) target of the session in mm, None without positions."""
    targets = [float(v) for v in (r.number("target_mm") for r in results.positions) if v is not None]
    return (min(targets), max(targets)) if targets else None


def require_comparable(before: Results, after: Results, before_dir: Path, after_dir: Path) -> None:
    """Raise a one-line InputError when the two sessions are of different rigs or travels."""
    a, b = rig_of(before), rig_of(after)
    differ = [k for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]
    if differ:
        k = differ[0]
        raise InputError(f"lps compare: {before_dir} and {after_dir} are of different rigs ({k} {a.get(k, 'none')} vs "
                         f"{b.get(k, 'none')}); compare an as-found and an as-left session of one stage, camera and board")
    ta, tb = travel_of(before), travel_of(after)
    if ta is None or tb is None or max(abs(ta[0] - tb[0]), abs(ta[1] - tb[1])) > TRAVEL_TOLERANCE_MM:
        def text(t: tuple[float, float] | None) -> str:
            return "no targets" if t is None else f"{t[0]:g}-{t[1]:g} mm"

        raise InputError(f"lps compare: {before_dir} travels {text(ta)} and {after_dir} {text(tb)}; compare two sessions "
                         "over the same targets")
