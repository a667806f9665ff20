"""Printable targets (SPEC 13): each ChArUco target at true scale on its own page, in vector.

Every square and every marker cell is a filled rectangle in millimetres, so the
print is as exact as the printer: nothing is rasterized. Each page names the
target, its marker ids and dictionary, and carries a 100 mm scale bar whose
length the user checks with a ruler or caliper before mounting (the printed
square size is the length unit of every result). Qt is imported inside
functions only.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from lps_gui.camera.charuco import DEFAULT_DICTIONARY
from lps_gui.core.geometry.targets import Target
from lps_gui.errors import InputError
from lps_gui.io.atomic import commit_temp, temp_path
from lps_gui.report.pdf.layout import ensure_gui_app

MARGIN_MM = 15.0  # white around the board: the detector needs a quiet zone, the printer a border
CAPTION_MM = 22.0  # below the board: id, ids, scale bar
SCALE_BAR_MM = 100.0


@dataclass(frozen=True)
class PrintedTargets:
    path: Path
    pages: int
    page_sizes_mm: tuple[tuple[float, float], ...]


def marker_cells(target: Target, k: int) -> np.ndarray:
    """The k-th marker's cells, 1 = black, shape (n + 2, n + 2) with the black border (n = marker bits)."""
    name = target.board.dictionary or DEFAULT_DICTIONARY
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, name))
    n = dictionary.markerSize
    img = cv2.aruco.generateImageMarker(dictionary, target.first_marker + k, n + 2, borderBits=1)
    return (img < 128).astype(np.uint8)


def board_rectangles(target: Target) -> list[tuple[float, float, float, float]]:
    """Black rectangles (x, y, w, h) mm of the target, origin at the top-left of its squares.

    Squares alternate from black at the top left (as OpenCV draws ChArUco boards);
    markers sit centred in the white squares in row-major order, ids from first_marker on.
    """
    b = target.board
    s = b.square_mm
    m = b.marker_mm or 0.7 * s
    rects: list[tuple[float, float, float, float]] = []
    k = 0
    for r in range(b.rows + 1):
        for c in range(b.cols + 1):
            if (r + c) % 2 == 0:
                rects.append((c * s, r * s, s, s))
                continue
            cells = marker_cells(target, k)
            k += 1
            cell = m / cells.shape[0]
            x0, y0 = c * s + (s - m) / 2, r * s + (s - m) / 2
            for i, j in zip(*np.nonzero(cells)):
                rects.append((x0 + j * cell, y0 + i * cell, cell, cell))
    return rects


def write_targets_pdf(path: Path | str, targets: list[Target]) -> PrintedTargets:
    """One page per target, each page the board's size plus margins and caption (print at 100 %)."""
    ensure_gui_app()
    from PySide6.QtCore import QMarginsF, QRectF, QSizeF, Qt
    from PySide6.QtGui import QColor, QFont, QPageLayout, QPageSize, QPainter, QPdfWriter, QPen

    path = Path(path)
    tmp = temp_path(path)
    writer = QPdfWriter(str(tmp))
    writer.setResolution(1200)
    writer.setTitle("lps-calib targets")
    writer.setCreator("lps-calib")
    painter = QPainter()
    sizes = []
    dpmm = 1200 / 25.4

    def page_for(t: Target) -> tuple[float, float]:
        b = t.board
        return ((b.cols + 1) * b.square_mm + 2 * MARGIN_MM,
                (b.rows + 1) * b.square_mm + 2 * MARGIN_MM + CAPTION_MM)

    for j, t in enumerate(targets):
        w, h = page_for(t)
        layout = QPageLayout(QPageSize(QSizeF(w, h), QPageSize.Unit.Millimeter, f"target {t.id}"),
                             QPageLayout.Orientation.Portrait, QMarginsF(0, 0, 0, 0), QPageLayout.Unit.Millimeter)
        writer.setPageLayout(layout)
        if j == 0:
            if not painter.begin(writer):
                raise InputError(f"{path}: cannot write the PDF here; check the folder exists and is writable")
        else:
            writer.newPage()
        sizes.append((w, h))
        painter.setPen(Qt.PenStyle.NoPen)
        painter.setBrush(QColor(0, 0, 0))
        for x, y, rw, rh in board_rectangles(t):
            painter.drawRect(QRectF((MARGIN_MM + x) * dpmm, (MARGIN_MM + y) * dpmm, rw * dpmm, rh * dpmm))
        b = t.board
        y_cap = MARGIN_MM + (b.rows + 1) * b.square_mm + 4.0
        font = QFont("DejaVu Sans")
        font.setPointSizeF(9.0)
        painter.setFont(font)
        painter.setPen(QPen(QColor(0, 0, 0)))
        ids = t.marker_range
        text = (f"target {t.id}   {b.cols}x{b.rows} inner corners, square {b.square_mm:g} mm, marker "
                f"{(b.marker_mm or 0.7 * b.square_mm):g} mm, {b.dictionary or DEFAULT_DICTIONARY} ids {ids.start}-{ids.stop - 1}")
        painter.drawText(QRectF(MARGIN_MM * dpmm, y_cap * dpmm, (w - 2 * MARGIN_MM) * dpmm, 5 * dpmm),
                         Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter, text)
        bar = min(SCALE_BAR_MM, w - 2 * MARGIN_MM)
        y_bar = y_cap + 8.0
        painter.setPen(Qt.PenStyle.NoPen)
        for k in range(int(bar // 10)):
            painter.setBrush(QColor(0, 0, 0) if k % 2 == 0 else QColor(255, 255, 255))
            painter.drawRect(QRectF((MARGIN_MM + 10 * k) * dpmm, y_bar * dpmm, 10 * dpmm, 2 * dpmm))
        painter.setBrush(Qt.BrushStyle.NoBrush)
        painter.setPen(QPen(QColor(0, 0, 0), 0.1 * dpmm))
        painter.drawRect(QRectF(MARGIN_MM * dpmm, y_bar * dpmm, bar * dpmm, 2 * dpmm))
        painter.drawText(QRectF((MARGIN_MM + bar + 3) * dpmm, (y_bar - 1.5) * dpmm, 80 * dpmm, 5 * dpmm),
                         Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter,
                         f"{bar:g} mm: print at 100 %, measure this bar")
    painter.end()
    commit_temp(tmp, path, ends_with=b"%%EOF")
    return PrintedTargets(path, len(targets), tuple(sizes))
