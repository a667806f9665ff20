"""The results tabs of the sections only some sessions have (error motions, an ASME B5.64 test, ...).

Which sections there are and what their tabs show is the report's registry
(:mod:`lps_gui.report.registry`: the report's own figures and rows, so screen and
paper agree); here only how a tab draws it. A session without the section gets no tab.
"""
from __future__ import annotations

import pyqtgraph as pg
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QLabel, QSplitter, QVBoxLayout, QWidget

from lps_gui.gui.results.plot_adapter import ReadableAxis
from lps_gui.gui.widgets import TextTable
from lps_gui.report.pages.content import SectionContent


class SectionPage(QSplitter):
    """One section tab: its figures stacked, then the findings and the table."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(Qt.Orientation.Vertical, parent)
        self.plots: dict[str, pg.PlotWidget] = {}
        self.lines = QLabel()
        self.lines.setWordWrap(True)
        self.lines.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.table = TextTable(numeric=range(2, 5))
        bottom = QWidget()
        lay = QVBoxLayout(bottom)
        lay.setContentsMargins(0, 4, 0, 0)
        lay.addWidget(self.lines)
        lay.addWidget(self.table, 1)
        self.bottom = bottom
        self.addWidget(bottom)

    def set_content(self, content: SectionContent) -> None:
        """The findings and the table now; the plots come one by one (:meth:`plot_for`)."""
        for plot in self.plots.values():
            plot.setVisible(False)
        self.lines.setText("\n".join(content.lines))
        self.lines.setVisible(bool(content.lines))
        self.table.set_rows(content.header, content.rows, content.colors)
        self.table.setVisible(bool(content.rows))
        self.setSizes([300] * len(content.figures) + [160])  # the figures get the room; the table below them

    def plot_for(self, index: int, key: str) -> pg.PlotWidget:
        """The plot of figure ``key`` at place ``index`` (built on first use, reused by later results)."""
        plot = self.plots.get(key)
        if plot is None:
            plot = self.plots[key] = pg.PlotWidget(background="w", axisItems={"bottom": ReadableAxis("bottom")})
        self.insertWidget(index, plot)
        plot.setVisible(True)
        return plot


def tab_tip(content: SectionContent) -> str:
    """The tab's tooltip: how its figures were made."""
    return "\n".join([f.notes or f.title for f in content.figures])
