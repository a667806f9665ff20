"""Where each imported image was taken: from a step, from the file names, or from a CSV (SPEC 16).

No stage reported these positions, so they are the user's word: every rule
that fills in what the user did not say (image order, direction, run) is
written here once and named in the docs. Directions and runs not given are
read from the positions themselves (:func:`infer_passes`): a sweep that
goes back is a backward pass, a sweep in the first direction again is the
next run.
"""
from __future__ import annotations

import csv
import io
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

import numpy as np

from lps_gui.camera.folder_replay import natural_key
from lps_gui.core.planning.plan import Plan
from lps_gui.errors import InputError

NUMBER = r"[-+]?(?:\d+(?:[.,]\d*)?|[.,]\d+)(?:[eE][-+]?\d+)?"
FIELDS = {"mm": NUMBER, "index": r"\d+", "run": r"\d+", "dir": r"[-+]|fwd|bwd|forward|backward|f|b"}
DIRECTION_WORDS = {"+": "+", "fwd": "+", "forward": "+", "f": "+", "-": "-", "bwd": "-", "backward": "-", "b": "-"}
CSV_HEADER = ("file", "target", "direction", "run")


@dataclass(frozen=True)
class ImageStop:
    """One imported image: its file (relative to the images folder, '/'-separated) and where it was taken."""

    file: str
    target_mm: float
    direction: str  # "+" or "-"
    run: int


def stops_from_step(files: list[str], start_mm: float, step_mm: float, directions: str = "+",
                    runs: int = 1) -> list[ImageStop]:
    """Images in natural name order on the plan a capture with the same switches would have run.

    The images are ``runs`` runs of one pass per direction, each pass over the
    same targets ``start_mm + k * step_mm`` (upward forward, downward backward),
    exactly as `lps capture --start --step --directions --runs` lists them.
    """
    if not (math.isfinite(step_mm) and step_mm > 0):
        raise InputError(f"--step {step_mm:g}: give a positive step in mm (images taken downward: --directions -)")
    passes = runs * (2 if directions == "both" else 1)
    if len(files) % passes or len(files) < 2 * passes:
        raise InputError(f"{len(files)} images do not split into {passes} pass(es) of at least 2 targets "
                         f"({runs} run(s), directions {directions}); check --runs and --directions")
    m = len(files) // passes
    plan = Plan(start_mm=start_mm, stop_mm=start_mm + (m - 1) * step_mm, step_mm=step_mm, directions=directions,
                runs=runs, overshoot_mm=0.0, settle_s=0.0)
    return [ImageStop(f, float(s.target_mm), s.direction, s.run) for f, s in zip(files, plan.stops())]


def name_pattern(pattern: str) -> re.Pattern[str]:
    """The regular expression of a ``--from-names`` pattern: ``{mm}`` (required), ``{index}``, ``{run}``, ``{dir}``, ``*``."""
    parts = re.split(r"(\{[a-z]*\}|\*)", pattern)
    out, seen = [], set()
    for part in parts:
        if part == "*":
            out.append(".*?")
        elif part.startswith("{") and part.endswith("}"):
            name = part[1:-1]
            if name not in FIELDS:
                raise InputError(f"--from-names {pattern!r}: unknown field {part}; use {{mm}}, {{index}}, {{run}}, {{dir}}")
            if name in seen:
                raise InputError(f"--from-names {pattern!r}: {part} appears twice; give each field once")
            seen.add(name)
            out.append(f"(?P<{name}>{FIELDS[name]})")
        else:
            out.append(re.escape(part))
    if "mm" not in seen:
        raise InputError(f"--from-names {pattern!r}: no {{mm}} field; give a pattern like 'pos_{{mm}}.png'")
    return re.compile("".join(out) + r"\Z", re.IGNORECASE)


def _mm(text: str) -> float:
    return float(text.replace(",", "."))


def stops_from_names(files: list[str], pattern: str, where: str = "") -> list[ImageStop]:
    """Positions (and index, run, direction when the pattern has them) read from the file names.

    Order: by ``{index}`` when the pattern has it, else natural name order with ``{mm}`` compared as a number,
    then grouped by ``{run}`` and by ``{dir}`` (forward first) when given, a
    pass ordered by position (upward forward, downward backward).
    """
    rx = name_pattern(pattern)
    rows = []
    for f in files:
        m = rx.match(Path(f).name)
        if m is None:
            raise InputError(f"{where}{f}: the name does not match --from-names {pattern!r} (no number where {{mm}} "
                             "is); rename it, move it out of the folder or fix the pattern")
        g = m.groupdict()
        name, mm = Path(f).name, _mm(g["mm"])
        order = (natural_key(name[:m.start("mm")]), mm, natural_key(name[m.end("mm"):]))  # the number as a number
        rows.append((f, mm, int(g["index"]) if g.get("index") else None,
                     int(g["run"]) if g.get("run") else None, DIRECTION_WORDS[g["dir"].lower()] if g.get("dir") else None,
                     order))
    if "index" in rx.groupindex:
        seen: dict[int, str] = {}
        for f, _, index, *_ in rows:
            if index in seen:
                raise InputError(f"{where}{f}: index {index} again (also {seen[index]}); each image needs its own {{index}}")
            seen[index] = f
        rows.sort(key=lambda r: r[2])
    else:
        rows.sort(key=lambda r: r[5])
        if "run" in rx.groupindex or "dir" in rx.groupindex:
            rows.sort(key=lambda r: (r[3] or 0, r[4] == "-", r[1] if r[4] != "-" else -r[1]))
    return complete([(f, mm, d, run) for f, mm, _, run, d, _ in rows])


def stops_from_csv(text: str, where: str) -> tuple[list[ImageStop], list[int]]:
    """Rows ``file,target[,direction,run]`` (a header line optional), in the order listed, and their line numbers."""
    rows = []
    for n, row in enumerate(csv.reader(io.StringIO(text)), 1):
        cells = [c.strip() for c in row]
        if not any(cells) or cells[0].startswith("#"):
            continue
        if n == 1 and cells[0].lower() == "file":
            continue
        if len(cells) not in (2, 4):
            raise InputError(f"{where}: line {n} has {len(cells)} fields; give file,target or file,target,direction,run")
        try:
            target = _mm(cells[1])
            if not math.isfinite(target):
                raise ValueError
        except ValueError:
            raise InputError(f"{where}: line {n}: target {cells[1]!r} is not a number of mm") from None
        direction = run = None
        if len(cells) == 4:
            direction = DIRECTION_WORDS.get(cells[2].lower())
            if direction is None:
                raise InputError(f"{where}: line {n}: direction {cells[2]!r} is not + or -")
            if not cells[3].isdigit() or int(cells[3]) < 1:
                raise InputError(f"{where}: line {n}: run {cells[3]!r} is not a whole number from 1")
            run = int(cells[3])
        rows.append((cells[0], target, direction, run, n))
    if not rows:
        raise InputError(f"{where}: no rows; give one line file,target[,direction,run] per image")
    given = {r[2] is not None for r in rows}
    if len(given) > 1:
        n = next(r[4] for r in rows if (r[2] is None) == (rows[0][2] is not None))
        raise InputError(f"{where}: line {n}: give direction and run on every line or on none")
    seen: dict[str, int] = {}
    for f, *_, n in rows:
        if f in seen:
            raise InputError(f"{where}: line {n}: {f} is listed again (line {seen[f]}); list each image once")
        seen[f] = n
    return complete([r[:4] for r in rows]), [r[4] for r in rows]


def complete(rows: Iterable[tuple[str, float, str | None, int | None]]) -> list[ImageStop]:
    """Stops from (file, mm, direction or None, run or None): what is missing read from the positions."""
    rows = list(rows)
    targets = np.array([r[1] for r in rows], dtype=float)
    directions, runs = infer_passes(targets)
    return [ImageStop(f, float(mm), d or directions[i], run or runs[i]) for i, (f, mm, d, run) in enumerate(rows)]


def infer_passes(targets: np.ndarray, tol_mm: float = 1e-9) -> tuple[list[str], list[int]]:
    """The direction and run of each image from the sequence of its positions.

    Images at one position in a row are one stop. A pass is a run of stops
    moving one way; at a turn, the images of the turning stop are shared
    between the pass arriving and the pass leaving (an odd one stays with
    the arriving pass), as a capture lists both ends of a forward-backward
    sweep. A single move back whose stops are single images is a return to
    the start (the next pass, not a pass of its own). A run ends where a pass
    in the first direction begins again.
    """
    n = len(targets)
    if n == 0:
        return [], []
    change = np.flatnonzero(np.abs(np.diff(targets)) > tol_mm) + 1
    starts = np.concatenate([[0], change])
    counts = np.diff(np.concatenate([starts, [n]]))
    moves = np.sign(np.diff(targets[starts]))  # one per pair of stops
    if moves.size == 0:
        return ["+"] * n, [1] * n
    returns = _lone_moves_back(moves, counts)
    moves[returns] = -moves[returns]  # a return joins the pass it starts
    # each stop's pass sign: the move arriving at it, the first stop the move leaving it
    arriving = np.concatenate([[moves[0]], moves])
    leaving = np.concatenate([moves, [moves[-1]]])
    sign = np.repeat(arriving, counts)
    for k in np.flatnonzero(arriving != leaving):  # a turning stop: its later images leave with the next pass
        if counts[k] > 1:
            first = starts[k] + (counts[k] + 1) // 2
            sign[first:starts[k] + counts[k]] = leaving[k]
    first_dir = sign[0]
    new_run = np.concatenate([[False], (sign[1:] == first_dir) & (sign[:-1] != first_dir)])
    new_run[starts[1:][returns]] = True  # the stop a return arrives at starts the next run
    runs = 1 + np.cumsum(new_run)
    return ["+" if s > 0 else "-" for s in sign], [int(r) for r in runs]


def _lone_moves_back(moves: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Which moves are returns to the start: a lone move against two passes the same way, single images at both ends."""
    k = np.arange(1, moves.size - 1)
    lone = (moves[k - 1] == moves[k + 1]) & (moves[k] != moves[k + 1]) & (counts[k] == 1) & (counts[k + 1] == 1)
    out = np.zeros(moves.size, dtype=bool)
    out[k[lone]] = True
    return out


def plan_of(stops: list[ImageStop]) -> Plan:
    """session.json's plan for imported images: their targets, directions and runs as found (no moves planned)."""
    targets = sorted({round(s.target_mm, 9) for s in stops})
    if len(targets) < 2:
        raise InputError(f"all {len(stops)} images are at {targets[0]:g} mm; give images at two positions at least")
    dirs = {s.direction for s in stops}
    groups: dict[tuple[int, str, float], int] = {}
    for s in stops:
        key = (s.run, s.direction, round(s.target_mm, 9))
        groups[key] = groups.get(key, 0) + 1
    return Plan(targets_mm=tuple(targets), directions="both" if len(dirs) == 2 else dirs.pop(),
                runs=max(s.run for s in stops), frames_per_stop=max(groups.values()), overshoot_mm=0.0, settle_s=0.0)
