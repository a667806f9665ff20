"""As-found / as-left report: two estimated sessions of one stage, before and after compensation.

Each session's verdict against its stage spec, the ISO 230-2 figures side
by side under the main report's names with U (k = 2) and the improvement
factor with its U, for simulated sessions the true E (labelled: the
improvement of true E is not the one of measured E), and the deviation
curves of both overlaid (mean per target and direction). The figure is a plain :class:`FigureSpec` (no
Qt); the PDF uses the report's :class:`PdfFlow`, Qt imported inside.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lps_gui.errors import InputError
from lps_gui.io.results.iso_e import session_E_um, true_E_um  # noqa: F401  (the comparison's E)
from lps_gui.io.results.keys import DEVIATION_UM
from lps_gui.io.results.model import Results, as_results
from lps_gui.io.results.sections import Iso230
from lps_gui.report.figures.plots import (
    _by_direction,
    _dir_label,
    per_target_stats,
    position_columns,
)
from lps_gui.report.figures.spec import (
    BACKWARD_COLOR,
    FORWARD_COLOR,
    FigureSpec,
    Series,
)
from lps_gui.report.pages.sections import NO_SPEC, stage_spec
from lps_gui.report.pages.summary import fmt, iso_rows, u_key
from lps_gui.report.pages.verdict import verdicts
from lps_gui.report.pdf.document import load_results, load_session_meta

COMPARE_FILE = "as-found-as-left.pdf"
AFTER_COLORS = {"+": "#2a9d3c", "-": "#a8326e"}
ISO_KEYS = ("iso230_2_E", "iso230_2_E_up", "iso230_2_E_down", "iso230_2_M", "iso230_2_B", "iso230_2_A", "iso230_2_R")


@dataclass(frozen=True)
class CompareRow:
    """One figure as found and as left, each with U (k = 2), and the ratio with its U."""

    name: str
    before: float | None
    u_before: float | None
    after: float | None
    u_after: float | None

    @property
    def ratio(self) -> float | None:
        return self.before / self.after if self.before is not None and self.after else None

    @property
    def u_ratio(self) -> float | None:
        """U of before/after from the two U's (sessions independent): r sqrt((U_b/b)^2 + (U_a/a)^2)."""
        r = self.ratio
        if r is None or self.u_before is None or self.u_after is None or not self.before:
            return None
        return abs(r) * math.hypot(self.u_before / self.before, self.u_after / self.after)

    def cells(self) -> list[str]:
        def pm(v: float | None, u: float | None) -> str:
            return fmt(v) if u is None else f"{fmt(v)} \u00b1 {fmt(u, 2)}"

        ratio = "" if self.ratio is None else f"{self.ratio:.1f}x" + (
            "" if self.u_ratio is None else f" \u00b1 {self.u_ratio:.1f}")
        return [self.name, pm(self.before, self.u_before), pm(self.after, self.u_after), ratio]


def comparison_figure(before: Results, after: Results) -> FigureSpec:
    """Mean deviation per target and direction, as found (blue/orange) and as left (green/purple)."""
    series = []
    for results, tag, dashed in ((before, "as found", True), (after, "as left", False)):
        cols = position_columns(results)
        for d, sel in _by_direction(cols):
            t, mean, _, _ = per_target_stats(cols["target_mm"][sel], cols[DEVIATION_UM][sel], ~cols["outlier"][sel])
            color = (FORWARD_COLOR if d == "+" else BACKWARD_COLOR) if dashed else AFTER_COLORS[d]
            series.append(Series(t, mean, f"{tag} {_dir_label(d)}", "line+markers", color, dashed=dashed))
    return FigureSpec("compare", "Deviation as found and as left", "target position [mm]", "deviation [\u00b5m]", series,
                      "mean over runs per target and direction")


def _iso(results: Results) -> Iso230 | None:
    return results.figures.iso230_2


def _u(results: Results, key: str) -> float | None:
    return results.uncertainty.u_k2(u_key(key)) if results.uncertainty else None


def compare_rows(before: Results | dict[str, Any], after: Results | dict[str, Any]) -> list[CompareRow]:
    """Every ISO 230-2 figure either session has, named as in the main report, with U from each results.json."""
    before, after = as_results(before), as_results(after)
    b_rows = {r.key: r for r in iso_rows(_iso(before))}
    a_rows = {r.key: r for r in iso_rows(_iso(after))}
    out = []
    for key in ISO_KEYS:
        b, a = b_rows.get(key), a_rows.get(key)
        if b is None and a is None:
            continue
        name = (b or a).name
        out.append(CompareRow(name, b.value if b else None, _u(before, key) if b else None,
                              a.value if a else None, _u(after, key) if a else None))
    return out


def comparison_rows(before: Results | dict[str, Any], after: Results | dict[str, Any]) -> list[list[str]]:
    """[name, as found ± U, as left ± U, improvement ± U] per ISO 230-2 figure (text cells, \u00b5m)."""
    return [r.cells() for r in compare_rows(before, after)]


def true_E_rows(before: Results, after: Results) -> list[list[str]]:
    """The simulator's true E before and after, when both sessions are simulated (known exactly: no U)."""
    try:
        b, a = true_E_um(before), true_E_um(after)
    except InputError:
        return []
    return [CompareRow("True E (simulator; not a measurement)", b, None, a, None).cells()]


def verdict_rows(before: Results, after: Results, spec_before: dict[str, Any] | None,
                 spec_after: dict[str, Any] | None) -> list[list[str]]:
    """[criterion, as found, as left]: each session against its stage spec (figure, U, word)."""
    def text(v: Any) -> str:
        u = "" if v.u_k2 is None else f" \u00b1 {fmt(v.u_k2)}"
        return f"{v.measured_text()}{u}: {v.verdict}"

    b = {v.name: v for v in verdicts(before, spec_before)}
    a = {v.name: v for v in verdicts(after, spec_after)}
    return [[name, text(b[name]) if name in b else "no spec", text(a[name]) if name in a else "no spec"]
            for name in dict.fromkeys([*b, *a])]


def write_comparison(before_dir: Path | str, after_dir: Path | str, out: Path | str | None = None,
                     clipped: list[str] | None = None) -> Path:
    """Write the as-found / as-left PDF (default AFTER/as-found-as-left.pdf); returns its path.

    ``clipped``, when given, receives every string that does not fit its box (the layout check).
    """
    from lps_gui import __version__
    from lps_gui.report.pdf.layout import ensure_gui_app, pdf_file

    before, after = load_results(Path(before_dir)), load_results(Path(after_dir))
    out = Path(out) if out is not None else Path(after_dir) / COMPARE_FILE
    if not out.parent.is_dir():
        raise InputError(f"{out.parent}: folder not found; create it or choose another --out")
    rows = comparison_rows(before, after)
    truth_rows = true_E_rows(before, after)
    if not rows and not truth_rows:
        raise InputError("as-found/as-left: neither session has ISO 230-2 figures; measure both directions or two runs")
    specs = [stage_spec(load_session_meta(Path(d)), r) for d, r in ((before_dir, before), (after_dir, after))]
    ensure_gui_app()
    with pdf_file(out, "As found / as left", f"lps-calib {__version__} \u00b7 {Path(before_dir).name} -> {Path(after_dir).name}") as flow:
        flow.heading("Stage compensation: as found / as left", 15)
        for tag, results, folder in (("as found", before, before_dir), ("as left", after, after_dir)):
            flow.paragraph(f"{tag}: {(results.inputs and results.inputs.session) or folder}  ({results.created or ''})")
        flow.space(2)
        flow.heading("Verdict against the stage specification", 11)
        if any(specs):
            flow.table(["criterion", "as found", "as left"], verdict_rows(before, after, *specs), [40, 70, 70],
                       size_pt=8.0, align_right_from=9)
        else:
            flow.paragraph(NO_SPEC, color="#555555")
        flow.heading("ISO 230-2 figures [\u00b5m], U (k = 2)", 11)
        flow.table(["figure", "as found", "as left", "improvement\n(as found / as left)"], rows, [78, 34, 34, 34])
        flow.paragraph("Improvement = as found / as left of the measured figures, with U from the two sessions' "
                       "U (taken as independent). The as-left E cannot fall below the measurement's own noise: the "
                       "table's entries carry that noise into the correction.", size_pt=7.5, color="#555555")
        if truth_rows:
            flow.heading("Simulation only: the true E", 11)
            flow.table(["figure", "as found", "as left", "improvement\n(of true E)"], truth_rows, [78, 34, 34, 34],
                       colors=["#555555"] * len(truth_rows))
            flow.paragraph("The simulator knows the stage's true positions: the improvement of true E is what the "
                           "compensation achieved; the improvement of measured E above also carries the noise of "
                           "both measurements.", size_pt=7.5, color="#555555")
        flow.space(3)
        flow.figure(comparison_figure(before, after), 110.0)
    if clipped is not None:
        clipped.extend(flow.log.clipped)
    return out


def improvement_factor(before: Results | dict[str, Any], after: Results | dict[str, Any], key: str = "E_um"
                       ) -> float | None:
    b, a = (iso.number(key) if (iso := _iso(as_results(r))) else None for r in (before, after))
    return None if b is None or not a else b / a

