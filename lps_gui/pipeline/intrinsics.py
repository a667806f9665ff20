"""Intrinsics from a set of board images: detect every image, then calibrate (SPEC 6)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from lps_gui.core.board import Board
from lps_gui.core.camera_model import CameraIntrinsics
from lps_gui.core.intrinsics_calibration import IntrinsicsCalibration, calibrate_intrinsics
from lps_gui.core.intrinsics_crossval import CrossValidation, cross_validate
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.errors import InputError
from lps_gui.io.corners_vnl import CornerTable

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm")


def expand_image_paths(items: list[Path]) -> list[Path]:
    """Files as given, folders expanded to their images (sorted)."""
    out: list[Path] = []
    for item in map(Path, items):
        if item.is_dir():
            out += sorted(p for p in item.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
        else:
            out.append(item)
    return out


def image_size_of(paths: list[Path], table: CornerTable) -> tuple[int, int]:
    """Size (w, h) of the first image that was read."""
    import cv2

    for p in paths:
        if str(p) in table.failed:
            continue
        img = cv2.imread(str(p), cv2.IMREAD_GRAYSCALE)
        if img is not None:
            return (img.shape[1], img.shape[0])
    raise InputError("intrinsics: none of the images could be read; check the paths")


def calibrate_images(
    paths: list[Path],
    board: Board,
    progress: ProgressFn = no_progress,
    cancel: CancelToken | None = None,
    workers: int | None = None,
    flags: int = 0,
    warp: str = "auto",
) -> IntrinsicsCalibration:
    """Detect the board in every image and calibrate; failed images are listed in the warnings.

    The returned intrinsics carry per-view RMS, coverage, flagged views and
    warnings in ``extra`` so intrinsics.json keeps them.
    """
    from lps_gui.pipeline.detect import detect_images

    paths = expand_image_paths(paths)
    table = detect_images(paths, board, progress, cancel, workers, track=False)
    size = image_size_of(paths, table)
    cal = calibrate_intrinsics(board.flat_points(), list(table.corners_px), size, flags=flags, warp=warp)
    cal.view_names = list(table.names)
    cal.warnings += [f"{name}: {reason}" for name, reason in table.failed.items()]
    cal.intrinsics = _with_report(cal)
    return cal


def cross_validate_calibration(cal: IntrinsicsCalibration, board: Board, flags: int = 0, warp: str = "auto") -> CrossValidation:
    """Calibrate the even and the odd views of ``cal`` apart (same corners) and compare their projections."""
    return cross_validate(board.flat_points(), cal.image_points, cal.intrinsics.image_size, flags=flags, warp=warp)


def _with_report(cal: IntrinsicsCalibration) -> CameraIntrinsics:
    from dataclasses import replace

    names = cal.view_names or [f"view {i}" for i in range(len(cal.per_view_rms_px))]
    extra = {
        **cal.intrinsics.extra,
        "per_view_rms_px": {n: (None if not np.isfinite(v) else round(float(v), 5)) for n, v in zip(names, cal.per_view_rms_px)},
        "coverage_grid": cal.coverage.tolist(),
        "flagged_views": [names[i] for i in cal.flagged_views],
        "warnings": list(cal.warnings),
        "rejected_corners": [{"view": names[c.view], "corner": c.corner, "residual_px": round(c.residual_px, 4)}
                             for c in cal.rejected_corners],
    }
    if cal.warp_mm is not None:
        extra["board_warp_mm"] = [float(v) for v in cal.warp_mm]
        extra["board_warp_sigma_mm"] = [float(v) for v in cal.warp_sigma_mm]
    return replace(cal.intrinsics, extra=extra)
