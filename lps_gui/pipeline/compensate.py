"""`lps compensate`: a session's results.json -> a controller's compensation table and backlash lines."""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from lps_gui.core.metrology.compensation import CompensationTable, build_table, own_sigma_um
from lps_gui.errors import InputError
from lps_gui.io.compensation_file import backlash_lines, skew_lines, write_table
from lps_gui.io.results.model import Results, as_results, read_results
from lps_gui.pipeline.session_checks import require_current_results
from lps_gui.io.results.keys import DEVIATION_UM, SIGMA_TOTAL_UM

RESULTS_FILE = "results.json"


def session_results(session_dir: Path | str, command: str = "compensate") -> Results:
    """results.json of a session folder, computed from its current files; a one-line error otherwise."""
    folder = Path(session_dir)
    path = folder / RESULTS_FILE
    if not folder.is_dir():
        raise InputError(f"{folder}: session folder not found; check the path")
    if not path.exists():
        raise InputError(f"{folder}: no results.json; run `lps estimate {folder}` first")
    results = read_results(path)
    require_current_results(folder, results, command)
    return results


def table_from_results(results: Results | dict[str, Any], max_points: int = 256, axis: str = "X") -> CompensationTable:
    """The compensation table of an estimated session (outliers and unusable views left out).

    A planar session (SPEC 10) gives the table of ``axis``: its deviation
    against its target over every capture (all lines of the other axis pooled;
    the other axis' squareness goes to the skew settings), each capture's
    direction being the side that axis was approached from.
    """
    results = as_results(results)
    if results.planar:
        return _planar_axis_table(results, axis, max_points)
    rows, col = results.positions, results.column
    is_ref = np.array([r.index == results.parameters.reference_index for r in rows])
    valid = np.array([r.usable and r.get(DEVIATION_UM) is not None for r in rows])
    direction = np.array([1.0 if r.direction == "+" else -1.0 for r in rows])
    noise, total = col("sigma_um"), col(SIGMA_TOTAL_UM)
    intrinsics_var = np.maximum(np.nan_to_num(total**2 - noise**2), 0.0)  # correlated, grows with the distance
    sigma = np.sqrt(own_sigma_um(noise, is_ref) ** 2 + intrinsics_var)
    return build_table(col("target_mm"), direction, col("run"), col(DEVIATION_UM), sigma, valid, max_points)


def _planar_axis_table(results: Results, axis: str, max_points: int) -> CompensationTable:
    if axis not in ("X", "Y"):
        raise InputError(f"--axis {axis}: a planar session measured X and Y; choose one of them")
    a = "XY".index(axis)
    key = axis.lower()

    rows, col = results.positions, results.column
    is_ref = np.array([r.index == results.parameters.reference_index for r in rows])
    valid = np.array([bool(r.used) and r.get(f"deviation_{key}_um") is not None for r in rows])
    side = np.array([float((r.get("approach") or [1, 1])[a]) for r in rows])
    passes = col("run") * 2 + np.array([r.direction == "+" for r in rows])
    sigma = own_sigma_um(col(f"sigma_{key}_um"), is_ref)
    return build_table(col(f"target_{key}_mm"), side, passes, col(f"deviation_{key}_um"), sigma, valid, max_points)


def compensate_session(session_dir: Path | str, fmt: str, out: Path | str, axis: str = "X",
                       error_motions_out: Path | str | None = None) -> tuple[CompensationTable, list[str]]:
    """Write the table of ``session_dir`` as ``fmt`` to ``out``; return it and the settings lines to print
    (backlash; for a planar session also the skew correction from the measured squareness).
    ``error_motions_out``: also the six error motions per nominal position as CSV (SPEC 14)."""
    results = session_results(session_dir)
    table = table_from_results(results, axis=axis)
    if error_motions_out is not None:
        from lps_gui.pipeline.error_motion_table import error_motion_table

        error_motion_table(results)  # refused before anything is written
    write_table(out, table, fmt)
    if error_motions_out is not None:
        from lps_gui.pipeline.error_motion_table import write_error_motion_table

        write_error_motion_table(error_motions_out, results)
    b = table.backlash_um()
    lines = [] if b is None else backlash_lines(b, axis)
    planar = results.figures.planar
    if planar and planar.squareness_urad is not None:
        lines += skew_lines(planar.squareness_urad)
    return table, lines
