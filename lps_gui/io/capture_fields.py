"""The fields of a captures.jsonl line, checked one by one with errors that name field and line.

Other capture scripts write ``time`` as ISO 8601; both that and unix seconds
are accepted. Index, run, targets and the file name are checked so a bad
line is reported where it is, not as a crash or a wrong answer later.
"""
from __future__ import annotations

import json
import math
from datetime import datetime
from pathlib import Path
from typing import Any

from lps_gui.errors import InputError
from lps_gui.io.session_paths import check_relative

MAX_INDEX = 10_000_000  # far above any plan (plans are limited well below this)
MAX_LINE_BYTES = 1 << 16
MAX_POSITION_MM = 1e6  # a kilometre of travel


def _int(d: dict[str, Any], key: str, default: int | None = None) -> int:
    v = d.get(key, default)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v != int(v):
        raise ValueError(f"field {key!r} must be a whole number, not {v!r}")
    if not 0 <= int(v) <= MAX_INDEX:
        raise ValueError(f"field {key!r} is {v!r}, outside 0..{MAX_INDEX}")
    return int(v)


def _float(d: dict[str, Any], key: str, optional: bool = False) -> float | None:
    v = d.get(key)
    if v is None and optional:
        return None
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ValueError(f"field {key!r} must be a finite number, not {v!r}")
    return float(v)


def _position(d: dict[str, Any], key: str, optional: bool = False) -> float | None:
    """A finite number of mm within any stage's travel (1e308 would overflow the solver)."""
    v = _float(d, key, optional)
    if v is not None and abs(v) > MAX_POSITION_MM:
        raise ValueError(f"field {key!r} is {v!r} mm, outside +-{MAX_POSITION_MM:g} mm")
    return v


def _coordinate(d: dict[str, Any], key: str, optional: bool = False) -> float | tuple[float, float] | None:
    """A position: a finite number (one axis) or [x, y] (a planar stage)."""
    v = d.get(key)
    if isinstance(v, (list, tuple)):
        if len(v) != 2:
            raise ValueError(f"field {key!r}: a planar position is [x, y], not {v!r}")
        x, y = (_position({key: c}, key) for c in v)
        return (x, y)
    return _position(d, key, optional)


def parse_time(v: Any) -> float:
    """Unix seconds from a number or an ISO 8601 string (no zone: local time)."""
    if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v):
        return float(v)
    if isinstance(v, str):
        try:
            return datetime.fromisoformat(v.strip().replace("Z", "+00:00")).timestamp()
        except ValueError:
            pass
    raise ValueError(f"field 'time' must be unix seconds or an ISO 8601 time, not {v!r}")


def capture_fields(d: Any) -> dict[str, Any]:
    """CaptureRecord keyword arguments from one parsed line."""
    if not isinstance(d, dict):
        raise ValueError("not a JSON object")
    for key in ("index", "run", "direction", "target_mm", "file"):
        if key not in d:
            raise ValueError(f"field {key!r} missing")
    direction = d["direction"]
    if direction not in ("+", "-"):
        raise ValueError(f"field 'direction' must be \"+\" or \"-\", not {direction!r}")
    if not isinstance(d["file"], str):
        raise ValueError(f"field 'file' must be a string, not {d['file']!r}")
    source = d.get("source")
    if source is not None and not isinstance(source, str):
        raise ValueError(f"field 'source' must be a string, not {source!r}")
    sha = d.get("sha256")
    if sha is not None and not isinstance(sha, str):
        raise ValueError(f"field 'sha256' must be a hex string, not {sha!r}")
    return {
        "index": _int(d, "index"),
        "run": _int(d, "run"),
        "direction": direction,
        "target_mm": _coordinate(d, "target_mm"),
        "reported_mm": _coordinate(d, "reported_mm", optional=True),
        "file": d["file"],
        "sha256": sha,
        "time": parse_time(d.get("time", 0.0)),
        "frame": _int(d, "frame", 0),
        "commanded_mm": _position(d, "commanded_mm", optional=True),
        "settle_s": _float(d, "settle_s", optional=True),
        "since_move_s": _float(d, "since_move_s", optional=True),
        "segment": None if d.get("segment") is None else _int(d, "segment"),  # a stitched capture's (SPEC 13)
        "source": source,  # "import" (SPEC 16)
    }


def parse_capture_lines(path: Path) -> list[dict[str, Any]]:
    """Every complete line of captures.jsonl as checked fields; a torn last line is ignored."""
    from lps_gui.io.image_file import read_file_limited

    raw = read_file_limited(path, 1 << 30, "captures file", follow_symlinks=False)
    lines = raw.split(b"\n")
    out: list[dict[str, Any]] = []
    seen: dict[int, int] = {}
    for n, line in enumerate(lines, 1):
        if not line.strip():
            continue
        last = n == len(lines)  # no newline after it: torn by a crash mid-append
        try:
            if len(line) > MAX_LINE_BYTES:
                raise ValueError(f"line is {len(line)} bytes long")
            fields = capture_fields(json.loads(line.decode("utf-8")))
        except (ValueError, RecursionError, UnicodeDecodeError) as exc:
            if last:
                continue
            why = "not valid JSON" if isinstance(exc, (json.JSONDecodeError, UnicodeDecodeError, RecursionError)) else str(exc)
            raise InputError(f"{path}: line {n} is not a capture record ({why}); fix the line or restore the file "
                             "from a backup") from None
        check_relative(fields["file"], f"{path}: line {n}")
        if fields["index"] in seen:
            raise InputError(f"{path}: line {n} repeats index {fields['index']} of line {seen[fields['index']]} "
                             "(two captures wrote at once?); remove the duplicate lines")
        seen[fields["index"]] = n
        out.append(fields)
    return out
