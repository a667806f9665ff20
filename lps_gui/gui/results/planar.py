"""What the results panel shows for a planar (XY) session: the report's own rows and table (SPEC 10).

The figures tabs already come from :func:`lps_gui.report.figures.plots.figures_from_results`
(a planar session's are the planar section there); the
figures table and the per-position table come from
:mod:`lps_gui.report.pages.planar`, so the screen and the PDF show the same numbers.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

from lps_gui.io.results.model import Results


def planar_table_rows(results: Results) -> list[tuple[str, str, str]] | None:
    """(figure, value, U (k = 2), unit and note) rows of a planar session's figures and truth check; None for one axis."""
    if not results.planar or results.figures.planar is None:
        return None
    from lps_gui.report.pages.planar import planar_summary_rows, planar_truth_rows

    rows = planar_summary_rows(results)
    if results.truth_comparison and results.truth_comparison.position_rms_error_um is not None:
        rows += [replace(r, name=f"Truth: {r.name}") for r in planar_truth_rows(results)]
    return [(r.name, r.text(), _u_text(r), f"{r.unit}  {r.note}".strip()) for r in rows]


def _u_text(row: Any) -> str:
    u = getattr(row, "u_text", None)
    return u() if callable(u) else ""


def position_table_for(results: Results) -> tuple[list[str], list[list[str]]]:
    """Header and rows of the per-position table, planar or single-axis."""
    if results.planar:
        from lps_gui.report.pages.planar import planar_position_table

        return planar_position_table(results)[:2]
    from lps_gui.report.pages.summary import position_table

    return position_table(results)[:2]
