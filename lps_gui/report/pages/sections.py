"""Report sections both report kinds paint: verdict, figures with U, environment and budget, ISO per target.

The line report (:mod:`lps_gui.report.pdf.document`) and the planar report
(:mod:`lps_gui.report.pages.planar`) call the same painters, so a section
looks and reads the same in both; each takes a :class:`~lps_gui.report.pdf.layout.PdfFlow`
and the results dict and paints nothing when the results lack the section.
No Qt here.
"""
from __future__ import annotations

from typing import Any, Sequence

from lps_gui.io.results.model import Results, as_results
from lps_gui.report.pages import budget as B
from lps_gui.report.pages import summary as S
from lps_gui.report.pages.iso_table import iso_target_table
from lps_gui.report.pages.verdict import Verdict, overall, verdicts

FRONT_FIGURES = ("iso230_2_A", "iso230_2_R", "iso230_2_E", "iso230_2_B", "max_abs_deviation", "scale",
                 "straightness_span_1", "straightness_span_2")  # page 1 without a stage spec
NOTE_SIZE = 7.0
GREY = "#555555"


def stage_spec(meta: dict[str, Any], results: Results | dict[str, Any]) -> dict[str, Any] | None:
    """The stage specification: session.json's, else the one results.json carries."""
    return meta.get("stage_spec") or as_results(results).stage_spec


def figure_table(flow: Any, rows: Sequence[S.Row]) -> None:
    """Figures with their U (k = 2); a note column when any row has a note."""
    notes = any(r.note for r in rows)
    header = ["figure", "value", "U (k = 2)", "unit"] + (["note"] if notes else [])
    cells = [[r.name, r.text(), r.u_text(), r.unit] + ([r.note] if notes else []) for r in rows]
    widths = [70, 26, 22, 14, 48] if notes else [88, 26, 22, 16]
    flow.table(header, cells, widths, colors=["#888888" if r.unresolved else None for r in rows],
               align_left=(4,) if notes else ())


def overall_color(rows: Sequence[Verdict]) -> str:
    words = [r.verdict for r in rows]
    if rows and all(w == "PASS" for w in words):
        return "#007a1f"
    return "#c00000" if "FAIL" in words else "#333333"


def verdict_table(flow: Any, rows: Sequence[Verdict]) -> None:
    """The verdict rows: the compared figure, its U (k = 2), the limit and the word, then their notes."""
    from lps_gui.core.metrology.asme_b5_64 import tur

    ratios = [tur(v.limit, v.u_k2) for v in rows]  # ASME B5.64: tolerance over U
    cells = [[v.name, v.measured_text(), f"\u00b1 {S.fmt(v.u_k2)} {v.unit}" if v.u_k2 is not None else "not assessed",
              f"{S.fmt(v.limit)} {v.unit}", "\u2014" if ratio is None else f"{ratio:.1f}", v.verdict]
             for v, ratio in zip(rows, ratios)]
    flow.table(["criterion", "compared figure", "U (k = 2)", "limit", "TUR", "verdict"], cells, [40, 34, 26, 22, 12, 46],
               size_pt=8.5, row_mm=4.6, colors=[v.color for v in rows], align_left=(5,))
    for v in rows:
        flow.paragraph(f"{v.name}: {v.note}.", size_pt=NOTE_SIZE, color=GREY)


DECISION_RULE = ("Decision rule ISO 14253-1: PASS when the figure plus U is within the limit, FAIL when the "
                 "figure minus U is beyond it, otherwise not resolved. Each U is that of the figure compared: "
                 "against a \u00b1 limit the half band A/2 (or R/2) is compared, so its U is half the U of A "
                 "(or R) listed with the measured figures; a p-v's U is that of the larger per-target span. "
                 "U covers the measurement (see the uncertainty budget), not the stage's own scatter. TUR (test "
                 "uncertainty ratio, ASME B5.64): the limit over that U.")
NO_SPEC = ("No stage specification was given (enter it with lps capture --spec or in the capture panel): "
           "no verdict is given.")


def verdict_section(flow: Any, results: Results, spec: dict[str, Any] | None,
                    front_rows: Sequence[S.Row] | None = None) -> None:
    """Heading, the overall word and the verdict table; without a spec, ``front_rows`` (the figures with U)."""
    rows = verdicts(results, spec)
    flow.heading("Verdict", 11)
    flow.paragraph(overall(rows), size_pt=10.0, color=overall_color(rows))
    for message in S.session_flags(results):  # what holds for the whole session (a lens model that does not fit)
        flow.paragraph(message, size_pt=8.5, color="#c00000")
    if rows:
        verdict_table(flow, rows)
        flow.paragraph(DECISION_RULE, size_pt=NOTE_SIZE, color=GREY)
        return
    flow.paragraph(NO_SPEC + (" The measured figures:" if front_rows else ""), color=GREY)
    if front_rows:
        figure_table(flow, front_rows)


def iso_section(flow: Any, results: Results, title: str = "ISO 230-2 per target") -> bool:
    """The ISO 230-2 per-target table with its legend; False (nothing painted) without one."""
    table = iso_target_table(results)
    if table is None:
        return False
    header, body, widths = table
    flow.heading(title, 11)
    flow.table(header, body, widths, size_pt=6.8, row_mm=3.4, align_right_from=0)
    flow.paragraph("x\u0304: mean deviation over the runs; s: standard deviation over the runs (1-sigma, "
                   "n \u2212 1); R = 4 s each way; B\u2c7c = x\u0304\u2191 \u2212 x\u0304\u2193; "
                   "R\u2c7c = max(2s\u2191 + 2s\u2193 + |B\u2c7c|, R\u2191, R\u2193). Deviations are "
                   "relative to the first capture.", size_pt=NOTE_SIZE, color=GREY)
    return True


def uncertainty_sections(flow: Any, results: Results, axis: str | None = None, environment: bool = True) -> None:
    """Environment, then the GUM budget (ISO/TR 230-9 style); ``axis`` names one axis's budget of a planar stage."""
    if environment:
        flow.heading("Environment", 11)
        flow.table(None, [list(r) for r in B.environment_rows(results)], [52, 128], size_pt=8.0, row_mm=4.2,
                   align_right_from=9)
    flow.heading("Uncertainty budget (GUM, ISO/TR 230-9)" + (f", {axis} axis" if axis else ""), 11)
    rows = B.budget_rows(results)
    if not rows:
        flow.paragraph("These results carry no uncertainty budget; re-run lps estimate.", color=GREY)
        return
    flow.table(B.BUDGET_HEADER, rows, B.BUDGET_WIDTHS, size_pt=7.5, row_mm=4.0, align_right_from=2,
               align_left=(3, 5))
    for note in B.budget_notes(results):
        flow.paragraph(note, size_pt=7.5, color="#333333")


# ----------------------------------------------------------------------------- identification and signing


def two_pairs(rows: list[tuple[str, str]]) -> list[list[str]]:
    """(label, text) rows as a table of two pairs a line, the first half down the left: page 1 keeps its blocks."""
    half = (len(rows) + 1) // 2
    return [[*rows[i], *(rows[i + half] if i + half < len(rows) else ("", ""))] for i in range(half)]


def identification_blocks(flow: Any, meta: dict[str, Any], results: Results, title: list[tuple[str, str]]) -> None:
    """Page 1's identification, then the certificate's signing block (laboratory, instruments and their
    certificates, dates, approval: :mod:`lps_gui.report.pages.signing`), two pairs a line."""
    from lps_gui.report.pages.signing import signing_rows

    flow.heading("Identification", 11)
    flow.table(None, two_pairs(title), [22, 68, 22, 68], size_pt=7.5, row_mm=3.8, align_right_from=9)
    flow.heading("Certificate and approval", 11)
    flow.table(None, two_pairs(signing_rows(meta, results)), [22, 68, 22, 68], size_pt=7.5, row_mm=3.8,
               align_right_from=9)
