"""The line-by-line corners.vnl reader and writer as they were before issue 15: the reference the numpy one must match."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from lps_gui.errors import InputError
from lps_gui.io.corners.vnl import HEADER, CornerTable


def format_corners_vnl(table: CornerTable) -> str:
    lines = [HEADER]
    for key, value in table.meta.items():
        lines.append(f"## {key} = {value}")
    for name, reason in table.failed.items():
        lines.append(f"## failed {name}: {reason.replace(chr(10), ' ')}")
    for name, corners in zip(table.names, table.corners_px):
        if name in table.failed or not np.isfinite(corners).any():
            lines.append(f"{name} - - -")
            continue
        for x, y in corners.tolist():  # Python floats format ~3x faster than numpy scalars
            lines.append(f"{name} - - -" if not (math.isfinite(x) and math.isfinite(y)) else f"{name} {x:.4f} {y:.4f} 0")
    return "\n".join(lines) + "\n"


def read_corners_vnl(path: Path | str, n_corners: int) -> CornerTable:
    """Read corners.vnl, checking every view against the board's corner count.

    Raises InputError naming the file and the fix when the file is empty,
    truncated, holds NaNs, or a view has another number of corners.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{path}: corners file not found; run `lps detect` first") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read corners ({exc}); delete it and run `lps detect` again") from exc
    if not text.strip():
        raise InputError(f"{path}: is empty; delete it and run `lps detect` on the session")
    rows: dict[str, list[tuple[float, float]]] = {}
    failed: dict[str, str] = {}
    meta: dict[str, str] = {}
    saw_header = False
    for lineno, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("##"):
            body = line[2:].strip()
            if body.startswith("failed "):
                name, _, reason = body[7:].partition(":")
                failed[name.strip()] = reason.strip()
            elif "=" in body:
                k, _, v = body.partition("=")
                meta[k.strip()] = v.strip()
            continue
        if line.startswith("#"):
            saw_header = saw_header or line.split()[1:4] == ["filename", "x", "y"]
            continue
        fields = line.split()
        if len(fields) < 3:
            raise InputError(f"{path}: line {lineno} is truncated ({raw!r}); delete the file and run `lps detect` again")
        name, xs, ys = fields[0], fields[1], fields[2]
        level = fields[3] if len(fields) > 3 else "0"
        if xs == "-" or ys == "-" or level in ("-", "-1"):
            xy = (np.nan, np.nan)
        else:
            try:
                xy = (float(xs), float(ys))
            except ValueError:
                raise InputError(f"{path}: line {lineno} has non-numeric x/y ({raw!r}); regenerate with `lps detect`") from None
            if not (np.isfinite(xy[0]) and np.isfinite(xy[1])):
                raise InputError(f"{path}: line {lineno} holds NaN/inf; write missing corners as '- - -' or re-run `lps detect`")
        rows.setdefault(name, []).append(xy)
    if not saw_header:
        raise InputError(f"{path}: missing the '{HEADER}' header; not a corners file, regenerate it with `lps detect`")
    if not rows:
        raise InputError(f"{path}: holds no corners; run `lps detect` on the session")
    names = list(rows)
    corners = np.full((len(names), n_corners, 2), np.nan)
    for i, name in enumerate(names):
        pts = rows[name]
        if len(pts) == 1 and not np.isfinite(pts[0][0]):
            failed.setdefault(name, "board not found")
            continue
        if len(pts) != n_corners:
            raise InputError(
                f"{path}: {name} has {len(pts)} corners but the board has {n_corners}; "
                "check inner_corners in board.json or re-run `lps detect`"
            )
        corners[i] = pts
    return CornerTable(names, corners, failed, meta)
