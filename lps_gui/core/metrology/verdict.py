"""The verdict rows: each specified figure with its measured value, U (k = 2), limit and decision.

Decision rule (ISO 14253-1, ``core.metrology.decision_rule``): a row PASSes when the measured figure
plus its expanded uncertainty is within the limit, FAILs when the figure minus U is beyond it, and is
"not resolved" when the limit lies inside the uncertainty zone (or the check itself says so). Figures
from fewer runs than ISO 230-2 asks (5 per direction) are "indicative": the word says so and the colour
is amber, never a red FAIL. The ASME test's own result (min-step, settling) is a row like any figure.

Here, not in the report, because the results (results.json ``verdict``, the ASME TURs) are computed
from these rows and the report prints them: one computation, below both. ``results`` is a typed results
document (``lps_gui.io.results.model.Results``; its callers convert a dict with ``as_results``), read
by its attributes only, so the math layer imports no file layer.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

from lps_gui.core.metrology.decision_rule import FAIL, NOT_MEASURED, NOT_RESOLVED, PASS, decide
from lps_gui.core.metrology.digits import fmt
from lps_gui.core.metrology.iso230 import ISO_RUNS, check_specification
from lps_gui.core.metrology.resolution import runs_per_direction

MU = "\u00b5"
PASS_COLOR, FAIL_COLOR, INDICATIVE_COLOR, GREY = "#007a1f", "#c00000", "#a05a00", "#555555"
# which U of results.json uncertainty.figures_k2 belongs to a check, and whether the check is a run statistic
CHECK_FIGURES = {"Positional accuracy": ("A_um", True), "Repeatability": ("R_um", True),
                 "Straight-line accuracy": ("straightness_span_max", False)}
LEGACY_U_KEYS = {"straightness_span_max": "straightness_um_max"}  # results.json from before the per-span U
QUANTITIES = {"Positional accuracy": "A", "Repeatability": "R"}  # ISO 230-2 symbol of a run statistic
TEST_ROWS = ("Minimum incremental motion", "Settling time")  # the verdict rows of the ASME tests


@dataclass(frozen=True)
class SpecCheck:
    """One criterion of the stage specification against its measured figure."""

    name: str
    measured: float | None
    limit: float
    unit: str
    passed: bool | None  # None: not measured by this session
    note: str = ""
    indicative: bool = False  # fewer runs than ISO 230-2 asks: a verdict to read, not a FAIL

    def verdict(self) -> str:
        """PASS / FAIL / not resolved, "(indicative)" when fewer than 5 runs per direction back it."""
        if self.passed is None:
            return "not resolved" if self.measured is not None else "not measured"
        word = "PASS" if self.passed else ("above limit" if self.indicative else "FAIL")
        return f"{word} (indicative)" if self.indicative else word

    def color(self) -> str:
        """Green pass, red fail; grey when not resolved; muted (never red) when indicative."""
        if self.passed is None:
            return "#555555"
        if self.indicative:
            return "#4f7a5a" if self.passed else "#8a6d00"
        return "#007a1f" if self.passed else "#c00000"


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


def _finite(v: Any) -> float | None:
    """A check's measured figure as a finite float, else None (``check_specification`` writes floats or None)."""
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) else None


def spec_checks(figures: Mapping[str, Any], spec: dict[str, Any] | None) -> list[SpecCheck]:
    """Pass/fail of the stage specification (session.json ``stage_spec``) against results.json ``figures``,
    by ``core.metrology.iso230.check_specification`` (one reading of a data sheet); here only its rows are typed."""
    if not spec:
        return []
    out = []
    for c in check_specification(dict(figures), spec):
        passed = c.get("passed")
        out.append(SpecCheck(str(c.get("name", "")), _finite(c.get("measured")), float(c.get("limit", math.nan)),
                             str(c.get("unit") or "\u00b5m"), None if passed is None else bool(passed),
                             str(c.get("note") or ""), bool(c.get("indicative", False))))
    return out


def _straightness_quantity(results: Any) -> str:
    """"p-v v1" or "p-v v2": the larger per-target span, the one the straight-line check compares."""
    st = results.figures.straightness
    spans = [(v.span_um, k) for k, v in (("v1", st.v1), ("v2", st.v2)) if v is not None and v.span_um is not None
             ] if st else []
    return f"p-v {max(spans)[1]}" if spans else "p-v"


def _decide(c: SpecCheck, u: float | None) -> str:
    return decide(c.measured, c.limit, c.passed, u, unresolved_figure=c.note.lower().startswith("not resolved"))


def min_step_word(step: Any, limit_um: float) -> tuple[str, str]:
    """(verdict, note) of an ``asme_b5_64.incremental_step`` section: PASS when a step size no larger than the limit
    was achieved; FAIL when every size tested up to the limit was resolved and not achieved (or sticks); not resolved
    when such a size was not resolved."""
    mim = step.minimum_incremental_motion_um
    if mim is not None and mim <= limit_um + 1e-9:
        return PASS, f"steps of {fmt(mim)} {MU}m resolved and achieved"
    tested = [s for s in step.sizes if s.commanded_um is not None and s.commanded_um <= limit_um + 1e-9]
    if not tested:
        return NOT_MEASURED, f"no step of {fmt(limit_um)} {MU}m or less was commanded"
    if any(s.n_resolved < s.n_steps for s in tested):
        return NOT_RESOLVED, "the steps up to the limit are not all resolved (their U exceeds the command)"
    parts = [f"{fmt(s.commanded_um)} {MU}m: {s.n_achieved} of {s.n_steps} achieved, {s.n_stuck} below half "
             f"(noise alone {fmt(s.n_stuck_by_noise, 2)})" + (", the stage sticks" if s.sticks else "") for s in tested]
    return FAIL, "; ".join(parts) + f"; the minimum incremental motion is larger than {fmt(max(s.commanded_um for s in tested))} {MU}m"


def asme_rows(results: Any, spec: dict[str, Any]) -> list[tuple[Any, ...]]:
    """(name, quantity, measured, U, limit, unit, verdict, note, shown) of the session's ASME test against its tolerance."""
    asme = results.asme_b5_64
    out: list[Any] = []
    if asme is None:
        return out
    step, settling = asme.incremental_step, asme.settling
    limit = spec.get("min_incremental_motion_um")
    if step is not None and step.raw and limit is not None:
        word, note = min_step_word(step, float(limit))
        u = None if step.max_step_sigma_um is None else 2.0 * step.max_step_sigma_um  # U (k = 2) of one step
        failed = [s.commanded_um for s in step.sizes if s.commanded_um is not None and not s.all_achieved]
        shown = f"> {fmt(max(failed))} {MU}m" if step.minimum_incremental_motion_um is None and failed else ""
        out.append(("Minimum incremental motion", "step", step.minimum_incremental_motion_um, u, float(limit),
                    f"{MU}m", word, note, shown))
    limit = spec.get("settling_time_s")
    if settling is not None and settling.raw and limit is not None:
        t, u = settling.settling_time_s, settling.settling_time_U_s
        word = decide(t, float(limit), None if t is None else t <= float(limit), u)
        note = (f"the longest over {settling.n_stops} moves, band \u00b1{fmt(settling.band_um)} {MU}m"
                if t is not None else "no settling time fitted")
        band = "band" if settling.band_um is None else f"\u00b1{settling.band_um:g} {MU}m band"
        out.append(("Settling time", band, t, u, float(limit), "s", word, note, ""))
    return out


def verdicts(results: Any, spec: dict[str, Any] | None) -> list[Verdict]:
    """The verdict rows of a typed results document against a stage specification (empty without one)."""
    if not spec:
        return []
    figures_k2 = results.uncertainty.figures_k2 if results.uncertainty else {}
    half = 0.5 if str(spec.get("limits", "plus_minus")) == "plus_minus" else 1.0
    runs = runs_per_direction(dict(results.figures.raw))
    out = []
    for c in spec_checks(results.figures.raw, spec):
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
