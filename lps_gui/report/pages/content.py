"""What a result section shows on screen: its figures, a few lines of findings, one table; plain data.

The section's module builds it from the results (the report's own figures and rows, so screen and
paper agree) and the GUI draws it (``gui/results/section_tabs.SectionPage``). No Qt here.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from lps_gui.report.figures.spec import FigureSpec


@dataclass
class SectionContent:
    """What one section tab shows: its figures, a few lines of findings, one table (or a folder's pictures)."""

    title: str
    figures: list[FigureSpec]
    lines: list[str] = field(default_factory=list)
    header: list[str] = field(default_factory=list)
    rows: list[list[str]] = field(default_factory=list)
    colors: list[str | None] = field(default_factory=list)
    pictures: list[tuple[str, str]] = field(default_factory=list)  # (image file, caption): a folder's pictures
