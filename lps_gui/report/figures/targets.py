"""Where each target of a row was seen, drawn under the deviation over the full travel (SPEC 13).

A row's positions are measured against different targets along the travel: a
printed scale error or a mounting flaw of one target shows only over the
stretch measured against it. The deviation plot (report and GUI alike, the
same :class:`FigureSpec`) gets one bar per target, in lanes below the data,
from the first to the last stop that saw it (results.json ``targets``
``stretch_mm``), so a step or slope in the deviation can be read against the
target boundaries. No Qt here.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from lps_gui.io.results.model import Results, as_results
from lps_gui.report.figures.spec import FigureSpec, Series

TARGET_COLORS = ("#3b3b3b", "#2a9d3c", "#c2185b", "#1b8a8a", "#b5651d", "#6a4c93")  # read in grey scale too
LANE_FRACTION = 0.08  # lane spacing as a fraction of the deviation's span
TARGET_LABEL = "seen by"  # legend: "seen by T0"


def target_stretches(results: Results | Mapping[str, Any] | None) -> list[tuple[str, float, float]]:
    """(id, first, last) X of the stops that saw each target (none without results); targets never seen are left out."""
    out = []
    for t in as_results(results).targets if results is not None else ():
        stretch = t.stretch
        if stretch is not None and stretch[0][0] is not None and stretch[1][0] is not None:
            lo, hi = float(stretch[0][0]), float(stretch[1][0])
            if np.isfinite(lo) and np.isfinite(hi):
                out.append((str(t.id), lo, hi))
    return out


def lanes(stretches: list[tuple[str, float, float]]) -> list[int]:
    """The lane of each stretch: the first lane whose last stretch ended before this one starts (interval colouring)."""
    ends: list[float] = []
    out = []
    for _, lo, hi in stretches:
        lane = next((k for k, end in enumerate(ends) if end < lo), len(ends))
        if lane == len(ends):
            ends.append(hi)
        else:
            ends[lane] = hi
        out.append(lane)
    return out


def with_target_stretches(figure: FigureSpec, results: Results | Mapping[str, Any] | None) -> FigureSpec:
    """``figure`` (the deviation vs target) with each target's stretch as a bar below the data."""
    stretches = target_stretches(results)
    if not stretches:
        return figure
    ys = [a for s in figure.series for a in (s.y, s.band_low, s.band_high) if a is not None]
    finite = np.concatenate([a[np.isfinite(a)] for a in ys]) if ys else np.zeros(0)
    low, high = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    gap = LANE_FRACTION * max(high - low, 1e-9)
    bars = [Series(np.array([lo, hi]), np.full(2, low - (lane + 1) * gap), f"{TARGET_LABEL} {name}", "line+markers",
                   TARGET_COLORS[j % len(TARGET_COLORS)])
            for j, ((name, lo, hi), lane) in enumerate(zip(stretches, lanes(stretches)))]
    note = "bars: the stretch of travel over which each target was seen (its print scale enters only there)"
    return replace(figure, series=list(figure.series) + bars,
                   notes="; ".join(n for n in (figure.notes, note) if n))
