"""results.json, positions.csv and summary.csv (SPEC 7).

results.json is the complete, versioned record (schema in
docs/ARCHITECTURE.md); the CSVs are views of it for spreadsheets. All three
are written as one set (:func:`lps_gui.io.file_set.write_file_set`): all
three to checked temp files, then renamed together, results.json last, so a
full disk leaves the old set whole and a reader never sees a results.json
whose CSVs are from another run.
"""
from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any

from lps_gui.errors import InputError
from lps_gui.io.file_set import write_file_set
from lps_gui.io.jsonfile import json_bytes, read_json

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


def _fmt(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return "" if value != value else f"{value:.6g}"
    return str(value)


def positions_csv(results: dict[str, Any]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(POSITION_COLUMNS)
    for row in results["positions"]:
        w.writerow([_fmt(row.get(c)) for c in POSITION_COLUMNS])
    return buf.getvalue()


def summary_csv(results: dict[str, Any]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(("name", "value", "unit"))
    for name, value, unit in results.get("summary", []):
        w.writerow((name, _fmt(value), unit))
    return buf.getvalue()


def write_results(folder: Path | str, results: dict[str, Any]) -> dict[str, Path]:
    """Write the three result files into ``folder``; returns their paths.

    A ``folder`` ending in ``.json`` names the results file itself; its CSVs
    go beside it as ``<stem>-positions.csv`` and ``<stem>-summary.csv``.
    """
    folder, names = _result_names(Path(folder))
    files = {
        names["positions"]: positions_csv(results).encode("utf-8"),
        names["summary"]: summary_csv(results).encode("utf-8"),
        names["results"]: json_bytes(results),
    }
    written = write_file_set(folder, files, last=names["results"])
    return {key: written[name] for key, name in names.items()}


def _result_names(path: Path) -> tuple[Path, dict[str, str]]:
    if path.suffix.lower() != ".json" or path.is_dir():
        return path, {"positions": POSITIONS_FILE, "summary": SUMMARY_FILE, "results": RESULTS_FILE}
    if path.name == RESULTS_FILE:
        return path.parent, {"positions": POSITIONS_FILE, "summary": SUMMARY_FILE, "results": RESULTS_FILE}
    return path.parent, {"positions": f"{path.stem}-{POSITIONS_FILE}", "summary": f"{path.stem}-{SUMMARY_FILE}",
                         "results": path.name}


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
