"""The demo's last two steps, shared by the one-board demo and the row demo: estimate, then the report.

Its own module so that :mod:`lps_gui.pipeline.demos.run` and
:mod:`lps_gui.pipeline.demos.targets` both use it without importing each other.
"""
from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Callable

from lps_gui.core.progress import CancelToken
from lps_gui.io.results.model import Results, as_results
from lps_gui.io.results.sections import Parameters
from lps_gui.pipeline.estimate import estimate_session

StepFn = Callable[[str, str, str, float], None]


def estimate_and_report(folder: Path, res: Any, step: StepFn, bar: Callable[[str], Any], cancel: CancelToken | None,
                        describe: Callable[[Parameters], str]) -> Results:
    """Estimate the session through the one path, then write report.pdf; ``res`` (a DemoResult) gets the results,
    the PDF and the CSVs; ``describe`` says what the estimate fitted (the step's line)."""
    from lps_gui.report.pdf.document import write_report

    t0 = time.monotonic()
    results = as_results(estimate_session(folder, method="joint", progress=bar("estimate"), cancel=cancel),
                         str(folder / "results.json"))
    res.results = results
    step("estimate", "done", describe(results.parameters), t0)

    t0 = time.monotonic()
    res.report_pdf = write_report(folder, results, progress=bar("report"))
    res.csvs = [folder / n for n in ("positions.csv", "summary.csv") if (folder / n).exists()]
    step("report", "done", f"{res.report_pdf}", t0)
    return results
