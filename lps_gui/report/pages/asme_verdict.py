"""The verdict rows of an ASME B5.64 test session: the test's own result against its tolerance.

A min-step session's page 1 said only "Not fully resolved" while page 4 concluded the minimum
incremental motion was larger than the 2 um specified (issue 37): the test's result is a row of the
verdict like any figure, so page 1, results.json and summary.csv carry it. No Qt here.
"""
from __future__ import annotations

from typing import Any

from lps_gui.core.metrology.decision_rule import FAIL, NOT_MEASURED, NOT_RESOLVED, PASS, decide
from lps_gui.io.results.model import Results
from lps_gui.io.results.sections import IncrementalStep, Settling
from lps_gui.report.pages.summary import fmt

MU = "\u00b5"
TEST_ROWS = ("Minimum incremental motion", "Settling time")  # the verdict rows of the ASME tests


def min_step_word(step: IncrementalStep, limit_um: float) -> tuple[str, str]:
    """(verdict, note): PASS when a step size no larger than the limit was achieved; FAIL when every size tested
    up to the limit was resolved and not achieved (or sticks); not resolved when such a size was not resolved."""
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


def asme_rows(results: Results, spec: dict[str, Any]) -> list[tuple[Any, ...]]:
    """(name, quantity, measured, U, limit, unit, verdict, note, shown) of the session's ASME test against its tolerance."""
    asme = results.asme_b5_64
    out: list[Any] = []
    if asme is None:
        return out
    step, settling = asme.incremental_step, asme.settling
    limit = spec.get("min_incremental_motion_um")
    if isinstance(step, IncrementalStep) and step.raw and limit is not None:
        word, note = min_step_word(step, float(limit))
        u = None if step.max_step_sigma_um is None else 2.0 * step.max_step_sigma_um  # U (k = 2) of one step
        failed = [s.commanded_um for s in step.sizes if s.commanded_um is not None and not s.all_achieved]
        shown = f"> {fmt(max(failed))} {MU}m" if step.minimum_incremental_motion_um is None and failed else ""
        out.append(("Minimum incremental motion", "step", step.minimum_incremental_motion_um, u, float(limit),
                    f"{MU}m", word, note, shown))
    limit = spec.get("settling_time_s")
    if isinstance(settling, Settling) and settling.raw and limit is not None:
        t, u = settling.settling_time_s, settling.settling_time_U_s
        word = decide(t, float(limit), None if t is None else t <= float(limit), u)
        note = (f"the longest over {settling.n_stops} moves, band \u00b1{fmt(settling.band_um)} {MU}m"
                if t is not None else "no settling time fitted")
        band = "band" if settling.band_um is None else f"\u00b1{settling.band_um:g} {MU}m band"
        out.append(("Settling time", band, t, u, float(limit), "s", word, note, ""))
    return out
