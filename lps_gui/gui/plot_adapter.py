"""Draw the shared plot definitions (lps_gui.report.figures) with pyqtgraph.

The PDF paints the same :class:`FigureSpec` objects with QPainter, so the
screen and the report cannot disagree; this module only maps styles.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt

from lps_gui.report.figures import OUTLIER_COLOR, FigureSpec, Series

BAND_ALPHA = 50  # of 255: a 2-sigma band reads as a tint behind the curve
MARKER_SIZE_PX = 6


@dataclass
class DrawnFigure:
    """What was drawn, so clicks and tests can reach the data."""

    spec: FigureSpec
    items: list[pg.PlotDataItem] = field(default_factory=list)  # one per series, in series order
    outliers: list[pg.PlotDataItem] = field(default_factory=list)
    bands: list[pg.FillBetweenItem] = field(default_factory=list)

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


def draw_series(plot: pg.PlotItem, s: Series, drawn: DrawnFigure) -> None:
    """Add one series (band first, then curve, then outlier crosses) to ``plot``."""
    s = s.finite()
    if s.band_low is not None and s.band_high is not None and s.x.size > 1:
        order = np.argsort(s.x, kind="stable")
        lo = pg.PlotDataItem(s.x[order], s.band_low[order], pen=None)
        hi = pg.PlotDataItem(s.x[order], s.band_high[order], pen=None)
        band = pg.FillBetweenItem(lo, hi, brush=pg.mkBrush(_rgba(s.color, BAND_ALPHA)))
        plot.addItem(band)
        drawn.bands.append(band)
    pen = None
    if "line" in s.style:
        pen = pg.mkPen(s.color, width=2, style=Qt.PenStyle.DashLine if s.dashed else Qt.PenStyle.SolidLine)
    kwargs: dict = {"pen": pen, "name": s.label}
    if "markers" in s.style:
        kwargs.update(symbol="o", symbolSize=MARKER_SIZE_PX, symbolBrush=pg.mkBrush(s.color), symbolPen=None)
    item = pg.PlotDataItem(s.x, s.y, **kwargs)
    plot.addItem(item)
    drawn.items.append(item)
    if s.marked is not None and np.any(s.marked):
        m = np.asarray(s.marked, bool)
        cross = pg.PlotDataItem(s.x[m], s.y[m], pen=None, symbol="x", symbolSize=14,
                                symbolBrush=pg.mkBrush(OUTLIER_COLOR), symbolPen=pg.mkPen(OUTLIER_COLOR, width=2),
                                name="outlier")
        plot.addItem(cross)
        drawn.outliers.append(cross)


def figure_steps(plot: pg.PlotItem, fig: FigureSpec) -> tuple[DrawnFigure, list[Callable[[], None]]]:
    """Drawing ``fig`` into ``plot`` as small steps (set-up, one per series, finish).

    Each step takes a few milliseconds, so a caller can run them in separate
    event-loop turns and the window never freezes while results come up.
    """
    drawn = DrawnFigure(fig)

    def setup() -> None:
        plot.disableAutoRange()  # no range update per added item
        if plot.legend is not None:
            plot.legend.clear()  # first: removing items one by one would resize the legend each time
        plot.clear()
        if plot.legend is None:
            plot.addLegend(offset=(-10, 10), labelTextSize="8pt")
        plot.setTitle(fig.title)
        plot.setLabel("bottom", fig.x_label)
        plot.setLabel("left", fig.y_label)
        plot.showGrid(x=True, y=True, alpha=0.25)
        plot.setLogMode(x=fig.x_log, y=False)

    steps: list[Callable[[], None]] = [setup]
    steps += [lambda s=s: draw_series(plot, s, drawn) for s in fig.series]
    steps.append(plot.enableAutoRange)
    return drawn, steps


def draw_figure(plot: pg.PlotItem, fig: FigureSpec) -> DrawnFigure:
    """Replace ``plot``'s contents by ``fig``: title, axis labels with units, legend, series."""
    drawn, steps = figure_steps(plot, fig)
    for step in steps:
        step()
    return drawn
