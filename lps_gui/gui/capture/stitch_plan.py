"""The capture panel's stitching row: one board moved along the travel every N stops (SPEC 13).

0 stops (the default) is one placement, the plan as it is; N > 0 splits the
plan's targets into segments of N stops, each repeating the last M of the one
before (:func:`lps_gui.core.planning.segments.stitched_segments`). The capture
then pauses before each segment and says where to move the board.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

from PySide6.QtCore import Signal
from PySide6.QtWidgets import QHBoxLayout, QSpinBox, QWidget

from lps_gui.core.planning.plan import Plan


class StitchRow(QWidget):
    """Two spin boxes: segment length in stops (0: never move the board) and the overlap."""

    changed = Signal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.segment_stops = QSpinBox()
        self.segment_stops.setRange(0, 100_000)
        self.segment_stops.setSpecialValueText("never (one placement)")
        self.segment_stops.setSuffix(" stops")
        self.segment_stops.setToolTip("One board that covers part of the travel: capture it in segments of this many "
                                      "stops, moving the board between them (the capture pauses and says where)")
        self.overlap_stops = QSpinBox()
        self.overlap_stops.setRange(1, 1000)
        self.overlap_stops.setValue(3)
        self.overlap_stops.setPrefix("overlap ")
        self.overlap_stops.setToolTip("each segment repeats the last stops of the one before: they tie the segments")
        lay = QHBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self.segment_stops, 2)
        lay.addWidget(self.overlap_stops, 1)
        for w in (self.segment_stops, self.overlap_stops):
            w.valueChanged.connect(lambda _v: self.changed.emit())

    def apply(self, plan: Plan) -> Plan:
        """``plan`` in segments when a segment length is set (a one-axis plan only)."""
        n = self.segment_stops.value()
        if not n or plan.planar:
            return plan
        from lps_gui.core.planning.segments import stitched_segments

        return replace(plan, segments=stitched_segments(plan.targets(), n, self.overlap_stops.value()))

    def show_plan(self, plan: Any) -> None:
        """The row of a plan read back (a resumed session)."""
        segs = getattr(plan, "segments", None)
        if not segs:
            self.segment_stops.setValue(0)
            return
        n = len([t for t in plan.targets() if segs[0][0] - 1e-9 <= t <= segs[0][1] + 1e-9])
        self.segment_stops.setValue(n)
