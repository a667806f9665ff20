"""The results tabs of the sections only some sessions have: error motions (SPEC 14) and an ASME B5.64 test.

The figures are the report's own :class:`FigureSpec` definitions
(:func:`lps_gui.report.pages.error_motions.error_motion_figures`,
:func:`lps_gui.report.figures.asme.test_figures`) and the tables its rows, so
screen and paper agree; a session without the section gets no tab.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import pyqtgraph as pg
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QLabel, QSplitter, QVBoxLayout, QWidget

from lps_gui.gui.results.plot_adapter import ReadableAxis
from lps_gui.gui.widgets import TextTable
from lps_gui.io.results.model import Results
from lps_gui.report.figures.spec import FigureSpec

MOTION_HEADER = ["motion", "what", "p-v", "noise p-v", "median \u03c3", "unit", ""]
UNRESOLVED_ROW = "#888888"  # as the report's table: not resolved reads grey, never as a finding


@dataclass
class SectionContent:
    """What one section tab shows: its figures, a few lines of findings, one table."""

    title: str
    figures: list[FigureSpec]
    lines: list[str] = field(default_factory=list)
    header: list[str] = field(default_factory=list)
    rows: list[list[str]] = field(default_factory=list)
    colors: list[str | None] = field(default_factory=list)


def error_motions_content(results: Results) -> SectionContent | None:
    """The "Error motions" tab: angular and linear figures (and the tool point), the table of motions."""
    from lps_gui.report.pages.error_motions import error_motion_figures, error_motion_rows

    figures = error_motion_figures(results)
    if not figures:
        return None
    rows = error_motion_rows(results)
    unresolved = [r[0] for r in rows if r[-1] != "resolved"]
    lines = [f"Not resolved (grey): {', '.join(unresolved)}." if unresolved else "Every error motion is resolved."]
    tool = results.error_motions.tool_point
    if tool:
        lines.append(f"Tool point {list(tool.offset_mm)} mm ({tool.frame} frame): the angular error motions add up "
                     f"to {tool.max_abs_abbe_um:.3g} \u00b5m (max |Abbe term|) to the positioning error there.")
    return SectionContent("Error motions", figures, lines, MOTION_HEADER, rows,
                          [None if r[-1] == "resolved" else UNRESOLVED_ROW for r in rows])


def asme_content(results: Results) -> SectionContent | None:
    """The "ASME B5.64" tab, for a session that ran the incremental-step or the settling test."""
    from lps_gui.report.figures.asme import test_figures
    from lps_gui.report.pages.asme import TUR_HEADER, finding_lines, section, tur_cells

    s = section(results)
    if not s.has_test:
        return None
    rows = tur_cells(s.test_uncertainty_ratio)
    lines = finding_lines(results) + ([] if rows else ["No tolerance in session.json stage_spec: no test "
                                                       "uncertainty ratio is stated."])
    return SectionContent("ASME B5.64", test_figures(s), lines, TUR_HEADER, rows)


SECTIONS: tuple[Callable[[Results], SectionContent | None], ...] = (error_motions_content, asme_content)


def section_contents(results: Results) -> list[SectionContent]:
    """The section tabs these results have, in tab order."""
    return [c for c in (make(results) for make in SECTIONS) if c is not None]


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
