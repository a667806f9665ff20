"""corners.vnl of a session with targets (SPEC 13): ``# filename target corner x y``.

One row per identified corner (target = its id, corner = r * cols + c); a view
in which no target was found is one ``filename - - - -`` row, its reason in a
``## failed <filename>: <reason>`` comment as in the single-board file. In
memory the corners are one dense (K, N, 2) array over the targets' corners
laid end to end (target j's corners at ``offsets[j]`` ...), NaN where not
seen, so every solver sees a view as one set of points.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from lps_gui.core.geometry.targets import Target, target_offsets
from lps_gui.errors import InputError
from lps_gui.io.atomic import write_bytes_atomic
from lps_gui.io.corners.vnl_fast import comment_fields

HEADER = "# filename target corner x y"
MAX_FILE_BYTES = 2 << 30  # ~10^7 views x corners; past that the file is not a session's


@dataclass
class TargetCornerTable:
    """Corners of many views of many targets."""

    names: list[str]
    targets: list[str]  # target ids, in session order
    offsets: np.ndarray  # (len(targets) + 1,)
    corners_px: np.ndarray  # (K, offsets[-1], 2), NaN where missing
    failed: dict[str, str] = field(default_factory=dict)
    meta: dict[str, str] = field(default_factory=dict)
    sha256: str | None = field(default=None, compare=False)

    def target_corners(self, j: int) -> np.ndarray:
        """Target j's corners in every view, (K, n_j, 2)."""
        return self.corners_px[:, self.offsets[j]: self.offsets[j + 1]]

    def seen(self) -> np.ndarray:
        """Corners seen per view and target, (K, n_targets) int."""
        ok = np.isfinite(self.corners_px[..., 0])
        return np.add.reduceat(ok, self.offsets[:-1], axis=1) if ok.shape[1] else np.zeros((len(self.names), 0), int)


def empty_table(names: list[str], targets: list[Target]) -> TargetCornerTable:
    offsets = target_offsets(targets)
    return TargetCornerTable(list(names), [t.id for t in targets], offsets,
                             np.full((len(names), offsets[-1], 2), np.nan))


def target_corners_bytes(table: TargetCornerTable) -> bytes:
    lines = [HEADER]
    lines += [f"## {key} = {value}" for key, value in table.meta.items()]
    lines += [f"## failed {name}: {reason.replace(chr(10), ' ')}" for name, reason in table.failed.items()]
    which = np.repeat(np.arange(len(table.targets)), np.diff(table.offsets))
    number = np.arange(table.offsets[-1]) - table.offsets[which]
    for i, name in enumerate(table.names):
        xy = table.corners_px[i]
        seen = np.flatnonzero(np.isfinite(xy).all(axis=1))
        if not len(seen):
            lines.append(f"{name} - - - -")
            continue
        lines += [f"{name} {table.targets[which[k]]} {number[k]} {xy[k, 0]:.4f} {xy[k, 1]:.4f}" for k in seen]
    return ("\n".join(lines) + "\n").encode("utf-8")


def write_target_corners(path: Path | str, table: TargetCornerTable) -> None:
    if any(any(ch.isspace() for ch in n) for n in table.names):
        raise InputError("corners.vnl: file names with spaces cannot be stored; rename the images")
    write_bytes_atomic(path, target_corners_bytes(table))


def is_target_layout(path: Path | str) -> bool:
    """Whether a corners.vnl has the SPEC 13 header (a session with targets) rather than the single-board one."""
    with open(path, "rb") as fh:
        return fh.readline(200).strip().split() == HEADER.encode().split()


def read_target_corners(path: Path | str, targets: list[Target]) -> TargetCornerTable:
    """Read a SPEC 13 corners.vnl; every error names the file, the line and what to do."""
    path = Path(path)
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise InputError(f"{path}: {size} bytes is too large for a corners file; run lps detect again")
    data = path.read_bytes()
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not a text file ({exc.reason}); run lps detect again") from exc
    lines = text.splitlines()
    if not lines or lines[0].split() != HEADER.split():
        raise InputError(f"{path}: the first line must be '{HEADER}' (a session with targets); run lps detect again")
    index = {t.id: j for j, t in enumerate(targets)}
    offsets = target_offsets(targets)
    counts = np.diff(offsets)
    failed, meta, _ = comment_fields([line for line in lines[1:] if line.lstrip().startswith("#")])
    fast = _regular_rows(lines[1:], index, offsets)
    if fast is not None:  # the file as lps detect writes it, at numpy speed; anything else (and every error) below
        return TargetCornerTable(fast[0], [t.id for t in targets], offsets, fast[1], failed, meta,
                                 sha256=hashlib.sha256(data).hexdigest())
    names: list[str] = []
    slot: dict[str, int] = {}
    rows: list[tuple[int, int, float, float]] = []
    for lineno, line in enumerate(lines[1:], start=2):
        if line.lstrip().startswith("#"):
            continue
        tok = line.split()
        if not tok:
            continue
        if len(tok) != 5:
            raise InputError(f"{path}:{lineno}: expected 'filename target corner x y', got {len(tok)} fields")
        name = tok[0]
        if name not in slot:
            slot[name] = len(names)
            names.append(name)
        if tok[1:] == ["-", "-", "-", "-"]:
            continue
        j = index.get(tok[1])
        if j is None:
            raise InputError(f"{path}:{lineno}: target {tok[1]!r} is not in session.json targets "
                             f"({', '.join(index)}); run lps detect again")
        try:
            c = int(tok[2])
            x, y = float(tok[3]), float(tok[4])
        except ValueError as exc:
            raise InputError(f"{path}:{lineno}: corner, x and y must be numbers ({exc})") from exc
        if not 0 <= c < counts[j]:
            raise InputError(f"{path}:{lineno}: corner {c} of {tok[1]} is outside 0-{counts[j] - 1}")
        if not (np.isfinite(x) and np.isfinite(y) and abs(x) < 1e6 and abs(y) < 1e6):
            raise InputError(f"{path}:{lineno}: corner position ({tok[3]}, {tok[4]}) is not a pixel position")
        rows.append((slot[name], offsets[j] + c, x, y))
    corners = np.full((len(names), offsets[-1], 2), np.nan)
    if rows:
        a = np.array(rows)
        corners[a[:, 0].astype(int), a[:, 1].astype(int)] = a[:, 2:]
    return TargetCornerTable(names, [t.id for t in targets], offsets, corners, failed, meta,
                             sha256=hashlib.sha256(data).hexdigest())


def _regular_rows(lines: list[str], index: dict[str, int], offsets: np.ndarray) -> tuple[list[str], np.ndarray] | None:
    """Names (first appearance order) and corners (K, N, 2) when every row is well formed, else None."""
    body = [line for line in lines if line.strip() and not line.lstrip().startswith("#")]
    tok = " ".join(body).split()
    if len(tok) != 5 * len(body):
        return None
    names = tok[0::5]
    slots = {name: k for k, name in enumerate(dict.fromkeys(names))}
    dash = [t == "-" for t in tok[1::5]]
    if any(d and row != ["-", "-", "-"] for d, row in zip(dash, zip(tok[2::5], tok[3::5], tok[4::5]))):
        return None
    keep = [k for k, d in enumerate(dash) if not d]
    try:
        j = np.array([index[tok[5 * k + 1]] for k in keep], int)
        c = np.array([tok[5 * k + 2] for k in keep], int)
        xy = np.stack([np.array([tok[5 * k + 3] for k in keep], float), np.array([tok[5 * k + 4] for k in keep], float)],
                      axis=1) if keep else np.empty((0, 2))
    except (KeyError, ValueError):
        return None
    counts = np.diff(offsets)
    if keep and (np.any(c < 0) or np.any(c >= counts[j]) or not np.all(np.isfinite(xy)) or np.any(np.abs(xy) >= 1e6)):
        return None
    corners = np.full((len(slots), offsets[-1], 2), np.nan)
    if keep:
        corners[np.array([slots[names[k]] for k in keep]), offsets[j] + c] = xy
    return list(slots), corners
