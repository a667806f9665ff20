"""The ISO 14253-1 decision rule: conformance is decided with the expanded uncertainty, never without it.

A figure PASSes when it plus its expanded uncertainty U (k = 2) is within the
limit, FAILs when it minus U is beyond the limit, and is "not resolved" when
the limit lies inside the uncertainty zone. Pure: the report's verdict rows
and the ASME results both call it, so one rule decides everywhere.
"""
from __future__ import annotations

import math

PASS, FAIL, NOT_RESOLVED, NOT_MEASURED = "PASS", "FAIL", "not resolved", "not measured"


def decide(measured: float | None, limit: float, passed: bool | None, u: float | None,
           unresolved_figure: bool = False) -> str:
    """PASS, FAIL, "not resolved" or "not measured" for one figure against its limit.

    ``passed`` is the bare comparison (None: the figure could not be compared);
    ``unresolved_figure`` says the figure itself is below its noise floor.
    Without a finite U the bare comparison stands.
    """
    if passed is None or measured is None:
        return NOT_RESOLVED if unresolved_figure or measured is not None else NOT_MEASURED
    if u is None or not math.isfinite(u):
        return PASS if passed else FAIL
    if passed and measured + u > limit:
        return NOT_RESOLVED
    if not passed and measured - u <= limit:
        return NOT_RESOLVED
    return PASS if passed else FAIL
