"""Stitched plans (one board moved along the travel): segments of stops that overlap (SPEC 13).

A user with one board that covers part of the travel captures it in
segments: the board stays put during a segment and is moved along before the
next, which starts by repeating the last stops of the one before (the overlap
ties the segments, :mod:`lps_gui.core.estimator.stitching`). A segment is the [first,
last] target of the plan's grid it covers; the plan visits each segment's
runs in turn and the capture pauses between segments for the board to be
moved. No I/O.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from lps_gui.errors import InputError

SAME_MM = 1e-9


def segments_from_list(items: Any) -> tuple[tuple[float, float], ...]:
    """session.json's ``plan.segments`` ([[first, last], ...] in mm) as a tuple of pairs."""
    if not isinstance(items, (list, tuple)) or not items:
        raise InputError("plan: segments must be a list of [first_mm, last_mm] pairs")
    out = []
    for k, seg in enumerate(items):
        if not (isinstance(seg, (list, tuple)) and len(seg) == 2
                and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in seg)):
            raise InputError(f"plan: segment {k} must be [first_mm, last_mm], not {seg!r}")
        out.append((float(seg[0]), float(seg[1])))
    return tuple(out)


def check_segments(segments: Any, targets: np.ndarray) -> tuple[tuple[float, float], ...]:
    """The segments, checked: ascending, each on at least 3 of the plan's targets, each sharing a stop with the next."""
    segs = segments_from_list(segments)
    x = np.asarray(targets, float)
    if x.ndim != 1:
        raise InputError("plan: segments (one moved board) are for a one-axis plan")
    counts = []
    for k, (a, b) in enumerate(segs):
        inside = x[(x >= a - SAME_MM) & (x <= b + SAME_MM)]
        if b < a or inside.size < 3:
            raise InputError(f"plan: segment {k} [{a:g}, {b:g}] mm covers {inside.size} targets; give at least 3")
        counts.append(inside)
    for k in range(len(segs) - 1):
        if not np.intersect1d(np.round(counts[k], 9), np.round(counts[k + 1], 9)).size:
            raise InputError(f"plan: segments {k} and {k + 1} share no target; let each segment start a few stops "
                             f"before the last one ended (the overlap ties them)")
    covered = np.zeros(x.size, bool)
    for a, b in segs:
        covered |= (x >= a - SAME_MM) & (x <= b + SAME_MM)
    if not covered.all():
        raise InputError(f"plan: target {x[~covered][0]:g} mm is in no segment; the segments must cover the plan")
    return segs


def stitched_segments(targets: np.ndarray, segment_stops: int, overlap_stops: int = 3) -> tuple[tuple[float, float], ...]:
    """Segments of ``segment_stops`` consecutive targets, each starting ``overlap_stops`` before the last one ended."""
    x = np.sort(np.asarray(targets, float))
    if not 1 <= overlap_stops < segment_stops:
        raise InputError(f"plan: the overlap ({overlap_stops} stops) must be at least 1 and less than a segment "
                         f"({segment_stops} stops)")
    if segment_stops >= x.size:
        return ((float(x[0]), float(x[-1])),)
    out, first = [], 0
    while True:
        last = min(first + segment_stops - 1, x.size - 1)
        out.append((float(x[first]), float(x[last])))
        if last == x.size - 1:
            return tuple(out)
        first = last - overlap_stops + 1


def board_move_mm(segments: tuple[tuple[float, float], ...], k: int) -> float:
    """How far to move the board along the travel before segment ``k``: the advance of the segment's first stop."""
    return segments[k][0] - segments[k - 1][0]
