"""Draw the shared plot definitions (lps_gui.report.figures.plots) with pyqtgraph.

The PDF paints the same :class:`FigureSpec` objects with QPainter, so the
screen and the report cannot disagree; this module only maps styles.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QEvent, QObject, Qt

from lps_gui.report.figures.spec import OUTLIER_COLOR, FigureSpec, Series

BAND_ALPHA = 50  # of 255: a 2-sigma band reads as a tint behind the curve
MARKER_SIZE_PX = 6
LEGEND_ROW = 4  # PlotItem layout rows: 0 title, 1 top axis, 2 view, 3 bottom axis; the legend goes under
COMPACT_LEGEND_AT = 7  # series: from here the legend names each colour once and each line style once
LEGEND_ROW_CHARS = 100  # a legend row longer than this widens the plot beyond a half-screen panel
STYLE_GREY = "#555555"
PLOT_DATA_MIN_PX = 90  # the least height a plot's data area gets under its title and above its legend


class ReadableAxis(pg.AxisItem):
    """An axis whose log-scale ticks read as plain numbers (2, 5, 10, 20 mm), not "2·10¹"."""

    def logTickStrings(self, values, scale, spacing):  # noqa: N802 (pyqtgraph's name)
        out = []
        for v in 10.0 ** (np.asarray(values, float)) * scale:
            mantissa = v / 10.0 ** np.floor(np.log10(v)) if v > 0 else 0.0
            out.append(f"{v:.4g}" if round(mantissa, 6) in (1.0, 2.0, 5.0) else "")  # 1-2-5: no crowding
        return out


def component_name(label: str) -> str:
    """"roll forward ↑" / "truth roll" -> "roll": what a colour stands for in a compact legend."""
    return re.sub(r"\s*\b(forward|backward)\b\s*[\u2191\u2193]?", "", label.replace("truth ", "")).strip()


def wants_compact_legend(fig: FigureSpec) -> bool:
    """Many series sharing colours (components drawn per direction and as truth): name each colour once.

    Series of colours of their own (the settling test's moves) keep their labels.
    """
    colors = {s.color for s in fig.series}
    return len(fig.series) >= COMPACT_LEGEND_AT and 2 * len(colors) <= len(fig.series)


def compact_legend(legend: pg.LegendItem, fig: FigureSpec) -> None:
    """One entry per colour (the component) and one per line style (direction, truth): 12 entries become 7."""
    seen: dict[str, str] = {}
    for s in fig.series:
        seen.setdefault(s.color, component_name(s.label))
    for color, name in seen.items():
        legend.addItem(pg.PlotDataItem([0, 1], [0, 0], pen=pg.mkPen(color, width=4)), name)
    styles = [("line" in s.style and not s.dashed, "markers" in s.style and "line" not in s.style, s.dashed)
              for s in fig.series]
    if any(st[0] for st in styles):
        legend.addItem(pg.PlotDataItem([0, 1], [0, 0], pen=pg.mkPen(STYLE_GREY, width=2)), "forward \u2191 (line, \u00b12\u03c3 band)")
    if any(st[1] for st in styles):
        legend.addItem(pg.PlotDataItem([0], [0], pen=None, symbol="o", symbolSize=MARKER_SIZE_PX,
                                       symbolBrush=pg.mkBrush(STYLE_GREY), symbolPen=None), "backward \u2193")
    if any(st[2] for st in styles):
        legend.addItem(pg.PlotDataItem([0, 1], [0, 0], pen=pg.mkPen(STYLE_GREY, width=2, style=Qt.PenStyle.DashLine)),
                       "truth")


@dataclass
class DrawnFigure:
    """What was drawn, so clicks and tests can reach the data."""

    spec: FigureSpec
    items: list[pg.PlotDataItem] = field(default_factory=list)  # one per series, in series order
    outliers: list[pg.PlotDataItem] = field(default_factory=list)
    bands: list[pg.FillBetweenItem] = field(default_factory=list)
    inlier_y: list[np.ndarray] = field(default_factory=list)  # values that set the y range

    def point_count(self, label_prefix: str = "") -> int:
        """Finite points in the series whose label starts with ``label_prefix``."""
        n = 0
        for s, item in zip(self.spec.series, self.items):
            if s.label.startswith(label_prefix):
                x, _ = item.getData()
                n += 0 if x is None else len(x)
        return n


def _rgba(color: str, alpha: int) -> tuple[int, int, int, int]:
    c = pg.mkColor(color)
    return (c.red(), c.green(), c.blue(), alpha)


def draw_series(plot: pg.PlotItem, s: Series, drawn: DrawnFigure, named: bool = True) -> None:
    """Add one series (band first, then curve, then outlier crosses) to ``plot``; ``named``: in the legend."""
    raw, s = s, s.finite()
    gaps = raw is not s and raw.style == "line" and raw.band_low is None  # a NaN breaks a plain line (two limits)
    keep = ~np.asarray(s.marked, bool) if s.marked is not None else np.ones(s.y.shape, bool)
    drawn.inlier_y.append(s.y[keep])
    if s.band_low is not None and s.band_high is not None:
        drawn.inlier_y += [s.band_low[keep], s.band_high[keep]]
    if s.band_low is not None and s.band_high is not None and s.x.size > 1:
        order = np.argsort(s.x, kind="stable")
        lo = pg.PlotCurveItem(s.x[order], s.band_low[order])  # curves (not PlotDataItem): the fill needs a path
        hi = pg.PlotCurveItem(s.x[order], s.band_high[order])
        band = pg.FillBetweenItem(lo, hi, brush=pg.mkBrush(_rgba(s.color, BAND_ALPHA)))
        plot.addItem(band)
        drawn.bands.append(band)
    pen = None
    if "line" in s.style:
        pen = pg.mkPen(s.color, width=2, style=Qt.PenStyle.DashLine if s.dashed else Qt.PenStyle.SolidLine)
    kwargs: dict = {"pen": pen, "name": s.label if named else None}
    if "markers" in s.style:
        kwargs.update(symbol="o", symbolSize=MARKER_SIZE_PX, symbolBrush=pg.mkBrush(s.color), symbolPen=None)
    item = pg.PlotDataItem(raw.x, raw.y, connect="finite", **kwargs) if gaps else pg.PlotDataItem(s.x, s.y, **kwargs)
    plot.addItem(item)
    drawn.items.append(item)
    if s.marked is not None and np.any(s.marked):
        m = np.asarray(s.marked, bool)
        cross = pg.PlotDataItem(s.x[m], s.y[m], pen=None, symbol="x", symbolSize=14,
                                symbolBrush=pg.mkBrush(OUTLIER_COLOR), symbolPen=pg.mkPen(OUTLIER_COLOR, width=2),
                                name=s.marked_label)
        plot.addItem(cross)
        drawn.outliers.append(cross)


def legend_columns(fig: FigureSpec, compact: bool) -> int:
    """Columns of the legend: more for many series, fewer for long labels ("... not resolved (noise p-v ...)")."""
    columns = 4 if compact else (3 if len(fig.series) > 4 else 2)
    longest = max((len(s.label) for s in fig.series), default=0)
    return columns if compact else max(1, min(columns, LEGEND_ROW_CHARS // max(longest, 1)))


class _LegendFit(QObject):
    """Event filter on a plot widget: a resize re-flows its legend (:func:`fit_legend`)."""

    def eventFilter(self, obj: QObject, event: QEvent) -> bool:
        if event.type() == QEvent.Type.Resize and isinstance(obj, pg.PlotWidget):
            fit_legend(obj.getPlotItem())
        return False


_LEGEND_FIT = _LegendFit()


def fit_legend(plot: pg.PlotItem) -> None:
    """As many legend columns as the plot's width holds (at most the figure's), the title wrapped to it: a legend
    or title wider than the plot made its scene wider than the view, and the right side was cut off ("trut", "yav")."""
    legend, view = plot.legend, plot.getViewWidget()
    if view is None:
        return
    room = view.width() - plot.getAxis("left").width() - plot.getAxis("right").width() - 24  # the title's column
    title = plot.titleLabel.item
    title.setTextWidth(-1)
    if title.boundingRect().width() > room:
        title.setTextWidth(max(60, room))  # wraps onto a second line
    plot.titleLabel.updateMin()
    if legend is None or not legend.items:
        return
    wanted = getattr(legend, "wanted_columns", legend.columnCount)
    for sample, label in legend.items:  # a label longer than the room wraps ("EYX not resolved (noise p-v ...)")
        label.item.setTextWidth(-1)
        if sample.boundingRect().width() + label.item.boundingRect().width() + 16 > room:
            label.item.setTextWidth(max(60, room - sample.boundingRect().width() - 16))  # the legend's own margins
        label.updateMin()
    entry = max(sample.boundingRect().width() + label.item.boundingRect().width() for sample, label in legend.items)
    columns = int(max(1, min(wanted, room // (entry + 12))))
    if columns != legend.columnCount:
        legend.setColumnCount(columns)
    # the title, axis and legend take what they need; the data get at least PLOT_DATA_MIN_PX more: a stack of
    # plots taller than its tab then scrolls (results_panel.tab_holder) instead of squeezing the data away
    other = plot.titleLabel.minimumHeight() + legend.minimumHeight() + plot.getAxis("bottom").height()
    view.setMinimumHeight(int(other + PLOT_DATA_MIN_PX))


def figure_steps(plot: pg.PlotItem, fig: FigureSpec) -> tuple[DrawnFigure, list[Callable[[], None]]]:
    """Drawing ``fig`` into ``plot`` as small steps (set-up, one per series, finish).

    Each step takes a few milliseconds, so a caller can run them in separate
    event-loop turns and the window never freezes while results come up.
    """
    drawn = DrawnFigure(fig)
    compact = wants_compact_legend(fig)

    def setup() -> None:
        plot.disableAutoRange()  # no range update per added item
        if plot.legend is not None:
            plot.legend.clear()  # first: removing items one by one would resize the legend each time
        plot.clear()
        if plot.legend is None:
            # below the axes, in the plot's own layout: the legend never covers data
            plot.legend = pg.LegendItem(labelTextSize="8pt", labelTextColor="#202020",
                                        brush=pg.mkBrush(255, 255, 255, 0), pen=pg.mkPen(None))
            plot.layout.addItem(plot.legend, LEGEND_ROW, 1)
        plot.legend.wanted_columns = legend_columns(fig, compact)
        plot.legend.setColumnCount(plot.legend.wanted_columns)
        view = plot.getViewWidget()
        if view is not None and not view.property("_legend_fit"):
            view.installEventFilter(_LEGEND_FIT)
            view.setProperty("_legend_fit", True)
        plot.setTitle(fig.title, color="#202020", size="11pt")
        plot.setLabel("bottom", fig.x_label)
        plot.setLabel("left", fig.y_label)
        for axis in ("bottom", "left"):
            plot.getAxis(axis).enableAutoSIPrefix(False)  # the unit is in the label: no hidden "(x0.001)"
        plot.showGrid(x=True, y=True, alpha=0.25)
        plot.setLogMode(x=fig.x_log, y=False)

    steps: list[Callable[[], None]] = [setup]
    steps += [lambda s=s: draw_series(plot, s, drawn, named=not compact) for s in fig.series]
    if compact:
        steps.append(lambda: compact_legend(plot.legend, fig))
    steps.append(lambda: fit_range(plot, drawn))
    steps.append(lambda: fit_legend(plot))
    return drawn, steps


def fit_range(plot: pg.PlotItem, drawn: DrawnFigure, pad_fraction: float = 0.08) -> None:
    """Auto range, except that outliers do not set the y range: they sit at its edge.

    A replaced image can be off by centimetres while the stage errors are
    micrometres; scaling the axis to the outlier would flatten every curve.
    """
    plot.enableAutoRange()
    if not drawn.outliers:
        return
    y = np.concatenate([v[np.isfinite(v)] for v in drawn.inlier_y] + [np.zeros(0)])
    if y.size == 0:
        return
    lo, hi = float(y.min()), float(y.max())
    pad = pad_fraction * (hi - lo) or 1.0
    for cross in drawn.outliers:
        x, yo = cross.getData()
        if yo is not None and len(yo):
            cross.setData(x, np.clip(yo, lo - 0.5 * pad, hi + 0.5 * pad))
    plot.enableAutoRange(axis="x")
    plot.setYRange(lo - pad, hi + pad, padding=0.0)
