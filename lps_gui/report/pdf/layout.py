"""A top-to-bottom page flow on a QPdfWriter: headings, key-value tables, text, figures, images.

Blocks are placed at a cursor and move to a new A4 page when they do not fit;
every page gets the same footer. Qt is imported inside functions only.
"""
from __future__ import annotations

import os
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator, Sequence

from lps_gui.report.figures.spec import FigureSpec
from lps_gui.report.pdf.plot_painter import paint_figure
from lps_gui.report.pdf.text_fit import DrawnText, TextLog, draw_text, fit_widths, font

RESOLUTION_DPI = 600
MARGIN_MM = 15.0
FOOTER_MM = 8.0


def ensure_gui_app() -> Any:
    """A QGuiApplication for fonts and painting; offscreen when there is no display."""
    from PySide6.QtCore import QCoreApplication
    from PySide6.QtGui import QGuiApplication

    app = QCoreApplication.instance()
    if app is None:
        if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
            os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
        app = QGuiApplication(["lps-report"])
    return app


@dataclass
class PageLog:
    """What went on which page (tests check the page plan against the PDF), and every string drawn."""

    pages: list[list[str]] = field(default_factory=lambda: [[]])
    text: TextLog = field(default_factory=TextLog)  # every drawn string with its box (text_fit)

    def add(self, what: str) -> None:
        self.pages[-1].append(what)

    @property
    def clipped(self) -> list[str]:
        """``"page N: text"`` of every string wider or taller than its box: table cells, labels, headings."""
        return self.text.clipped()


class PdfFlow:
    """Paint blocks down A4 pages; ``y`` is the cursor in device units."""

    def __init__(self, path: Path, title: str, footer: str):
        from PySide6.QtCore import QMarginsF
        from PySide6.QtGui import QPageLayout, QPageSize, QPainter, QPdfWriter

        self.path = Path(path)
        self.writer = QPdfWriter(str(path))
        self.writer.setResolution(RESOLUTION_DPI)
        self.writer.setTitle(title)
        self.writer.setCreator("lps-calib")
        self.writer.setPageLayout(QPageLayout(QPageSize(QPageSize.PageSizeId.A4), QPageLayout.Orientation.Portrait,
                                              QMarginsF(0, 0, 0, 0), QPageLayout.Unit.Millimeter))
        self.mm = RESOLUTION_DPI / 25.4
        self.page_w = 210.0 * self.mm
        self.page_h = 297.0 * self.mm
        self.left = MARGIN_MM * self.mm
        self.width = self.page_w - 2 * MARGIN_MM * self.mm
        self.bottom = self.page_h - (MARGIN_MM + FOOTER_MM) * self.mm
        self.footer = footer
        self.painter = QPainter()
        if not self.painter.begin(self.writer):
            from lps_gui.errors import InputError

            raise InputError(f"{path}: cannot write the PDF here; check the folder exists and is writable")
        self.page = 1
        self.log = PageLog()
        self.y = MARGIN_MM * self.mm
        self._footer()

    # ---------------------------------------------------------------- pages
    def new_page(self) -> None:
        self.writer.newPage()
        self.page += 1
        self.log.pages.append([])
        self.log.text.page = self.page
        self.y = MARGIN_MM * self.mm
        self._footer()

    def ensure(self, height_mm: float) -> None:
        """Start a new page unless ``height_mm`` fits below the cursor."""
        if self.y + height_mm * self.mm > self.bottom + 1e-6:
            self.new_page()

    def remaining_mm(self) -> float:
        """Height left on this page below the cursor, mm."""
        return (self.bottom - self.y) / self.mm

    def finish(self) -> int:
        """End painting; a PDF Qt could not write completely (disk full) raises StorageError."""
        from lps_gui.errors import StorageError

        if not self.painter.end():
            raise StorageError(f"{self.path}: the PDF could not be written completely; "
                               "free disk space or choose another --out (the previous report is kept)")
        return self.page

    def abort(self) -> None:
        """End painting after a failure (the caller deletes the partial file)."""
        if self.painter.isActive():
            self.painter.end()

    def _footer(self) -> None:
        from PySide6.QtCore import QRectF, Qt
        from PySide6.QtGui import QColor

        p = self.painter
        p.save()
        p.setFont(font(7.0))
        p.setPen(QColor("#555555"))
        r = QRectF(self.left, self.page_h - (MARGIN_MM + 4) * self.mm, self.width, 5 * self.mm)
        p.drawLine(r.topLeft(), r.topRight())
        number = QRectF(r.right() - 20 * self.mm, r.top(), 20 * self.mm, r.height())
        draw_text(p, QRectF(r.left(), r.top(), r.width() - 21 * self.mm, r.height()),
                  int(Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter), self.footer, self.log.text, "footer")
        draw_text(p, number, int(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter), f"page {self.page}",
                  self.log.text, "footer")
        p.restore()

    # ---------------------------------------------------------------- blocks
    def heading(self, text: str, size_pt: float = 12.0) -> None:
        from PySide6.QtCore import QRectF, Qt
        from PySide6.QtGui import QColor

        h = size_pt * 0.55 + 2.5
        self.ensure(h + 12)  # never a heading alone at the foot of a page
        self.log.add(text)
        p = self.painter
        p.setFont(font(size_pt, bold=True))
        p.setPen(QColor("#000000"))
        draw_text(p, QRectF(self.left, self.y, self.width, h * self.mm),
                  int(Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignBottom), text, self.log.text, "heading")
        self.y += (h + 1.5) * self.mm

    def paragraph(self, text: str, size_pt: float = 8.5, color: str = "#000000") -> None:
        """Word-wrapped text across the page width."""
        from PySide6.QtCore import QRectF, Qt
        from PySide6.QtGui import QColor

        p = self.painter
        p.setFont(font(size_pt))
        flags = int(Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignTop | Qt.TextFlag.TextWordWrap)
        bound = p.boundingRect(QRectF(self.left, 0, self.width, 1e6), flags, text)
        self.ensure(bound.height() / self.mm + 1.5)
        p.setPen(QColor(color))
        draw_text(p, QRectF(self.left, self.y, self.width, bound.height()), flags, text, self.log.text, "paragraph")
        self.y += bound.height() + 1.5 * self.mm

    def table(self, header: Sequence[str] | None, rows: Sequence[Sequence[str]], widths_mm: Sequence[float],
              size_pt: float = 8.0, row_mm: float = 4.2, align_right_from: int = 1,
              colors: Sequence[str | None] | None = None, x_mm: float = 0.0,
              align_left: Sequence[int] = (), max_width_mm: float | None = None) -> None:
        """A ruled table; pages break between rows and repeat the header.

        Columns from ``align_right_from`` on are right-aligned (numbers), except
        those in ``align_left``; a header cell may hold a line break. A column
        too narrow for its widest cell (measured with the painter's font) is
        widened, first from other columns' slack, then up to ``max_width_mm``
        (default: to the right margin); what still does not fit is wrapped
        onto more lines (:func:`lps_gui.report.pdf.text_fit.fit_widths`).
        """
        from PySide6.QtCore import QLineF, QRectF, Qt
        from PySide6.QtGui import QColor, QFontMetricsF, QPen

        p = self.painter
        mm = self.mm
        x_left = self.left + x_mm * mm
        limit = (self.width / mm - x_mm) if max_width_mm is None else max_width_mm
        body_fm = QFontMetricsF(font(size_pt), p.device())
        head_fm = QFontMetricsF(font(size_pt, bold=True), p.device())
        need = [0.0] * len(widths_mm)
        for fm, cells in [(head_fm, header or [])] + [(body_fm, r) for r in rows]:
            for i, cell in enumerate(cells[:len(need)]):
                need[i] = max(need[i], max(fm.horizontalAdvance(line) for line in str(cell).split("\n")) / mm + 2.0)
        widths = fit_widths(widths_mm, need, max(limit, sum(widths_mm)))
        total_w = sum(widths) * mm
        wrap = int(Qt.TextFlag.TextWordWrap)
        first = str((header or (rows[0] if rows else [""]))[0])
        self.log.text.texts.append(DrawnText(self.page, "table width", f"table \"{first}\"",
                                             (self.left + self.width - x_left, row_mm * mm), (total_w, 0.0)))

        def lines_of(cells: Sequence[str], fm: Any) -> int:
            n = 1
            for cell, w in zip(cells, widths):
                br = fm.boundingRect(QRectF(0, 0, w * mm - 2 * mm, 1e7), wrap, str(cell))
                n = max(n, round(br.height() / fm.lineSpacing()) or 1)
            return n

        def draw_row(cells: Sequence[str], bold: bool, color: str | None, lines: int) -> None:
            p.setFont(font(size_pt, bold=bold))
            x = x_left
            for i, (cell, w) in enumerate(zip(cells, widths)):
                right = i >= align_right_from and i not in align_left
                align = Qt.AlignmentFlag.AlignRight if right else Qt.AlignmentFlag.AlignLeft
                p.setPen(QColor(color or "#000000"))
                draw_text(p, QRectF(x + 1 * mm, self.y, w * mm - 2 * mm, lines * row_mm * mm),
                          int(align | Qt.AlignmentFlag.AlignVCenter) | wrap, str(cell), self.log.text, "table")
                x += w * mm
            self.y += lines * row_mm * mm

        header_lines = lines_of(header, head_fm) if header else 0

        def draw_header() -> None:
            if header is None:
                return
            p.fillRect(QRectF(x_left, self.y, total_w, header_lines * row_mm * mm), QColor("#e8e8e8"))
            draw_row(header, True, None, header_lines)
            p.setPen(QPen(QColor("#000000"), 0.2 * mm))
            p.drawLine(QLineF(x_left, self.y, x_left + total_w, self.y))

        self.ensure(row_mm * (header_lines + 1) + 1)
        draw_header()
        for n, row in enumerate(rows):
            lines = lines_of(row, body_fm)
            if self.y + lines * row_mm * mm > self.bottom:
                self.new_page()
                draw_header()
            if n % 2 == 1:
                p.fillRect(QRectF(x_left, self.y, total_w, lines * row_mm * mm), QColor("#f6f6f6"))
            draw_row(row, False, colors[n] if colors else None, lines)
        p.setPen(QPen(QColor("#000000"), 0.2 * mm))
        p.drawLine(QLineF(x_left, self.y, x_left + total_w, self.y))
        self.y += 2.0 * mm

    def figure(self, spec: FigureSpec, height_mm: float) -> None:
        from PySide6.QtCore import QRectF

        self.ensure(height_mm)
        self.log.add(f"figure:{spec.key}")
        paint_figure(self.painter, QRectF(self.left, self.y, self.width, height_mm * self.mm), spec, self.mm,
                     self.log.text)
        self.y += (height_mm + 3.0) * self.mm

    def image(self, image: Any, x_mm: float, width_mm: float, caption: str) -> float:
        """Draw a QImage at the cursor (keeps the aspect ratio); returns its height in mm (caption included)."""
        from PySide6.QtCore import QRectF, Qt
        from PySide6.QtGui import QColor

        h_mm = width_mm * image.height() / max(image.width(), 1)
        target = QRectF(self.left + x_mm * self.mm, self.y, width_mm * self.mm, h_mm * self.mm)
        self.painter.drawImage(target, image)
        self.painter.setPen(QColor("#000000"))
        self.painter.drawRect(target)
        self.painter.setFont(font(7.0))
        draw_text(self.painter, QRectF(target.left(), target.bottom() + 0.5 * self.mm, target.width(), 4 * self.mm),
                  int(Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignTop), caption, self.log.text, "caption")
        return h_mm + 5.0

    def space(self, mm: float) -> None:
        self.y += mm * self.mm


@contextmanager
def pdf_file(out: Path, title: str, footer: str) -> Iterator["PdfFlow"]:
    """Paint a PDF into a temp file beside ``out``; only a complete one replaces ``out``.

    On leaving the block the painter is ended (its result checked) and the temp
    file is committed by :func:`lps_gui.io.atomic.commit_temp` (fsync, size,
    ``%%EOF`` trailer: Qt reports success when a full disk cuts a PDF short); on
    an exception it is aborted and removed, and the previous ``out`` is kept.
    """
    from lps_gui.io.atomic import commit_temp, temp_path

    out = Path(out)
    tmp = temp_path(out)
    try:
        flow = PdfFlow(tmp, title, footer)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    try:
        yield flow
        flow.finish()
    except BaseException:
        flow.abort()
        tmp.unlink(missing_ok=True)
        raise
    commit_temp(tmp, out, ends_with=b"%%EOF")
