"""The result sections only some sessions have, one line each: what the PDF paints and the GUI shows of them.

A section is one module (report/pages/...: whether the results have it, its figures, its PDF page
painter, its GUI tab's content as plain data) plus one line in :data:`SECTIONS`. The line report
(``report/pdf/document.py``) paints the sections present at each of its places, and the results panel
(``gui/results/section_tabs.py``) adds a tab for each section with a tab, in this order; neither names
a section. No Qt here.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

from lps_gui.io.results.model import Results
from lps_gui.report.figures.spec import FigureSpec
from lps_gui.report.pages import asme, error_motions, targets
from lps_gui.report.pages.content import SectionContent

# where in the line report's page flow a section's pages go
AFTER_FIGURES = "after the measured figures"  # behind page 2 (figures, ISO 230-2 table), before the budget
AFTER_PLOTS = "after the plots"  # behind the plots, before the outlier views


@dataclass(frozen=True)
class ResultSection:
    """One section of results.json the report and the GUI show when a session has it."""

    name: str  # its results.json key
    has: Callable[[Results], bool]  # whether these results have it
    figures: Callable[[Results], list[FigureSpec]]  # its figures: the tab draws these, the PDF painter the same
    place: str  # where the line report paints it: AFTER_FIGURES or AFTER_PLOTS
    paint: Callable[[Any, Results, float], Any]  # its PDF pages: (page flow, results, figure height in mm)
    tab: Callable[[Results, list[FigureSpec]], SectionContent] | None = None  # its GUI tab, given its figures


SECTIONS: tuple[ResultSection, ...] = (
    ResultSection("targets", targets.has_targets, lambda r: [], AFTER_FIGURES, targets.targets_section),
    ResultSection("error_motions", error_motions.has_error_motions, error_motions.error_motion_figures, AFTER_PLOTS,
                  error_motions.paint_error_motions_page, error_motions.error_motions_content),
    ResultSection("asme_b5_64", asme.has_test, asme.section_figures, AFTER_FIGURES, asme.test_pages,
                  asme.asme_content),
)


def present(results: Results, place: str | None = None) -> list[ResultSection]:
    """The sections these results have (at ``place`` of the line report, or anywhere), in registry order."""
    return [s for s in SECTIONS if (place is None or s.place == place) and s.has(results)]


def paint_sections(flow: Any, results: Results, place: str, figure_height_mm: float) -> None:
    """Paint the sections these results have at ``place`` of the line report."""
    for s in present(results, place):
        s.paint(flow, results, figure_height_mm)


def tab_contents(results: Results) -> list[SectionContent]:
    """The GUI's section tabs these results have, in tab order."""
    return [s.tab(results, s.figures(results)) for s in present(results) if s.tab is not None]
