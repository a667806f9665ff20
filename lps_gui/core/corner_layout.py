"""Do a session's corners sit as the board and the intrinsics say they must, before anything is fitted to them?

Three mistakes a corners file can carry that an estimate would otherwise
turn into a confident wrong answer (issue 39): a view whose corners come in
the reverse order (the board read from the other end: PnP finds the board
turned 180 degrees, and the joint fit then throws out healthy views instead),
corners mirrored (x and y swapped: no camera sees a board's front mirrored),
and corners outside the image the intrinsics were calibrated for (corners
scaled, or from another camera). On a stage the board keeps its orientation
in the image from view to view, so the majority direction of the first row
is the reference. Pure numbers in, reasons out.
"""
from __future__ import annotations

import numpy as np

EDGE_PX = 0.5  # a corner centre can sit up to half a pixel beyond the outermost pixel centre


def layout_problems(corners: np.ndarray, cols: int, rows: int, image_size: tuple[int, int]) -> list[tuple[int, str]]:
    """(view index, reason) of every view whose corners (K, N, 2), row-major ``cols`` x ``rows``, are not laid out
    as the board, the other views and the image say; views of NaN corners (not detected) are skipped."""
    c = np.asarray(corners, dtype=np.float64)
    valid = np.isfinite(c).all(axis=(1, 2))
    w, h = image_size
    x, y = c[..., 0], c[..., 1]
    outside = valid & ((x < -EDGE_PX) | (y < -EDGE_PX) | (x > w - 1 + EDGE_PX) | (y > h - 1 + EDGE_PX)).any(axis=1)
    along = c[:, cols - 1] - c[:, 0]  # the first row, first to last corner
    down = c[:, (rows - 1) * cols] - c[:, 0]  # the first column
    mirrored = valid & (along[:, 0] * down[:, 1] - along[:, 1] * down[:, 0] < 0)
    unit = along / np.maximum(np.linalg.norm(along, axis=1, keepdims=True), 1e-12)
    reference = np.nansum(np.where(valid[:, None], unit, 0.0), axis=0)
    reversed_ = valid & (unit @ reference < 0) if np.linalg.norm(reference) > 0 else np.zeros(len(c), bool)
    problems = []
    for k in range(len(c)):
        if outside[k]:
            far = np.nanmax(np.abs(c[k]), axis=0)
            problems.append((k, f"corners reach ({far[0]:.0f}, {far[1]:.0f}) px, outside the {w}x{h} image of the "
                                "intrinsics (corners scaled, or intrinsics of another camera or resolution)"))
        elif mirrored[k]:
            problems.append((k, "corners mirrored (x and y swapped?): no camera sees the front of a board mirrored"))
        elif reversed_[k]:
            problems.append((k, "corners in the reverse order of the other views (the board read from its other end)"))
    return problems
