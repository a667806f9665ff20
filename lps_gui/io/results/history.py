"""Results history: every estimate of a session is kept, the latest is recorded, stale reports are named.

``lps estimate`` writes the latest results at the top of the session folder
(results.json, positions.csv, summary.csv: what every reader opens) and a
copy into ``results/<created>-<method>/``; ``results/latest.json`` records
which one is the latest. A top-level results.json from before the history
existed is copied into the history before it is replaced, so re-running an
estimate (or another method) never loses a result. No symlinks: a plain
record survives copies to any file system.
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from lps_gui.errors import InputError
from lps_gui.file_limits import resolve_in_session
from lps_gui.io.atomic import write_bytes_atomic
from lps_gui.io.file_set import write_file_set
from lps_gui.io.jsonfile import json_bytes, read_json
from lps_gui.io.results.document import POSITIONS_FILE, RESULTS_FILE, SUMMARY_FILE, result_set_bytes

HISTORY_DIR = "results"
LATEST_FILE = "latest.json"
REPORT_FILE = "report.pdf"
SET = (RESULTS_FILE, POSITIONS_FILE, SUMMARY_FILE)


def entry_name(results: dict[str, Any]) -> str:
    """``20261201T162004-joint``: the results' creation time and method, safe as a folder name."""
    created = re.sub(r"[^0-9T]", "", str(results.get("created") or "")[:19]) or "undated"
    method = re.sub(r"[^A-Za-z0-9_-]", "_", str(results.get("method") or "unknown"))
    return f"{created}-{method}"


def _copy_set(src: Path, dest: Path) -> None:
    """Copy the result set into ``dest`` as one checked set (a full disk leaves no half copy)."""
    write_file_set(dest, {name: (src / name).read_bytes() for name in SET if (src / name).is_file()}, last=RESULTS_FILE)


def history_dir(session_dir: Path | str) -> Path:
    """The session's results/ folder; InputError when it is a link or leads out of the session (never written
    or read there: a history run would land in someone else's folder)."""
    folder = Path(session_dir)
    base = folder / HISTORY_DIR
    if base.is_symlink():
        raise InputError(f"{base}: is a symbolic link; a session's result history stays inside the session: "
                         "remove the link (lps creates the folder)")
    return resolve_in_session(folder, HISTORY_DIR)


def keep_previous(session_dir: Path | str) -> Path | None:
    """Copy the top-level result set into the history unless it is there already; returns its folder."""
    folder = Path(session_dir)
    top = folder / RESULTS_FILE
    if not top.is_file():
        return None
    kept = _kept_as_latest(folder)
    if kept is not None:
        return kept
    try:
        previous = read_json(top, "results file", follow_symlinks=False)
    except Exception:  # an unreadable old file is kept where it is, never a reason to stop an estimate
        return None
    dest = folder / HISTORY_DIR / entry_name(previous if isinstance(previous, dict) else {})
    if not (dest / RESULTS_FILE).exists():
        _copy_set(folder, dest)
    return dest


def _kept_as_latest(folder: Path) -> Path | None:
    """The history entry results/latest.json names, if its results.json is byte for byte the top-level one.

    The usual case (the top-level set is the one the last estimate recorded):
    a comparison of bytes instead of parsing a results.json of megabytes for
    its creation time and method.
    """
    try:
        name = (read_json(history_dir(folder) / LATEST_FILE, "results history", follow_symlinks=False) or {}).get("latest")
        if not isinstance(name, str) or not name or "/" in name or name in (".", ".."):
            return None
        entry = folder / HISTORY_DIR / name
        top, kept = folder / RESULTS_FILE, entry / RESULTS_FILE
        if kept.stat().st_size != top.stat().st_size or kept.read_bytes() != top.read_bytes():
            return None
    except Exception:  # no or unreadable record: the full check decides
        return None
    return entry


def _new_entry(folder: Path, results: dict[str, Any]) -> Path:
    dest = folder / HISTORY_DIR / entry_name(results)
    n = 1
    while (dest / RESULTS_FILE).exists() and read_json(dest / RESULTS_FILE, "results file", follow_symlinks=False) != results:
        n += 1  # two estimates within one second: keep both
        dest = folder / HISTORY_DIR / f"{entry_name(results)}-{n}"
    return dest


def _latest_record(dest: Path, results: dict[str, Any]) -> bytes:
    return json_bytes({"latest": dest.name, "created": results.get("created"), "method": results.get("method")})


def record_latest(session_dir: Path | str, results: dict[str, Any]) -> Path:
    """After the top-level set was written: copy it into the history and record it as the latest."""
    folder = Path(session_dir)
    dest = _new_entry(folder, results)
    _copy_set(folder, dest)
    write_bytes_atomic(folder / HISTORY_DIR / LATEST_FILE, _latest_record(dest, results))
    return dest


def commit_results(session_dir: Path | str, results: dict[str, Any]) -> Path:
    """Write a new result set into the session folder as one commit; returns its history entry.

    The previous set is kept first, then the new set's history copy is written; only then are the top-level
    results.json, positions.csv, summary.csv and results/latest.json replaced, in one journaled commit
    (:func:`lps_gui.io.file_set.write_file_set`). A full disk at any step leaves the old set (and latest.json
    naming it) in place, a kill leaves the old set or a journal the next command finishes.
    """
    folder = Path(session_dir)
    history_dir(folder)  # refused before anything is written when results/ leads out of the session
    keep_previous(folder)
    files = result_set_bytes(results)
    dest = _new_entry(folder, results)
    write_file_set(dest, files, last=RESULTS_FILE)
    write_file_set(folder, {**files, f"{HISTORY_DIR}/{LATEST_FILE}": _latest_record(dest, results)}, last=RESULTS_FILE)
    return dest


def history(session_dir: Path | str) -> list[dict[str, Any]]:
    """Every kept result set, oldest first: ``{"name", "path", "created", "method", "latest"}``."""
    base = history_dir(session_dir)
    latest = None
    if (base / LATEST_FILE).is_file():
        latest = (read_json(base / LATEST_FILE, "results history", follow_symlinks=False) or {}).get("latest")
    out = []
    sets = [p for p in base.glob("*") if (p / RESULTS_FILE).is_file()]
    for d in sorted(sets, key=lambda p: ((p / RESULTS_FILE).stat().st_mtime, p.name)):  # copies keep the mtime
        meta = read_json(d / RESULTS_FILE, "results file", follow_symlinks=False)
        out.append({"name": d.name, "path": d, "created": meta.get("created"), "method": meta.get("method"),
                    "latest": d.name == latest})
    return out


def stale_report_message(session_dir: Path | str) -> str | None:
    """A sentence when report.pdf is older than results.json (the report shows superseded results)."""
    folder = Path(session_dir)
    report, results = folder / REPORT_FILE, folder / RESULTS_FILE
    if report.is_file() and results.is_file() and report.stat().st_mtime < results.stat().st_mtime:
        return (f"{report}: older than {results.name} (results were re-estimated); "
                f"run `lps report {folder}` for a report of the latest results")
    return None
