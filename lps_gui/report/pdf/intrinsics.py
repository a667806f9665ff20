"""The intrinsics report: a PDF of one calibration (`lps intrinsics --report`).

Page 1: every parameter with its sigma, the board's bow, the error figures,
the cross-validation verdict when one was run, warnings and the rejected
corners. Then the pictures of :mod:`intrinsics_pictures`, two to a page.
"""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from lps_gui.core.geometry.camera_model import INTRINSIC_NAMES
from lps_gui.errors import InputError

if TYPE_CHECKING:
    from lps_gui.core.geometry.board import Board
    from lps_gui.core.intrinsics.calibration import IntrinsicsCalibration
    from lps_gui.core.intrinsics.crossval import CrossValidation

PICTURE_WIDTH_MM = 165.0
MAX_LISTED_CORNERS = 40


def parameter_rows(cal: "IntrinsicsCalibration") -> list[list[str]]:
    """Parameter, value, sigma, unit rows (the board's bow included when it was estimated)."""
    units = {"fx": "px", "fy": "px", "cx": "px", "cy": "px"}
    rows = [[n, f"{v:.6g}", f"{s:.3g}", units.get(n, "")] for n, v, s in zip(INTRINSIC_NAMES, cal.intrinsics.vector(), cal.std)]
    if cal.warp_mm is not None:
        for axis, v, s in zip("xy", cal.warp_mm, cal.warp_sigma_mm):
            rows.append([f"board bow {axis}", f"{v:+.4f}", f"{s:.3g}", "mm"])
    else:
        rows.append(["board bow", "not estimated", "", ""])
    w, h = cal.intrinsics.image_size
    rows.append(["image size", f"{w} x {h}", "", "px"])
    rows.append(["RMS error", f"{cal.rms_px:.4f}", "", "px"])
    rows.append(["views used", f"{len(cal.used_views)} of {len(cal.per_view_rms_px)}", "", ""])
    rows.append(["corners rejected", str(len(cal.rejected_corners)), "", ""])
    return rows


def identification_rows(cal: "IntrinsicsCalibration", board: "Board | None", date: str, version: str
                        ) -> list[list[str]]:
    """Date, board, lens model, views and software: what a reader of the calibration needs to trace it (issue 37)."""
    if board is None:
        board_text = "not given"
    else:
        kind = "ChArUco" if board.type != "chessboard" else "chessboard"
        board_text = (f"{kind} {board.cols}\u00d7{board.rows} inner corners, square {board.square_mm:g} mm "
                      "(the calibration's length unit; its print scale does not change the intrinsics)")
    higher = np.asarray(cal.intrinsics.higher, dtype=float)
    n_dist = 12 if np.any(higher[3:]) else 8 if np.any(higher) else 5  # SPEC 15: 5, 8 or 12 in OpenCV's order
    lens = {5: "OpenCV 5 coefficients (k1 k2 p1 p2 k3)", 8: "OpenCV 8 coefficients (rational: + k4 k5 k6)",
            12: "OpenCV 12 coefficients (rational and thin prism: + k4 k5 k6 s1 s2 s3 s4)"}[n_dist]
    return [["Date", date], ["Board", board_text], ["Lens model", lens],
            ["Views", f"{len(cal.used_views)} used of {len(cal.per_view_rms_px)}"], ["Software", f"lps-calib {version}"]]


def write_intrinsics_report(cal: "IntrinsicsCalibration", out: Path | str, crossval: "CrossValidation | None" = None,
                            title: str = "", clipped: list[str] | None = None, board: "Board | None" = None,
                            date: str | None = None) -> int:
    """Write the PDF; returns its number of pages. A failure leaves no partial file.

    ``board`` the calibration board (printed with the date, default now); ``clipped``, when given, receives
    every string that does not fit its box (the layout check).
    """
    import time

    from lps_gui import __version__
    from lps_gui.report.pdf.intrinsics_pictures import intrinsics_pictures
    from lps_gui.report.pdf.layout import ensure_gui_app, pdf_file

    out = Path(out)
    if not out.parent.is_dir():
        raise InputError(f"{out.parent}: folder not found; create it or choose another --report")
    ensure_gui_app()
    with pdf_file(out, f"Camera intrinsics report {title}".strip(), f"lps-calib {__version__} \u00b7 intrinsics {title}".strip()) as flow:
        flow.heading("Camera intrinsics \u2014 calibration report", 15)
        flow.table(None, identification_rows(cal, board, date or time.strftime("%Y-%m-%d %H:%M:%S%z"), __version__),
                   [30, 150], size_pt=8.0, row_mm=4.2, align_right_from=9)
        flow.paragraph("Board warp as mrcal models it: corner z = bow_x (1 - x\u00b2) + bow_y (1 - y\u00b2) with the "
                       "corner grid spanning [-1, 1]; the bow is the centre's offset from the edges along each board axis. "
                       "Sigmas are from the Jacobian at the solution, scaled by the residual noise.")
        flow.table(["parameter", "value", "\u03c3", "unit"], parameter_rows(cal), [45, 40, 30, 20])
        if crossval is not None:
            flow.heading("Cross-validation", 11)
            flow.paragraph(crossval.summary())
        if cal.warnings:
            flow.heading("Warnings", 11)
            for w in cal.warnings:
                flow.paragraph(w, color="#a04000")
        if cal.rejected_corners:
            flow.heading("Rejected corners", 11)
            names = cal.view_names
            rows = [[names[c.view] if c.view < len(names) else f"view {c.view}", str(c.corner), f"{c.residual_px:.3f}"]
                    for c in cal.rejected_corners[:MAX_LISTED_CORNERS]]
            flow.table(["view", "corner", "residual px"], rows, [110, 25, 30], align_right_from=1)
            if len(cal.rejected_corners) > MAX_LISTED_CORNERS:
                flow.paragraph(f"... and {len(cal.rejected_corners) - MAX_LISTED_CORNERS} more (all in intrinsics.json)")
        for k, (caption, image) in enumerate(intrinsics_pictures(cal, crossval, flow.log.text)):
            if k % 2 == 0:
                flow.new_page()
            flow.log.add(f"picture:{caption}")
            flow.space(flow.image(image, (180.0 - PICTURE_WIDTH_MM) / 2, PICTURE_WIDTH_MM, caption) + 4.0)
    if clipped is not None:
        clipped.extend(flow.log.clipped)
    return flow.page
