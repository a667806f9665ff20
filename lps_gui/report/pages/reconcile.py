"""One estimator per reported quantity, the other a cross-check reconciled in words (issue 37).

Straightness and the three angles are estimated twice: page 2 from the one-board fit (straightness at the
board plane under the constant orientation, SPEC 11; angles as each view's largest tilt against the largest
noise gives) and the error-motions page from the stops' full poses in the stage frame (ISO 230-1, the
stop-averaged profile tested against zero). The report states which is reported and why, and puts both
values side by side, so "not resolved" on one page and "resolved" on another read as one story. No Qt here.
"""
from __future__ import annotations

from typing import Any

from lps_gui.io.results.document import extreme_figures
from lps_gui.io.results.model import Results, as_results
from lps_gui.report.pages.summary import fmt

MU = "\u00b5"
ONE_ESTIMATOR = "error motions)"  # the label of a page-2 figure taken from the error motions (io.results.document)
# ISO 230-1 motion -> (page 2 summary key, which page's figure is reported)
PAIRS = {"EYX": ("straightness_span_1", "page 2"), "EZX": ("straightness_span_2", "page 2"),
         "EAX": ("max_abs_roll", "error motions"), "EBX": ("max_abs_pitch", "error motions"),
         "ECX": ("max_abs_yaw", "error motions")}
WHY = {"page 2": "The constant-orientation fit determines the displacement at the board plane to a few {mu}m per "
                 "view, while a stop's full pose carries the tilt-translation ambiguity of one plane, hence its "
                 "larger noise",
       "error motions": "The profile of stop-averaged angles is tested against zero as a whole (chi-square), the "
                        "largest stop-averaged angle (about their mean) against the largest noise gives: near the "
                        "noise floor the profile resolves a smooth motion the largest stop does not"}
PAGE2_NOTE = ("Roll, pitch and yaw are reported on the error motions page (ISO 230-1, stage frame); the max |angle| "
              "rows here are a cross-check, reconciled there. Straightness is reported here (at the board plane).")


def _page2_text(f: Any) -> str:
    return f.unresolved if f.unresolved else f"{fmt(f.value)} {f.unit}"


def reconciliation_lines(results: Results | dict[str, Any]) -> list[str]:
    """One sentence per quantity both estimators report: the reported figure, the cross-check, why they differ."""
    results = as_results(results)
    section = results.error_motions
    if section is None or not section.motions:
        return []
    page2 = {f.key: f for f in extreme_figures(results.to_dict())}
    lines = []
    for iso, (key, reported) in PAIRS.items():
        m, f = section.motions.get(iso), page2.get(key)
        if m is None or f is None or (f.value is None and not f.unresolved) or f.label.endswith(ONE_ESTIMATOR):
            continue  # a row of targets: page 2 already takes the error motion (one estimator, nothing to reconcile)
        unit = f"{MU}m" if m.unit == "um" else f"{MU}rad"
        here = (f"p-v {fmt(m.span())} {unit} resolved" if section.is_resolved(iso)
                else f"not resolved (noise p-v {fmt(m.noise_span())} {unit})")
        reported_text = f"{f.label} {_page2_text(f)}" if reported == "page 2" else here
        check_text = here if reported == "page 2" else _page2_text(f)
        where = "page 2" if reported == "page 2" else "this page"
        check = "the stops' full poses (this page)" if reported == "page 2" else f"page 2's {f.label}"
        lines.append(f"{iso}: reported on {where}, {reported_text}; cross-check from {check}: {check_text}. "
                     + WHY[reported].format(mu=MU) + ".")
    return lines


def page2_note(results: Results | dict[str, Any]) -> str:
    """Page 2's pointer to where each angle is reported (empty without error motions)."""
    results = as_results(results)
    section = results.error_motions
    if section is None or not section.motions:
        return ""
    labels = [f.label or "" for f in extreme_figures(results.to_dict())]
    return "" if all(label.endswith(ONE_ESTIMATOR) for label in labels) else PAGE2_NOTE
