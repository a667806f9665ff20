"""E (ISO 230-2) of a results document's deviation column: the measured one results.json holds, or a truth column's.

Below the comparison report and the compensation pass, which both state E before and after: one definition.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from lps_gui.errors import InputError
from lps_gui.io.results.keys import DEVIATION_UM
from lps_gui.io.results.model import Results, as_results


def session_E_um(results: Results | dict[str, Any], key: str = DEVIATION_UM) -> float:
    """E (ISO 230-2, um) of one deviation column of results.json.

    The measured deviations' E is the one results.json holds (the camera's noise taken out,
    ``iso230_2.noise_correction``): one definition, the report's, summary.csv's and this comparison's.
    A column of the simulator's truth has no noise: its E is computed from the column."""
    results = as_results(results)
    if key == DEVIATION_UM:
        iso = results.figures.iso230_2
        value = iso.number("E_um") if iso is not None else None
        if value is None:
            raise InputError("results.json has no ISO 230-2 E; estimate a bidirectional session (or two runs)")
        return float(value)
    from lps_gui.core.metrology.iso230 import figures_for_session

    rows = [r for r in results.positions if r.get(key) is not None and not r.outlier]
    if not rows:
        raise InputError(f"results.json has no {key}; estimate a simulated session")
    t = results.column("target_mm", rows)
    d = np.array([1.0 if r.direction == "+" else -1.0 for r in rows])
    run = np.array([r.run for r in rows])
    iso = figures_for_session(t, d, run, results.column(key, rows))["iso230_2"]
    if not iso or iso.get("E_um") is None:
        raise InputError("E needs both directions or two runs; capture a bidirectional session")
    return float(iso["E_um"])


def true_E_um(results: Results | dict[str, Any]) -> float:
    return session_E_um(results, "truth_deviation_um")
