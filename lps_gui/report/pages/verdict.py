"""The verdict of page 1: each specification row with its measured figure, U (k = 2) and the limit.

Decision rule (ISO 14253-1): a row PASSes when the measured figure plus its
expanded uncertainty is within the limit, FAILs when the figure minus U is
beyond it, and is "not resolved" when the limit lies inside the
uncertainty zone (or the check itself says so). Figures from fewer runs than
ISO 230-2 asks (5 per direction) are "indicative": the word is printed and
the colour is amber, never a red FAIL. Rows come from
:func:`lps_gui.report.pages.summary.spec_checks`, whichever rows the results carry.
No Qt here.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from lps_gui.core.metrology.decision_rule import decide
from lps_gui.core.metrology.iso230 import ISO_RUNS
from lps_gui.core.metrology.resolution import runs_per_direction
from lps_gui.io.results.model import Results, as_results
from lps_gui.report.pages.asme_verdict import asme_rows
from lps_gui.report.pages.summary import SpecCheck, fmt, spec_checks

PASS_COLOR, FAIL_COLOR, INDICATIVE_COLOR, GREY = "#007a1f", "#c00000", "#a05a00", "#555555"
# which U of results.json uncertainty.figures_k2 belongs to a check, and whether the check is a run statistic
CHECK_FIGURES = {"Positional accuracy": ("A_um", True), "Repeatability": ("R_um", True),
                 "Straight-line accuracy": ("straightness_span_max", False)}
LEGACY_U_KEYS = {"straightness_span_max": "straightness_um_max"}  # results.json from before the per-span U
QUANTITIES = {"Positional accuracy": "A", "Repeatability": "R"}  # ISO 230-2 symbol of a run statistic


@dataclass(frozen=True)
class Verdict:
    """One row of the verdict table."""

    name: str
    measured: float | None
    u_k2: float | None  # expanded uncertainty of ``measured`` (of ``quantity``) as compared with the limit
    limit: float
    unit: str
    verdict: str  # "PASS", "FAIL", "not resolved", "not measured", each optionally "(indicative)"
    color: str
    note: str
    quantity: str = ""  # what ``measured`` and ``u_k2`` are: "A/2", "R/2", "p-v v2", ...
    shown: str = ""  # printed instead of a missing value when the test bounds it ("> 2.00 µm")

    def measured_text(self) -> str:
        """The compared quantity and its value, e.g. "A/2 = 13.1 µm" (the figure page 2 lists as A is twice it)."""
        value = (self.shown or "\u2014") if self.measured is None else f"{fmt(self.measured)} {self.unit}"
        return f"{self.quantity} = {value}" if self.quantity else value


def _straightness_quantity(results: Results) -> str:
    """"p-v v1" or "p-v v2": the larger per-target span, the one the straight-line check compares."""
    st = results.figures.straightness
    spans = [(v.span_um, k) for k, v in (("v1", st.v1), ("v2", st.v2)) if v is not None and v.span_um is not None
             ] if st else []
    return f"p-v {max(spans)[1]}" if spans else "p-v"


def _decide(c: SpecCheck, u: float | None) -> str:
    return decide(c.measured, c.limit, c.passed, u, unresolved_figure=c.note.lower().startswith("not resolved"))


def verdicts(results: Results | dict[str, Any], spec: dict[str, Any] | None) -> list[Verdict]:
    """The verdict rows of a line session's results against a stage specification (empty without one); any
    session's, a plane's too: :func:`lps_gui.report.pages.session_verdict.session_verdicts`."""
    if not spec:
        return []
    return line_verdicts(as_results(results), spec)


def line_verdicts(results: Results, spec: dict[str, Any]) -> list[Verdict]:
    """The verdict rows of one axis's results (a line session's, or one axis of a plane shaped like one)."""
    figures_k2 = results.uncertainty.figures_k2 if results.uncertainty else {}
    half = 0.5 if str(spec.get("limits", "plus_minus")) == "plus_minus" else 1.0
    runs = runs_per_direction(dict(results.figures.raw))
    out = []
    for c in spec_checks(results, spec):
        key, run_statistic = CHECK_FIGURES.get(c.name, (None, False))
        u = figures_k2.get(key, figures_k2.get(LEGACY_U_KEYS.get(key, ""))) if key else None
        if u is not None and run_statistic:
            u = float(u) * half  # the figure is compared as a half band against a +- limit: U of A/2 is U(A)/2
        symbol = QUANTITIES.get(c.name)
        quantity = (symbol + ("/2" if half == 0.5 else "")) if symbol else (
            _straightness_quantity(results) if c.name == "Straight-line accuracy" else "")
        word = _decide(c, u)
        indicative = c.indicative and word in ("PASS", "FAIL")  # core.iso230: a run statistic from < 5 runs
        color = {"PASS": PASS_COLOR, "FAIL": FAIL_COLOR}.get(word, GREY)
        note = c.note
        if word == "not resolved" and c.passed is not None:
            note = f"the limit lies within \u00b1U of the figure (ISO 14253-1); {c.note}"
        if indicative:
            color = INDICATIVE_COLOR
            note = f"{runs} run(s) per direction, ISO 230-2 asks for {ISO_RUNS}; {note}"
            word += " (indicative)"
        out.append(Verdict(c.name, c.measured, u, c.limit, c.unit, word, color, note, quantity))
    for name, quantity, measured, u, limit, unit, word, note, shown in asme_rows(results, spec):  # the test's own result
        out.append(Verdict(name, measured, u, limit, unit, word, {"PASS": PASS_COLOR, "FAIL": FAIL_COLOR}.get(word, GREY),
                           note, quantity, shown))
    return out


NO_SPEC_WORD = "no specification"
OVERALL_TEXT = {NO_SPEC_WORD: "No stage specification given: figures only, no verdict.",
                "FAIL": "FAIL: the stage is outside its specification beyond the measurement uncertainty.",
                "PASS": "PASS: every specified figure is within its limit, uncertainty included.",
                "FAIL (indicative)": "Indicative FAIL: too few runs for an ISO 230-2 verdict; repeat with 5 runs per "
                                     "direction.",
                "not resolved": "Not fully resolved: see the rows below (indicative, not resolved or not measured)."}


def overall_word(words: list[str]) -> str:
    """One word for the whole verdict (results.json, summary.csv): FAIL beats an indicative FAIL beats not resolved;
    PASS only when every row passes."""
    if not words:
        return NO_SPEC_WORD
    if "FAIL" in words:
        return "FAIL"
    if all(w == "PASS" for w in words):
        return "PASS"
    if any(w.startswith("FAIL") for w in words):
        return "FAIL (indicative)"
    return "not resolved"


def overall(rows: list[Verdict]) -> str:
    """One line for the top of page 1: :func:`overall_word` in words."""
    return OVERALL_TEXT[overall_word([r.verdict for r in rows])]
