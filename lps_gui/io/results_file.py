"""results.json, positions.csv and summary.csv (SPEC 7).

results.json is the complete, versioned record (schema in
docs/ARCHITECTURE.md), assembled here only (:func:`assemble_results`); the
CSVs are views of it for spreadsheets (:func:`summary_rows` gives summary.csv's
rows). All three are written atomically, results.json last, so a reader never
sees a results.json whose CSVs are missing.
"""
from __future__ import annotations

import csv
import io
import math
import time
from pathlib import Path
from typing import Any

from lps_gui import __version__
from lps_gui.errors import InputError
from lps_gui.io.atomic import write_text_atomic
from lps_gui.io.jsonfile import read_json, write_json

FORMAT = "lps-results/1"
RESULTS_FILE = "results.json"
POSITIONS_FILE = "positions.csv"
SUMMARY_FILE = "summary.csv"
POSITION_COLUMNS = (
    "index",
    "run",
    "direction",
    "target_mm",
    "measured_mm",
    "deviation_um",
    "sigma_um",
    "rms_px",
    "outlier",
    "straightness_um_1",
    "straightness_um_2",
    "roll_urad",
    "pitch_urad",
    "yaw_urad",
)
PLANAR_POSITION_COLUMNS = (  # SPEC 10
    "index",
    "run",
    "direction",
    "target_x_mm",
    "target_y_mm",
    "measured_x_mm",
    "measured_y_mm",
    "deviation_x_um",
    "deviation_y_um",
    "sigma_x_um",
    "sigma_y_um",
    "rms_px",
    "outlier",
)


def json_float(x: Any) -> float | None:
    """A float for results.json: NaN and inf become null."""
    x = float(x)
    return x if math.isfinite(x) else None


def assemble_results(
    *,
    method: str,
    settings: dict[str, Any],
    inputs: dict[str, Any],
    board: dict[str, Any],
    intrinsics: dict[str, Any],
    session_meta: dict[str, Any],
    parameters: dict[str, Any],
    positions: list[dict[str, Any]],
    figures: dict[str, Any],
    flags: list[dict[str, Any]],
    timings_s: dict[str, float],
    truth_comparison: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """The results.json document from its parts, in schema order; ``summary`` derived last.

    ``truth_comparison`` only for simulated sessions (the key is then present).
    """
    results: dict[str, Any] = {
        "format": FORMAT,
        "software": {"name": "lps-calib", "version": __version__},
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "method": method,
        "settings": settings,
        "inputs": inputs,
        "board": board,
        "intrinsics": intrinsics,
        "session_meta": session_meta,
        "parameters": parameters,
        "positions": positions,
        "figures": figures,
        "flags": flags,
        "timings_s": timings_s,
    }
    if truth_comparison is not None:
        results["truth_comparison"] = truth_comparison
    results["summary"] = summary_rows(results)
    return results


def summary_rows(results: dict[str, Any]) -> list[tuple[str, Any, str]]:
    """(name, value, unit) rows for summary.csv and the report's summary table."""
    p = results["parameters"]
    fig = results["figures"]
    single = fig.get("single_run") or {}
    rows: list[tuple[str, Any, str]] = [
        ("method", results["method"], ""),
        ("views", p["n_views"], ""),
        ("views_used", p["n_used"], ""),
        ("outlier_views", p["n_outliers"], ""),
        ("corner_noise_sigma", p["sigma_px"], "px"),
        ("rms_reprojection", p["rms_px"], "px"),
    ]
    for key, unit in (("mean_step_mm", "mm"), ("step_std_um", "um"), ("max_abs_deviation_um", "um"),
                      ("scale_ppm", "ppm"), ("periodic_amplitude_um", "um"), ("periodic_period_mm", "mm")):
        if key in single:
            rows.append((key.rsplit("_", 1)[0] if unit in key else key, single[key], unit))
    iso = fig.get("iso230_2") or {}
    for key in ("A_um", "R_um", "E_um", "B_um", "M_um", "A_up_um", "A_down_um", "R_up_um", "R_down_um", "E_up_um", "E_down_um"):
        if iso.get(key) is not None:
            rows.append((f"iso230_2_{key[:-3]}", iso[key], "um"))
    if fig.get("straightness_span_um"):
        rows.append(("straightness_span_1", fig["straightness_span_um"][0], "um"))
        rows.append(("straightness_span_2", fig["straightness_span_um"][1], "um"))
    for name, value in (fig.get("angles_span_urad") or {}).items():
        rows.append((f"{name}_span", value, "urad"))
    tc = results.get("truth_comparison") or {}
    if tc.get("position_rms_error_um") is not None:
        rows.append(("truth_position_rms_error", tc["position_rms_error_um"], "um"))
        rows.append(("truth_position_max_abs_error", tc["position_max_abs_error_um"], "um"))
    if tc.get("board_plane_rms_error_um") is not None:
        rows.append(("truth_board_plane_rms_error", tc["board_plane_rms_error_um"], "um"))
        rows.append(("truth_abbe_term_rms", tc["abbe_rms_um"], "um"))
    rows.append(("software_version", results["software"]["version"], ""))
    return rows


def _fmt(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return "" if value != value else f"{value:.6g}"
    return str(value)


def position_columns(results: dict[str, Any]) -> tuple[str, ...]:
    """The positions.csv columns: SPEC 7 for a line, SPEC 10 for a planar session."""
    return PLANAR_POSITION_COLUMNS if len(results.get("axes") or ["X"]) == 2 else POSITION_COLUMNS


def positions_csv(results: dict[str, Any]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    columns = position_columns(results)
    w.writerow(columns)
    for row in results["positions"]:
        w.writerow([_fmt(row.get(c)) for c in columns])
    return buf.getvalue()


def summary_csv(results: dict[str, Any]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(("name", "value", "unit"))
    for name, value, unit in results.get("summary", []):
        w.writerow((name, _fmt(value), unit))
    return buf.getvalue()


def write_results(folder: Path | str, results: dict[str, Any]) -> dict[str, Path]:
    """Write the three result files into ``folder``; returns their paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = {
        "positions": folder / POSITIONS_FILE,
        "summary": folder / SUMMARY_FILE,
        "results": folder / RESULTS_FILE,
    }
    write_text_atomic(paths["positions"], positions_csv(results))
    write_text_atomic(paths["summary"], summary_csv(results))
    write_json(paths["results"], results)
    return paths


def read_results(path: Path | str) -> dict[str, Any]:
    """Read results.json (a folder is taken to hold one)."""
    path = Path(path)
    if path.is_dir():
        path = path / RESULTS_FILE
    if not path.exists():
        raise InputError(f"{path}: no results yet; run `lps estimate {path.parent}` first")
    data = read_json(path, "results file")
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise InputError(f"{path}: not an {FORMAT} file; re-run `lps estimate`")
    return data
