"""What a plot is, as plain data: :class:`Series`, :class:`FigureSpec` and the report's colours.

The figures of a line and of a plane (:mod:`lps_gui.report.figures.plots`, the planar
pages a section there) build these, and the painters (PDF and GUI) draw them.
No Qt here.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

# Colours that print and read in grey scale: blue / orange, black truth, red outliers.
FORWARD_COLOR = "#1f5fa8"
BACKWARD_COLOR = "#e07b00"
TRUTH_COLOR = "#222222"
TRUTH_COLORS = {"+": "#0d2747", "-": "#6b3500"}  # truth per direction: dark shades of the measured colours
SPEC_COLOR = "#c00000"
OUTLIER_COLOR = "#d00000"
IMAGE_ROTATION_COLOR = "#111111"
COMPONENT_COLORS = ("#1f5fa8", "#2a9d3c", "#a8326e")

STYLES = ("line", "markers", "line+markers")
DIRECTION_NAMES = {"+": "forward", "-": "backward"}
DIRECTION_ARROWS = {"+": "\u2191", "-": "\u2193"}


@dataclass(frozen=True)
class Series:
    """One curve: ``y`` against ``x``; bands and outlier marks are optional.

    ``band_low``/``band_high`` (same shape as ``y``) bound a shaded band,
    typically mean +- 2 sigma. ``marked`` (bool, same shape) picks the points
    drawn as outliers (a red cross), named ``marked_label`` in a legend. ``dashed`` draws the line dashed (truth).
    """

    x: np.ndarray  # shape (n,)
    y: np.ndarray  # shape (n,)
    label: str
    style: str = "line"  # one of STYLES
    color: str = FORWARD_COLOR
    band_low: np.ndarray | None = None  # shape (n,)
    band_high: np.ndarray | None = None  # shape (n,)
    marked: np.ndarray | None = None  # shape (n,), bool
    dashed: bool = False
    marked_label: str = "outlier"  # what a red cross means here (the ASME step figure: a stuck step)

    def finite(self) -> "Series":
        """The same series without points whose x or y is not finite."""
        ok = np.isfinite(self.x) & np.isfinite(self.y)
        if ok.all():
            return self

        def pick(a: np.ndarray | None) -> np.ndarray | None:
            return None if a is None else a[ok]

        return Series(self.x[ok], self.y[ok], self.label, self.style, self.color,
                      pick(self.band_low), pick(self.band_high), pick(self.marked), self.dashed, self.marked_label)


@dataclass(frozen=True)
class FigureSpec:
    """One plot: stable ``key`` (for tests and the GUI's tab names), labels with units."""

    key: str
    title: str
    x_label: str
    y_label: str
    series: list[Series] = field(default_factory=list)
    notes: str = ""
    x_log: bool = False

    def is_empty(self) -> bool:
        return not any(np.isfinite(s.y).any() for s in self.series)




def num_or_nan(v: Any) -> float:
    """A results.json number as float; NaN when absent or not a number."""
    try:
        return float(v) if v is not None else np.nan
    except (TypeError, ValueError):
        return np.nan
