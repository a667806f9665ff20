"""The targets of a row or constellation in the report (SPEC 13): one table and what it means.

Each row: the target, its marker ids, the views that saw it and that tie it to
another target, the stretch of travel it was seen over and its share of the
travel (the length its print's scale enters), the pose sigma (rotation and
position in the world frame of target 0) and its scale term of the
uncertainty budget (``target scale <id>``, the same number the budget table
lists; X / Y for a planar stage's per-axis budgets). No Qt here.
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from lps_gui.core.metrology.target_scale import SOURCE_PREFIX
from lps_gui.io.results.model import Results, as_results
from lps_gui.io.results.sections import TargetRecord
from lps_gui.report.pages.summary import DASH, fmt

TARGET_HEADER = ["target", "markers", "views", "ties", "seen over\n[mm]", "share", "\u03c3 rotation\n[\u00b5rad]",
                 "\u03c3 position\n[\u00b5m]", "scale term\nu [\u00b5m]"]
TARGET_WIDTHS = [14.0, 16.0, 11.0, 10.0, 26.0, 12.0, 33.0, 33.0, 19.0]
WORLD_FRAME = "world frame"
NOTE = ("Target 0 defines the world frame (its pose is fixed, no sigma). \u03c3 rotation: the three components of the "
        "rotation vector, \u03c3 position: of p in x, y, z of the world frame (1-sigma, corner noise). A view that sees "
        "two targets ties them; a target's print scale enters the share of the travel measured against it: its "
        "scale term is that share in squares times the print's u (\"{prefix} <id>\" in the uncertainty budget; "
        "a dash where the print's uncertainty is not stated).").format(prefix=SOURCE_PREFIX)


def _triple(values: tuple[float | None, ...], scale: float) -> str:
    if len(values) != 3 or None in values:
        return DASH
    return " / ".join(fmt(scale * v, 2) for v in values)


def _stretch(t: TargetRecord) -> str:
    if t.stretch is None:
        return "not seen"
    ends = [[fmt(v, 4) for v in end] for end in t.stretch]
    return " \u2013 ".join(e[0] if len(e) == 1 else f"({', '.join(e)})" for e in ends)  # x, or (x, y) of a plane


def target_table(results: Results | Mapping[str, Any]) -> tuple[list[str], list[list[str]], list[float]] | None:
    """The table of results.json ``targets``; None for a single-board session."""
    results = as_results(results)
    if not results.targets:
        return None
    unc = results.uncertainty
    budgets = [] if unc is None else [unc.budget] if unc.budget else [a.budget for a in unc.per_axis.values()]
    rows = []
    for j, t in enumerate(results.targets):
        terms = [b.contribution_um for budget in budgets for b in budget
                 if b.source == f"{SOURCE_PREFIX} {t.id}"]  # one per axis of a planar budget
        share = t.covered_fraction
        rows.append([
            str(t.id), DASH if t.first_marker is None else f"from {t.first_marker}",
            DASH if t.views is None else str(t.views), DASH if t.ties is None else str(t.ties), _stretch(t),
            DASH if share is None else f"{100 * share:.0f} %",
            WORLD_FRAME if j == 0 else _triple(t.rvec_sigma_rad, 1e6),
            WORLD_FRAME if j == 0 else _triple(t.p_sigma_mm, 1e3),
            " / ".join(fmt(v) for v in terms) if terms and None not in terms else DASH])
    return TARGET_HEADER, rows, TARGET_WIDTHS


def has_targets(results: Results) -> bool:
    """Whether the session measured a row or constellation of targets (SPEC 13), not one board."""
    return bool(results.targets)


def targets_section(flow: Any, results: Results | Mapping[str, Any], figure_height_mm: float = 0.0) -> bool:
    """Heading, the table of targets and its note; False (nothing painted) for a single-board session.
    (A table, no figure: ``figure_height_mm`` is the registry's common signature.)"""
    table = target_table(results)
    if table is None:
        return False
    header, rows, widths = table
    flow.heading(f"Targets ({len(rows)})", 11)
    flow.table(header, rows, widths, size_pt=7.5, row_mm=4.0, align_right_from=1, align_left=(4,))
    flow.paragraph(NOTE, size_pt=7.0, color="#555555")
    return True
