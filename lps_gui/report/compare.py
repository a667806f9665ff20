"""As-found / as-left report: two estimated sessions of one stage, before and after compensation.

Deviation curves of both overlaid (mean per target and direction), the ISO
230-2 figures side by side with the improvement factor, and for simulated
sessions the true E as well. The figure is a plain :class:`FigureSpec` (no
Qt); the PDF uses the report's :class:`PdfFlow`, Qt imported inside.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from lps_gui.errors import InputError
from lps_gui.report.figure_spec import BACKWARD_COLOR, FORWARD_COLOR, FigureSpec, Series
from lps_gui.report.figures import _by_direction, _dir_label, per_target_stats, position_columns
from lps_gui.report.summary import fmt

COMPARE_FILE = "as-found-as-left.pdf"
AFTER_COLORS = {"+": "#2a9d3c", "-": "#a8326e"}
ISO_ROWS = (("E_um", "positioning accuracy error E (bidirectional)"), ("E_up_um", "E forward"), ("E_down_um", "E backward"),
            ("M_um", "mean positioning error M"), ("B_um", "reversal error B"), ("A_um", "accuracy A"),
            ("R_um", "repeatability R"))


def comparison_figure(before: dict[str, Any], after: dict[str, Any]) -> FigureSpec:
    """Mean deviation per target and direction, as found (blue/orange) and as left (green/purple)."""
    series = []
    for results, tag, dashed in ((before, "as found", True), (after, "as left", False)):
        cols = position_columns(results)
        for d, sel in _by_direction(cols):
            t, mean, _, _ = per_target_stats(cols["target_mm"][sel], cols["deviation_um"][sel], ~cols["outlier"][sel])
            color = (FORWARD_COLOR if d == "+" else BACKWARD_COLOR) if dashed else AFTER_COLORS[d]
            series.append(Series(t, mean, f"{tag} {_dir_label(d)}", "line+markers", color, dashed=dashed))
    return FigureSpec("compare", "Deviation as found and as left", "target position [mm]", "deviation [\u00b5m]", series,
                      "mean over runs per target and direction")


def session_E_um(results: dict[str, Any], key: str = "deviation_um") -> float:
    """E (ISO 230-2, um) of one deviation column of results.json: measured, or the simulator's truth."""
    from lps_gui.core.iso230 import figures_for_session

    rows = [r for r in results.get("positions", []) if r.get(key) is not None and not r.get("outlier")]
    if not rows:
        raise InputError(f"results.json has no {key}; estimate a simulated session")
    t = np.array([r["target_mm"] for r in rows])
    d = np.array([1.0 if r["direction"] == "+" else -1.0 for r in rows])
    run = np.array([r["run"] for r in rows])
    iso = figures_for_session(t, d, run, np.array([r[key] for r in rows], dtype=float))["iso230_2"]
    if not iso or iso.get("E_um") is None:
        raise InputError("E needs both directions or two runs; capture a bidirectional session")
    return float(iso["E_um"])


def true_E_um(results: dict[str, Any]) -> float:
    return session_E_um(results, "truth_deviation_um")


def _iso(results: dict[str, Any]) -> dict[str, Any]:
    return (results.get("figures") or {}).get("iso230_2") or {}


def comparison_rows(before: dict[str, Any], after: dict[str, Any]) -> list[list[str]]:
    """[name, as found um, as left um, improvement factor] per ISO 230-2 figure both sessions have."""
    rows = []
    b_iso, a_iso = _iso(before), _iso(after)
    for key, name in ISO_ROWS:
        b, a = b_iso.get(key), a_iso.get(key)
        if b is None and a is None:
            continue
        factor = b / a if b is not None and a not in (None, 0) else None
        rows.append([name, fmt(b), fmt(a), "" if factor is None else f"{factor:.1f}x"])
    return rows


def true_E_rows(before: dict[str, Any], after: dict[str, Any]) -> list[list[str]]:
    """The simulator's true E before and after, when both sessions are simulated."""
    try:
        b, a = true_E_um(before), true_E_um(after)
    except InputError:
        return []
    return [["true E (simulator)", fmt(b), fmt(a), f"{b / a:.1f}x" if a else ""]]


def write_comparison(before_dir: Path | str, after_dir: Path | str, out: Path | str | None = None,
                     clipped: list[str] | None = None) -> Path:
    """Write the as-found / as-left PDF (default AFTER/as-found-as-left.pdf); returns its path.

    ``clipped``, when given, receives every string that does not fit its box (the layout check).
    """
    from lps_gui import __version__
    from lps_gui.report.layout import ensure_gui_app, pdf_file
    from lps_gui.report.pdf import load_results

    before, after = load_results(Path(before_dir)), load_results(Path(after_dir))
    out = Path(out) if out is not None else Path(after_dir) / COMPARE_FILE
    if not out.parent.is_dir():
        raise InputError(f"{out.parent}: folder not found; create it or choose another --out")
    rows = comparison_rows(before, after) + true_E_rows(before, after)
    if not rows:
        raise InputError("as-found/as-left: neither session has ISO 230-2 figures; measure both directions or two runs")
    ensure_gui_app()
    with pdf_file(out, "As found / as left", f"lps-calib {__version__} \u00b7 {Path(before_dir).name} -> {Path(after_dir).name}") as flow:
        flow.heading("Stage compensation: as found / as left", 15)
        flow.paragraph(f"as found: {before.get('inputs', {}).get('session', before_dir)}  ({before.get('created', '')})")
        flow.paragraph(f"as left: {after.get('inputs', {}).get('session', after_dir)}  ({after.get('created', '')})")
        flow.space(2)
        flow.heading("ISO 230-2 figures [\u00b5m]", 11)
        flow.table(["figure", "as found", "as left", "improvement"], rows, [80, 30, 30, 30])
        flow.space(3)
        flow.figure(comparison_figure(before, after), 110.0)
        flow.paragraph("Improvement = as found / as left. The as-left E cannot fall below the measurement's own noise: "
                       "the table's entries carry that noise into the correction.")
    if clipped is not None:
        clipped.extend(flow.log.clipped)
    return out


def improvement_factor(before: dict[str, Any], after: dict[str, Any], key: str = "E_um") -> float | None:
    b, a = _iso(before).get(key), _iso(after).get(key)
    return None if b is None or not a else float(b) / float(a)

