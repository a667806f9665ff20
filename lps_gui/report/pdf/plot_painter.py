"""Paint a :class:`FigureSpec` with QPainter: vector lines, bands, markers, outlier crosses.

The same plot definitions the GUI shows with pyqtgraph, drawn here for paper.
Qt is imported inside functions only (layer rule: report imports without Qt).
Sizes are given in millimetres and converted with the device's resolution,
so a plot looks the same on any paint device.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from lps_gui.report.figures.axes import data_range, log_ticks, nice_ticks, padded, tick_label
from lps_gui.report.figures.spec import OUTLIER_COLOR, FigureSpec, Series
from lps_gui.report.pdf.text_fit import TextLog, draw_text, fitting_size, font


def segments(x: np.ndarray, y: np.ndarray) -> list[np.ndarray]:
    """Index runs where both x and y are finite: a line breaks at a gap instead of jumping."""
    ok = np.isfinite(x) & np.isfinite(y)
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        return []
    breaks = np.flatnonzero(np.diff(idx) > 1) + 1
    return [s for s in np.split(idx, breaks) if s.size]


class _Mapper:
    """Data -> device coordinates inside a plot rectangle."""

    def __init__(self, rect: Any, xr: tuple[float, float], yr: tuple[float, float], x_log: bool):
        self.rect, self.xr, self.yr, self.x_log = rect, xr, yr, x_log

    def x(self, v: np.ndarray) -> np.ndarray:
        lo, hi = self.xr
        if self.x_log:
            v, lo, hi = np.log10(np.maximum(v, 1e-300)), math.log10(lo), math.log10(hi)
        return self.rect.left() + (np.asarray(v, dtype=float) - lo) / (hi - lo) * self.rect.width()

    def y(self, v: np.ndarray) -> np.ndarray:
        lo, hi = self.yr
        return self.rect.bottom() - (np.asarray(v, dtype=float) - lo) / (hi - lo) * self.rect.height()


def paint_figure(painter: Any, rect: Any, figure: FigureSpec, px_per_mm: float, log: TextLog | None = None) -> None:
    """Draw ``figure`` inside ``rect`` (QRectF, device units): title, axes, series, legend.

    Parameters
    ----------
    painter : QPainter
        Active on the target device.
    rect : QRectF
        The whole figure area, title and legend included.
    px_per_mm : float
        Device units per millimetre (resolution / 25.4).
    log : TextLog, optional
        Where every drawn string is recorded with its box (the clipping check).
    """
    from PySide6.QtCore import QRectF, Qt
    from PySide6.QtGui import QColor, QPen

    mm = px_per_mm
    painter.save()
    title_h = 5.5 * mm
    painter.setFont(font(fitting_size(painter, figure.title, rect.width(), 9.0, 7.0, bold=True), bold=True))
    painter.setPen(QColor("#000000"))
    draw_text(painter, QRectF(rect.left(), rect.top(), rect.width(), title_h),
              int(Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter), figure.title, log, "title")

    legend_rows = _legend_layout(painter, figure, rect.width() - 16 * mm, mm)
    notes_flags = int(Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignTop | Qt.TextFlag.TextWordWrap)
    notes_h = 0.0
    if figure.notes:
        painter.setFont(font(7.0))
        notes_h = painter.boundingRect(QRectF(0, 0, rect.width() - 18 * mm, 1e7), notes_flags, figure.notes).height()
    legend_h = len(legend_rows) * 4.0 * mm + (notes_h + 0.5 * mm if figure.notes else 0.0) + 1.0 * mm
    plot = QRectF(rect.left() + 16 * mm, rect.top() + title_h + 1 * mm,
                  rect.width() - 18 * mm, rect.height() - title_h - 11 * mm - legend_h)
    xr0, yr0 = data_range(figure, "x"), data_range(figure, "y")
    painter.setPen(QPen(QColor("#000000"), 0.25 * mm))
    if xr0 is None or yr0 is None:
        painter.drawRect(plot)
        painter.setFont(font(9.0))
        draw_text(painter, plot, int(Qt.AlignmentFlag.AlignCenter | Qt.TextFlag.TextWordWrap),
                  f"no data for this plot: {figure.notes}" if figure.notes else "no data for this plot", log, "axis")
        painter.restore()
        return
    xr = padded(*xr0, fraction=0.02, log=figure.x_log)
    yr = padded(*yr0, fraction=0.08)
    m = _Mapper(plot, xr, yr, figure.x_log)
    _paint_axes(painter, plot, m, figure, mm, log)

    painter.save()
    painter.setClipRect(plot)
    painter.setRenderHint(painter.RenderHint.Antialiasing, True)
    for s in figure.series:
        _paint_bands(painter, s, m)
    for s in figure.series:
        _paint_series(painter, s, m, mm)
    painter.restore()
    painter.setPen(QPen(QColor("#000000"), 0.25 * mm))
    painter.setBrush(Qt.BrushStyle.NoBrush)
    painter.drawRect(plot)

    # legend and notes under the x label
    y0 = plot.bottom() + 10.5 * mm
    painter.setFont(font(7.0))
    for row in legend_rows:
        x0 = plot.left()
        for s, w in row:
            _legend_swatch(painter, QRectF(x0, y0, 7 * mm, 3.5 * mm), s, mm)
            painter.setPen(QColor("#000000"))
            room = min(w, rect.right() - x0 - 8 * mm)
            draw_text(painter, QRectF(x0 + 8 * mm, y0, room, 3.5 * mm), int(Qt.AlignmentFlag.AlignVCenter), s.label,
                      log, "legend")
            x0 += w + 12 * mm
        y0 += 4.0 * mm
    if figure.notes:
        painter.setFont(font(7.0))
        painter.setPen(QColor("#444444"))
        draw_text(painter, QRectF(plot.left(), y0, rect.width() - 18 * mm, notes_h + 0.5 * mm), notes_flags,
                  figure.notes, log, "legend")
    painter.restore()


def _legend_layout(painter: Any, figure: FigureSpec, width: float, mm: float) -> list[list[tuple[Series, float]]]:
    """Legend entries flowed into rows that fit ``width``: [(series, text width)]."""
    from PySide6.QtGui import QFontMetricsF

    metrics = QFontMetricsF(font(7.0), painter.device())
    rows: list[list[tuple[Series, float]]] = [[]]
    used = 0.0
    for s in figure.series:
        w = metrics.horizontalAdvance(s.label)
        need = w + 20 * mm
        if rows[-1] and used + need > width:
            rows.append([])
            used = 0.0
        rows[-1].append((s, w))
        used += need
    return [r for r in rows if r]


def _paint_axes(painter: Any, plot: Any, m: _Mapper, figure: FigureSpec, mm: float, log: TextLog | None) -> None:
    """Grid, tick labels and axis labels; a label too long for its axis is set smaller (down to 6 pt)."""
    from PySide6.QtCore import QLineF, QRectF, Qt
    from PySide6.QtGui import QColor, QPen

    xt = log_ticks(*m.xr) if figure.x_log else nice_ticks(*m.xr, target=8)
    yt = nice_ticks(*m.yr, target=6)
    grid = QPen(QColor("#d0d0d0"), 0.15 * mm)
    painter.setFont(font(7.0))
    for v in xt:
        px = float(m.x(np.array([v]))[0])
        painter.setPen(grid)
        painter.drawLine(QLineF(px, plot.top(), px, plot.bottom()))
        painter.setPen(QColor("#000000"))
        draw_text(painter, QRectF(px - 12 * mm, plot.bottom() + 0.8 * mm, 24 * mm, 3.5 * mm),
                  int(Qt.AlignmentFlag.AlignHCenter | Qt.AlignmentFlag.AlignTop), tick_label(v, xt), log, "axis")
    for v in yt:
        py = float(m.y(np.array([v]))[0])
        painter.setPen(QPen(QColor("#909090"), 0.2 * mm) if v == 0 else grid)
        painter.drawLine(QLineF(plot.left(), py, plot.right(), py))
        painter.setPen(QColor("#000000"))
        draw_text(painter, QRectF(plot.left() - 15 * mm, py - 2 * mm, 14 * mm, 4 * mm),
                  int(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter), tick_label(v, yt), log, "axis")
    centre = int(Qt.AlignmentFlag.AlignHCenter | Qt.AlignmentFlag.AlignVCenter)
    painter.setFont(font(fitting_size(painter, figure.x_label, plot.width(), 8.0, 6.0)))
    draw_text(painter, QRectF(plot.left(), plot.bottom() + 5 * mm, plot.width(), 4.5 * mm), centre, figure.x_label,
              log, "axis")
    painter.save()
    painter.translate(plot.left() - 15.5 * mm, plot.center().y())
    painter.rotate(-90)
    painter.setFont(font(fitting_size(painter, figure.y_label, plot.height(), 8.0, 6.0)))
    draw_text(painter, QRectF(-plot.height() / 2, -1 * mm, plot.height(), 4.5 * mm), centre, figure.y_label, log,
              "axis")
    painter.restore()


def _qcolor(color: str, alpha: int = 255) -> Any:
    from PySide6.QtGui import QColor

    c = QColor(color)
    c.setAlpha(alpha)
    return c


def _paint_bands(painter: Any, s: Series, m: _Mapper) -> None:
    """A filled band between band_low and band_high, broken at gaps."""
    if s.band_low is None or s.band_high is None:
        return
    from PySide6.QtCore import QPointF, Qt
    from PySide6.QtGui import QPolygonF

    painter.setPen(Qt.PenStyle.NoPen)
    painter.setBrush(_qcolor(s.color, 55))
    order = np.argsort(s.x, kind="stable")
    x, lo, hi = s.x[order], s.band_low[order], s.band_high[order]
    ok_y = np.isfinite(lo) & np.isfinite(hi)
    for seg in segments(x, np.where(ok_y, 0.0, np.nan)):
        px = m.x(x[seg])
        pts = [QPointF(a, b) for a, b in zip(px, m.y(hi[seg]))] + [QPointF(a, b) for a, b in zip(px[::-1], m.y(lo[seg])[::-1])]
        painter.drawPolygon(QPolygonF(pts))


def _paint_series(painter: Any, s: Series, m: _Mapper, mm: float) -> None:
    from PySide6.QtCore import QLineF, QPointF, Qt
    from PySide6.QtGui import QPainterPath, QPen

    px, py = m.x(s.x), m.y(s.y)
    painter.setBrush(Qt.BrushStyle.NoBrush)
    if "line" in s.style:
        pen = QPen(_qcolor(s.color), (0.3 if s.dashed else 0.35) * mm)
        if s.dashed:
            pen.setDashPattern([4.0, 2.5])
        painter.setPen(pen)
        for seg in segments(px, py):
            path = QPainterPath(QPointF(px[seg[0]], py[seg[0]]))
            for i in seg[1:]:
                path.lineTo(px[i], py[i])
            painter.drawPath(path)
    if "markers" in s.style:
        r = (0.45 if s.x.size > 200 else 0.6) * mm
        painter.setPen(QPen(_qcolor(s.color), 0.2 * mm))
        painter.setBrush(_qcolor(s.color, 170))
        ok = np.isfinite(px) & np.isfinite(py)
        for a, b in zip(px[ok], py[ok]):
            painter.drawEllipse(QPointF(a, b), r, r)
    if s.marked is not None and np.any(s.marked):
        painter.setPen(QPen(_qcolor(OUTLIER_COLOR), 0.35 * mm))
        r = 1.1 * mm
        ok = np.asarray(s.marked, bool) & np.isfinite(px) & np.isfinite(py)
        for a, b in zip(px[ok], py[ok]):
            painter.drawLine(QLineF(a - r, b - r, a + r, b + r))
            painter.drawLine(QLineF(a - r, b + r, a + r, b - r))


def _legend_swatch(painter: Any, box: Any, s: Series, mm: float) -> None:
    from PySide6.QtCore import QLineF, QPointF, QRectF, Qt
    from PySide6.QtGui import QPen

    cy = box.center().y()
    if s.band_low is not None:
        painter.setPen(Qt.PenStyle.NoPen)
        painter.setBrush(_qcolor(s.color, 55))
        painter.drawRect(QRectF(box.left(), cy - 1.2 * mm, box.width(), 2.4 * mm))
    if "line" in s.style:
        pen = QPen(_qcolor(s.color), 0.35 * mm)
        if s.dashed:
            pen.setDashPattern([4.0, 2.5])
        painter.setPen(pen)
        painter.drawLine(QLineF(box.left(), cy, box.right(), cy))
    if "markers" in s.style:
        painter.setPen(QPen(_qcolor(s.color), 0.2 * mm))
        painter.setBrush(_qcolor(s.color, 170))
        painter.drawEllipse(QPointF(box.center().x(), cy), 0.6 * mm, 0.6 * mm)
    painter.setBrush(Qt.BrushStyle.NoBrush)
