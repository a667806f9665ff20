"""The result sections only some sessions have, one line each: what the PDF paints and the GUI shows of them.

A section is one module (report/pages/...: whether the results have it, its figures, its PDF page
painter, its GUI tab's content as plain data) plus one line in :data:`SECTIONS`. The line report
(``report/pdf/document.py``) paints the sections present at each of its places, and the results panel
(``gui/results/section_tabs.py``) adds a tab for each section with a tab, in this order; neither names
a section. A section placed :data:`REPORT` (a planar session's) is a report of its own: the PDF paints
its pages instead of the line report's and the results panel shows its figures and positions tables
instead of the line's (:func:`own_report`, :func:`figure_table`, :func:`position_table`). A document of its
own in a folder (a light field) is a :data:`FOLDER_SECTIONS` line: its tab's content and its PDF. No Qt here.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from lps_gui.io.results.model import Results
from lps_gui.report.figures.plots import planar_figures_from_results
from lps_gui.report.figures.spec import FigureSpec
from lps_gui.report.pages import asme, error_motions, lightfield, planar, targets
from lps_gui.report.pages.content import SectionContent
from lps_gui.report.pdf import lightfield as lightfield_pdf

# where in the line report's page flow a section's pages go
AFTER_FIGURES = "after the measured figures"  # behind page 2 (figures, ISO 230-2 table), before the budget
AFTER_PLOTS = "after the plots"  # behind the plots, before the outlier views
REPORT = "the whole report"  # a report of its own: its pages instead of the line report's


@dataclass(frozen=True)
class ResultSection:
    """One section of results.json the report and the GUI show when a session has it."""

    name: str  # its results.json key
    has: Callable[[Results], bool]  # whether these results have it
    figures: Callable[[Results], list[FigureSpec]]  # its figures: the tab draws these, the PDF painter the same
    place: str  # where the line report paints it: AFTER_FIGURES or AFTER_PLOTS; REPORT: instead of it
    paint: Callable[[Any, Results, float], Any] | None = None  # its PDF pages: (page flow, results, figure height mm)
    tab: Callable[[Results, list[FigureSpec]], SectionContent] | None = None  # its GUI tab, given its figures
    # place REPORT: every page, (page flow, session.json, results, identification rows, figure height mm)
    report: Callable[[Any, Mapping[str, Any], Results, list[tuple[str, str]], float], Any] | None = None
    table: Callable[[Results], list[tuple[str, str, str, str]] | None] | None = None  # the panel's figures table
    positions: Callable[[Results], tuple[list[str], list[list[str]]]] | None = None  # the per-position table


SECTIONS: tuple[ResultSection, ...] = (
    ResultSection("targets", targets.has_targets, lambda r: [], AFTER_FIGURES, targets.targets_section),
    ResultSection("error_motions", error_motions.has_error_motions, error_motions.error_motion_figures, AFTER_PLOTS,
                  error_motions.paint_error_motions_page, error_motions.error_motions_content),
    ResultSection("asme_b5_64", asme.has_test, asme.section_figures, AFTER_FIGURES, asme.test_pages,
                  asme.asme_content),
    ResultSection("planar", planar.has_planar, planar_figures_from_results, REPORT, report=planar.paint_planar_report,
                  table=planar.planar_panel_rows, positions=planar.planar_positions),
)


@dataclass(frozen=True)
class FolderSection:
    """A document of its own in a folder, not a section of results.json (a light field): the file that marks such
    a folder, the results dock's tab of it, its PDF."""

    name: str
    title: str  # the results dock's tab
    has: Callable[[Path], bool]  # whether a folder holds one
    content: Callable[[Path], SectionContent]  # its tab's content (a one-line InputError for a folder without one)
    report_file: str  # its PDF's file name in the folder
    write_report: Callable[..., int]  # its PDF, from what its pipeline computed


FOLDER_SECTIONS: tuple[FolderSection, ...] = (
    FolderSection("lightfield", "Light field", lightfield.has_lightfield, lightfield.lightfield_content,
                  lightfield_pdf.REPORT_FILE, lightfield_pdf.write_lightfield_report),
)


def folder_section(name: str) -> FolderSection:
    """The folder section called ``name`` (a KeyError names a section no line registers)."""
    return {s.name: s for s in FOLDER_SECTIONS}[name]


def present(results: Results, place: str | None = None) -> list[ResultSection]:
    """The sections these results have (at ``place`` of the line report, or anywhere), in registry order."""
    return [s for s in SECTIONS if (place is None or s.place == place) and s.has(results)]


def paint_sections(flow: Any, results: Results, place: str, figure_height_mm: float) -> None:
    """Paint the sections these results have at ``place`` of the line report."""
    for s in present(results, place):
        if s.paint is not None:
            s.paint(flow, results, figure_height_mm)


def tab_contents(results: Results) -> list[SectionContent]:
    """The GUI's section tabs these results have, in tab order."""
    return [s.tab(results, s.figures(results)) for s in present(results) if s.tab is not None]


def own_report(results: Results) -> ResultSection | None:
    """The section whose pages are the whole report of these results (a planar session's); None: the line report."""
    return next(iter(present(results, REPORT)), None)


def figure_table(results: Results) -> list[tuple[str, str, str, str]] | None:
    """The results panel's figures table of a section with a report of its own; None: the line's summary rows."""
    own = own_report(results)
    return own.table(results) if own is not None and own.table is not None else None


def position_table(results: Results) -> tuple[list[str], list[list[str]]]:
    """Header and rows of the per-position table the report prints: its own report's, else the line report's."""
    own = own_report(results)
    if own is not None and own.positions is not None:
        return own.positions(results)
    from lps_gui.report.pages.summary import position_table as line_positions

    return line_positions(results)[:2]
