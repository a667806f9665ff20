"""The verdict of page 1: each specification row with its measured figure, U (k = 2) and the limit.

The rows and the decision rule are computed in ``core.metrology.verdict`` (the results are built
from them too); here a results dict or document is read once and the names the pages use are kept.
No Qt here.
"""
from __future__ import annotations

from typing import Any

from lps_gui.core.metrology import verdict as _rows
from lps_gui.core.metrology.verdict import (  # noqa: F401  (the names the pages and tests use)
    FAIL_COLOR,
    GREY,
    INDICATIVE_COLOR,
    NO_SPEC_WORD,
    OVERALL_TEXT,
    PASS_COLOR,
    Verdict,
    overall,
    overall_word,
)
from lps_gui.io.results.model import Results, as_results


def verdicts(results: Results | dict[str, Any], spec: dict[str, Any] | None) -> list[Verdict]:
    """The verdict rows of results against a stage specification (empty without one)."""
    return _rows.verdicts(as_results(results), spec) if spec else []
