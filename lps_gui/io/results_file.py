"""results.json, positions.csv and summary.csv (SPEC 7).

results.json is the complete, versioned record (schema in
docs/ARCHITECTURE.md); the CSVs are views of it for spreadsheets. All three
are written atomically, results.json last, so a reader never sees a
results.json whose CSVs are missing.
"""
from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any

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
