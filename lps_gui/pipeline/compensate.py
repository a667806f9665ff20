"""`lps compensate`: a session's results.json -> a controller's compensation table and backlash lines."""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from lps_gui.core.compensation import CompensationTable, build_table, own_sigma_um
from lps_gui.errors import InputError
from lps_gui.io.compensation_file import backlash_lines, write_table
from lps_gui.io.results_file import read_results

RESULTS_FILE = "results.json"


def session_results(session_dir: Path | str) -> dict[str, Any]:
    """results.json of a session folder, with a one-line error when it is missing."""
    folder = Path(session_dir)
    path = folder / RESULTS_FILE
    if not folder.is_dir():
        raise InputError(f"{folder}: session folder not found; check the path")
    if not path.exists():
        raise InputError(f"{folder}: no results.json; run `lps estimate {folder}` first")
    return read_results(path)


def table_from_results(results: dict[str, Any], max_points: int = 256) -> CompensationTable:
    """The compensation table of an estimated session (outliers and unusable views left out)."""
    rows = results.get("positions") or []
    if not rows:
        raise InputError("results.json holds no positions; estimate the session again")

    def col(key: str) -> np.ndarray:
        return np.array([np.nan if r.get(key) is None else float(r[key]) for r in rows])

    ref = (results.get("parameters") or {}).get("reference_index")
    is_ref = np.array([r.get("index") == ref for r in rows])
    valid = np.array([bool(r.get("used", not r.get("outlier"))) and r.get("deviation_um") is not None for r in rows])
    direction = np.array([1.0 if r.get("direction") == "+" else -1.0 for r in rows])
    noise, total = col("sigma_um"), col("sigma_total_um")
    intrinsics_var = np.maximum(np.nan_to_num(total**2 - noise**2), 0.0)  # correlated, grows with the distance
    sigma = np.sqrt(own_sigma_um(noise, is_ref) ** 2 + intrinsics_var)
    return build_table(col("target_mm"), direction, col("run"), col("deviation_um"), sigma, valid, max_points)


def compensate_session(session_dir: Path | str, fmt: str, out: Path | str, axis: str = "X") -> tuple[CompensationTable, list[str]]:
    """Write the table of ``session_dir`` as ``fmt`` to ``out``; return it and the backlash lines to print."""
    table = table_from_results(session_results(session_dir))
    write_table(out, table, fmt)
    b = table.backlash_um()
    lines = [] if b is None else backlash_lines(b, axis)
    return table, lines
