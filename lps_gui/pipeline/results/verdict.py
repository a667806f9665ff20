"""results.json ``verdict`` and summary.csv's U and verdict rows: the page-1 verdict, machine-readable.

The rows are the report's own (:func:`lps_gui.core.metrology.verdict.verdicts`, one decision rule in
``core.metrology.decision_rule``), so the PDF, summary.csv and results.json cannot disagree; a session
without a stage specification gets "no specification", never a PASS.
"""
from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

from lps_gui.io.results.document import (
    FORMAT,
    json_float,
    summary_csv_rows,
    verdict_csv_rows,
)
from lps_gui.io.results.model import Results
from lps_gui.io.results.sections import AsmeB564, Figures, Uncertainty

DECISION_RULE = ("ISO 14253-1: PASS when the figure plus its expanded uncertainty U (k = 2) is within the limit, "
                 "FAIL when the figure minus U is beyond it, not resolved when the limit lies within +-U")


def check_key(name: str) -> str:
    """"Straight-line accuracy" -> "straight_line_accuracy" (a summary.csv row name)."""
    return re.sub(r"[^a-z0-9]+", "_", name.lower()).strip("_")


def measured(axes: tuple[str, ...], figures: Mapping[str, Any], uncertainty: Uncertainty | None,
             asme_b5_64: AsmeB564 | None = None) -> Results:
    """The typed sections the verdict rows read (figures, their U (k = 2), the ASME test), made from the values
    the builders computed: no results document is read (:mod:`lps_gui.pipeline.results.parts`)."""
    return Results(format=FORMAT, axes=tuple(axes), positions=(), source=BUILDER,
                   figures=Figures.from_dict(figures, "figures", BUILDER), uncertainty=uncertainty, asme_b5_64=asme_b5_64)


BUILDER = "results builder"  # the source the messages name when a builder's value does not type


def verdict_section(values: Results, spec: Mapping[str, Any] | None) -> dict[str, Any]:
    """results.json ``verdict``: the decision rule, the overall word and line, one row per specified figure, of
    the sections :func:`measured` typed against the stage specification (session.json ``stage_spec``)."""
    from lps_gui.core.metrology.verdict import overall, overall_word
    from lps_gui.io.results.verdict_rows import session_verdicts

    rows = session_verdicts(values, dict(spec) if spec else None)  # a plane's per-axis and squareness rows too
    return {
        "decision_rule": DECISION_RULE,
        "overall": overall_word([r.verdict for r in rows]),
        "overall_text": overall(rows),
        "checks": [{"key": check_key(r.name), "name": r.name, "quantity": r.quantity,
                    "measured": None if r.measured is None else json_float(r.measured),
                    "u_k2": None if r.u_k2 is None else json_float(r.u_k2), "limit": json_float(r.limit),
                    "unit": r.unit, "verdict": r.verdict, "note": r.note, **({"shown": r.shown} if r.shown else {})}
                   for r in rows],
    }


def summary_rows(results: dict[str, Any]) -> list[tuple[Any, ...]]:
    """summary.csv's rows (with U and the verdict rows): a view of the finished document, like positions.csv,
    made once every section is in it."""
    return planar_summary_rows(results) if len(results.get("axes") or ["X"]) == 2 else summary_csv_rows(results)


CSV_NAMES = {"squareness_urad": "squareness", "scale_x_ppm": "scale_x", "scale_y_ppm": "scale_y"}  # page 1's key
# -> summary.csv's name where the two differ (the others are the same)


def planar_summary_rows(results: dict[str, Any]) -> list[tuple[Any, ...]]:
    """summary.csv of a planar session as a line's: (name, value, unit, U (k = 2), note), then the verdict rows;
    U and note are page 1's (:func:`lps_gui.io.results.verdict_rows.planar_figure_us`, which its rows read)."""
    from lps_gui.io.results.verdict_rows import planar_figure_us
    from lps_gui.pipeline.results.planar import summary_csv_rows as planar_rows

    columns = {CSV_NAMES.get(key, key): (None if unresolved else u, unresolved.replace("\u00b5", "u"))
               for key, (u, unresolved) in planar_figure_us(results).items()}
    return [(name, value, unit, *columns.get(name, (None, ""))) for name, value, unit in planar_rows(results)
            ] + verdict_csv_rows(results.get("verdict"))
