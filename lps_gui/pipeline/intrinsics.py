"""Intrinsics from a set of board images: detect every image, then calibrate (SPEC 6)."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.intrinsics.calibration import IntrinsicsCalibration, calibrate_intrinsics
from lps_gui.core.intrinsics.crossval import LENS_MODELS, CrossValidation, choose_lens_model, cross_validate
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.errors import InputError
from lps_gui.io.corners.vnl import CornerTable

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm")


def expand_image_paths(items: list[Path]) -> list[Path]:
    """Files as given, folders expanded to their images (sorted); InputError for an image (named, or a folder
    entry named like one) that is no regular file (a FIFO, a device, a link to one), by its stat before any open."""
    from lps_gui.file_limits import check_regular_file

    out: list[Path] = []
    for item in map(Path, items):
        if item.is_dir():
            found = sorted(p for p in item.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
            for p in found:  # a link to a regular file elsewhere is the user's choice; /dev/urandom is not an image
                check_regular_file(p, "image")
            out += found
        else:
            if item.exists():  # a missing one fails as its view, like an unreadable image
                check_regular_file(item, "image")
            out.append(item)
    return out


def image_size_of(paths: list[Path], table: CornerTable) -> tuple[int, int]:
    """Size (w, h) of the images the board was found in (from their headers, checked like every read).

    Images of two sizes are refused: one camera model cannot fit both, and a calibration of a mixed set
    comes out confidently wrong (k2, k3 off by 10x).
    """
    from lps_gui.io.image_file import image_size

    sizes: dict[tuple[int, int], list[str]] = {}
    for p in paths:
        if str(p) not in table.failed:
            sizes.setdefault(image_size(p), []).append(str(p))
    if len(sizes) > 1:
        common = max(sizes, key=lambda k: len(sizes[k]))
        other = next(k for k in sizes if k != common)
        raise InputError(f"intrinsics: the images are of {len(sizes)} sizes: {len(sizes[common])} of "
                         f"{common[0]}x{common[1]}, {len(sizes[other])} of {other[0]}x{other[1]} (first: "
                         f"{sizes[other][0]}); calibrate with images of one camera at one resolution")
    if sizes:
        return next(iter(sizes))
    unreadable = [n for n, why in table.failed.items() if "board" not in why]
    if len(unreadable) == len(paths):
        raise InputError(f"intrinsics: none of the {len(paths)} images could be read (first: {unreadable[0]}: "
                         f"{table.failed[unreadable[0]]}); check the paths")
    raise InputError(f"intrinsics: the board was found in none of the {len(paths)} images; check --board matches "
                     "the printed board (inner corners, type)")


def calibrate_images(
    paths: list[Path],
    board: Board,
    progress: ProgressFn = no_progress,
    cancel: CancelToken | None = None,
    workers: int | None = None,
    flags: int = 0,
    warp: str = "auto",
    model: str = "opencv5",
    model_error: bool = True,
) -> IntrinsicsCalibration:
    """Detect the board in every image and calibrate; failed images are listed in the warnings.

    ``model``: "opencv5" (k1 k2 p1 p2 k3), "rational" (with OpenCV's rational and thin-prism terms, 12
    coefficients) or "auto" (the one two-fold cross-validation prefers,
    :func:`lps_gui.core.intrinsics.crossval.choose_lens_model`; recorded in ``extra["lens_model_choice"]``).
    ``model_error``: add the lens-model error the delete-one-view refits show to the covariance
    (:mod:`lps_gui.core.intrinsics.model_error`): without it a lens the model cannot follow biases every figure
    far beyond its bar (issue 35).

    The returned intrinsics carry per-view RMS, coverage, flagged views and
    warnings in ``extra`` so intrinsics.json keeps them.
    """
    from lps_gui.pipeline.detect import detect_images

    paths = expand_image_paths(paths)
    table = detect_images(paths, board, progress, cancel, workers, track=False)
    size = image_size_of(paths, table)
    drop_repeated_views(table)
    choice = None
    if model == "auto":
        choice = choose_lens_model(board.flat_points(), list(table.corners_px), size, flags=flags, warp=warp)
        model = choice.model
    if model not in LENS_MODELS:
        raise InputError(f"intrinsics: lens model must be opencv5, rational or auto, not {model!r}")
    cal = calibrate_intrinsics(board.flat_points(), list(table.corners_px), size, flags=flags | LENS_MODELS[model],
                               warp=warp, model_error=model_error)
    if choice is not None:
        cal.intrinsics = replace(cal.intrinsics, extra={**cal.intrinsics.extra, "lens_model_choice": {
            "model": choice.model, "heldout_rms_px": choice.heldout_rms_px}})
        cal.warnings.append(choice.summary())
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


def drop_repeated_views(table: CornerTable, min_views: int = 3) -> None:
    """Mark views that repeat an earlier one (or whose corners lie on a line) as failed, with the reason.

    Copies of one image would shrink the reported std as if they were new
    poses; fewer than ``min_views`` distinct usable views are refused.
    """
    from lps_gui.core.geometry.view_geometry import collinear_views, duplicate_views

    for k in collinear_views(table.corners_px):
        table.failed.setdefault(table.names[k], "corners lie on one line (board edge-on or corrupt corners)")
    for first, later in duplicate_views(table.corners_px):
        if table.names[first] not in table.failed:
            table.failed.setdefault(table.names[later], f"same view as {table.names[first]} (corners within 0.5 px): "
                                    "a copy adds no information; take a new pose")
    for name in table.failed:
        table.corners_px[table.names.index(name)] = np.nan
    usable = len(table.names) - len(table.failed)
    if usable < min_views:
        raise InputError(f"intrinsics: only {usable} distinct usable view(s) of {len(table.names)}; calibration "
                         f"needs at least {min_views} varied poses of the board (tilted, at several places)")