"""The verdict rows of any session: a line's (:mod:`lps_gui.report.pages.verdict`) or a plane's per-axis and squareness
rows (:func:`lps_gui.report.pages.planar.planar_verdicts`).

One entry for page 1, the GUI, results.json and summary.csv, so they read one list; a module of its own because
the planar rows are built from the line rows (the two modules must not import each other).
"""
from __future__ import annotations

from typing import Any

from lps_gui.io.results.model import Results, as_results
from lps_gui.report.pages.planar import planar_verdicts
from lps_gui.report.pages.verdict import Verdict, line_verdicts


def session_verdicts(results: Results | dict[str, Any], spec: dict[str, Any] | None) -> list[Verdict]:
    """The verdict rows of ``results`` against a stage specification (empty without one)."""
    if not spec:
        return []
    results = as_results(results)
    return planar_verdicts(results, spec) if results.planar else line_verdicts(results, spec)
