"""Range and shape checks of board.json and intrinsics values, before they are used.

A value of the right type but an absurd size (inner_corners 1e9, fx 1e300,
image_size 0, one distortion coefficient, a ragged covariance, std "abc")
would otherwise crash deep inside numpy or OpenCV, or be silently truncated
(inner_corners 9.5 read as 9). Each check raises InputError naming the file
and the field.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from lps_gui.errors import InputError

MAX_INNER_CORNERS = 1000
MAX_IMAGE_SIDE = 100_000
MAX_FOCAL_PX = 1e7
DIST_LENGTHS = (4, 5, 8, 12, 14)  # what OpenCV accepts


def _whole(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) or (
        isinstance(value, float) and math.isfinite(value) and value == int(value))


def _finite(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def check_board_values(d: Any, source: str) -> None:
    if not isinstance(d, dict):
        raise InputError(f"{source}: a board is a JSON object with type, inner_corners and square_mm")
    ic = d.get("inner_corners")
    if not (isinstance(ic, (list, tuple)) and len(ic) == 2 and all(_whole(v) and 2 <= v <= MAX_INNER_CORNERS for v in ic)):
        raise InputError(f"{source}: inner_corners must be two whole numbers [cols, rows] from 2 to {MAX_INNER_CORNERS}, "
                         f"not {ic!r}")
    sq = d.get("square_mm")
    if not (_finite(sq) and 0 < sq <= 1e4):
        raise InputError(f"{source}: square_mm must be a positive size in mm, not {sq!r}")


def _array(value: Any, shape: tuple[int, ...] | None = None) -> np.ndarray | None:
    """``value`` as a finite float array (of ``shape``), or None when it is not one (ragged, text, NaN)."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return None
    if shape is not None and a.shape != shape:
        return None
    return a if np.all(np.isfinite(a)) else None


def check_intrinsics_values(d: Any, source: str) -> None:
    if not isinstance(d, dict):
        raise InputError(f"{source}: intrinsics are a JSON object with image_size, camera_matrix and dist")
    size = d.get("image_size")
    size_list = list(size) if isinstance(size, (list, tuple, np.ndarray)) else None
    if not (size_list is not None and len(size_list) == 2
            and all(_whole(float(v) if isinstance(v, np.number) else v) and 1 <= v <= MAX_IMAGE_SIDE for v in size_list)):
        raise InputError(f"{source}: image_size must be [width, height] in pixels (1 to {MAX_IMAGE_SIDE}), not {size!r}")
    K = _array(d.get("camera_matrix"))
    if K is None or K.size != 9:
        raise InputError(f"{source}: camera_matrix must be 3 rows of 3 finite numbers")
    K = K.reshape(3, 3)
    fx, fy = K[0, 0], K[1, 1]
    if not (0 < fx <= MAX_FOCAL_PX and 0 < fy <= MAX_FOCAL_PX):
        raise InputError(f"{source}: focal lengths fx {fx:g}, fy {fy:g} px must be positive and below {MAX_FOCAL_PX:g}; recalibrate")
    dist = _array(d.get("dist", [0.0] * 5))
    if dist is None or dist.size not in DIST_LENGTHS:
        n = "non-numeric" if dist is None else dist.size
        raise InputError(f"{source}: dist must be {', '.join(map(str, DIST_LENGTHS))} finite coefficients "
                         f"(k1, k2, p1, p2[, k3...]), not {n}")
    std = d.get("std")
    if std is not None:
        if not isinstance(std, dict) or not all(_finite(v) and v >= 0 for v in std.values()):
            raise InputError(f"{source}: std must map parameter names to non-negative numbers, not {std!r}")
    if d.get("covariance") is not None and _array(d["covariance"], (9, 9)) is None:
        raise InputError(f"{source}: covariance must be 9 rows of 9 finite numbers (ragged or non-numeric here)")
