"""The environment and the uncertainty budget as report rows (results.json ``environment``, ``uncertainty``).

No Qt here: plain strings for :class:`lps_gui.report.pdf.layout.PdfFlow` tables.
"""
from __future__ import annotations

from typing import Any

from lps_gui.io.results.model import Results, as_results
from lps_gui.io.results.sections import EnvironmentRecord
from lps_gui.report.pages.summary import DASH, fmt

NOT_RECORDED = "not recorded"
BUDGET_HEADER = ["source", "type", "u(x\u1d62)", "unit", "c\u1d62", "unit of c\u1d62", "u\u1d62(y) [\u00b5m]"]
BUDGET_WIDTHS = [44.0, 11.0, 20.0, 14.0, 20.0, 24.0, 24.0]


def environment_rows(results: Results | dict[str, Any]) -> list[tuple[str, str]]:
    """(label, text): temperatures, expansion coefficients, the correction applied, notes."""
    env = as_results(results).environment or EnvironmentRecord()

    def value(key: str, unit: str) -> str:
        v = env.number(key)
        return NOT_RECORDED if v is None else f"{fmt(v, 4)} {unit}"

    rows = [("Board temperature", value("board_temperature_c", "\u00b0C")),
            ("Board expansion coefficient", value("board_cte_ppm_per_k", "ppm/K")),
            ("Board square size u (certificate)", value("square_mm_uncertainty_um", "\u00b5m")),
            ("Stage temperature", value("stage_temperature_c", "\u00b0C")),
            ("Stage expansion coefficient", value("stage_cte_ppm_per_k", "ppm/K"))]
    corr = env.board_scale_correction_ppm
    if corr:
        rows.append(("Thermal correction applied", f"{corr:+.1f} ppm on the length scale (board at 20 \u00b0C "
                     f"{fmt(env.square_mm_nominal, 5)} mm, used {fmt(env.square_mm_used, 7)} mm)"))
    else:
        rows.append(("Thermal correction applied", f"none: {_why_no_correction(env)}"))
    if env.notes:
        rows.append(("Notes", str(env.notes)))
    return rows


def _why_no_correction(env: EnvironmentRecord) -> str:
    """Which of the three cases left the length scale uncorrected."""
    t, a = env.board_temperature_c, env.board_cte_ppm_per_k
    if t is None and a is None:
        return "board temperature and expansion coefficient not recorded"
    if t is None:
        return "board temperature not recorded"
    if a is None:
        return "board expansion coefficient not recorded"
    return "the board was at 20 \u00b0C" if abs(t - 20.0) < 1e-9 else "the expansion coefficient is 0"


def budget_rows(results: Results | dict[str, Any]) -> list[list[str]]:
    """One row per source of ``uncertainty.budget``; a dash where a source was not recorded."""
    unc = as_results(results).uncertainty
    out = []
    for r in unc.budget if unc else ():
        unit = str(r.unit or "")
        sens_unit = f"\u00b5m/({unit})" if "/" in unit else f"\u00b5m/{unit}" if unit and unit != "\u00b5m" else "1"
        sensitivity, contribution = r.number("sensitivity"), r.number("contribution_um")
        out.append([str(r.source), str(r.type), fmt(r.number("value")), unit,
                    fmt(sensitivity), sens_unit if sensitivity is not None else DASH,
                    fmt(contribution) if contribution is not None else NOT_RECORDED])
    return out


def budget_notes(results: Results | dict[str, Any]) -> list[str]:
    """"source: note" lines under the budget table, and the combination."""
    unc = as_results(results).uncertainty
    if unc is None:
        return []
    notes = [f"{r.source}: {r.note}" for r in unc.budget if r.note]
    if unc.expanded_k2_um is not None:
        notes.append(f"Combined standard uncertainty u_c = {fmt(unc.combined_standard_um)} \u00b5m "
                     f"(root sum of squares, sources uncorrelated); expanded U = k u_c = "
                     f"{fmt(unc.expanded_k2_um)} \u00b5m with k = {fmt(unc.coverage_factor)} "
                     f"(about 95 %), for {unc.get('applies_to', 'a displacement')} "
                     f"({fmt(unc.travel_mm, 4)} mm).")
    if unc.not_in_u:
        notes.append("Not in U (not recorded): " + ", ".join(unc.not_in_u) + ". Record them in session.json "
                     "\"environment\" (or with lps capture --board-temp ...) for a complete budget.")
    return notes
