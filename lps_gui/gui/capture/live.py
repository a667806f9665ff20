"""The capture panel's live results: the deviation plot growing stop by stop, the flags, the report at the end.

:class:`LivePanel` attaches a :class:`lps_gui.pipeline.live.LiveCapture` to
the capture's engine on the worker thread; its events cross to the GUI
thread through a queued signal. The plot is the report's deviation figure
(:func:`lps_gui.report.figures.plots.deviation_figure`, mean with its +-2 sigma
band) drawn by :mod:`lps_gui.gui.results.plot_adapter` in small steps, one
event-loop turn each, so the window stays responsive while the estimate
grows. Each flag is listed with its frame the moment it is found; the
operator pauses, fixes and resumes with the capture buttons.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QObject, Qt, QTimer, Signal
from PySide6.QtWidgets import QCheckBox, QGroupBox, QLabel, QListWidget, QVBoxLayout, QWidget

from lps_gui.gui.results.plot_adapter import DrawnFigure, figure_steps
from lps_gui.io.results.keys import DEVIATION_UM, SIGMA_TOTAL_UM


class _Bridge(QObject):
    event = Signal(object)  # a LiveEvent, emitted on the live thread, delivered on the GUI thread


class LivePanel(QGroupBox):
    """Live results of the running capture (detection, running estimate, checks) and its final report."""

    report_ready = Signal(object)  # Path of the PDF written when the capture completed
    flagged = Signal(object)  # a LiveFlag, the moment it is found (the capture panel pauses on it when asked)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__("Live results", parent)
        self.enabled = QCheckBox("Detect, estimate, check; then report")  # short: a laptop's dock
        self.enabled.setChecked(True)
        self.pause_on_flag = QCheckBox("Pause the capture at a flag")
        self.pause_on_flag.setToolTip("Stop after the frame being taken when a check flags something: fix it, then Resume")
        self.enabled.setToolTip("Each frame is detected as it is written (corners.vnl), the positions estimated every "
                                "few stops and checked; when the last frame is written, results.json and report.pdf follow")
        self.plot = pg.PlotWidget(background="w")
        self.plot.setFixedHeight(260)  # the panel sits in a dock under the plan: a fixed size, nothing squeezed
        self.flags = QListWidget()
        self.flags.setMaximumHeight(90)
        self.flags.setWordWrap(True)  # a flag says what to check: the whole line, not a scroll bar
        self.flags.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.status = QLabel("")
        self.status.setWordWrap(True)
        lay = QVBoxLayout(self)
        for w in (self.enabled, self.pause_on_flag, self.plot, self.flags, self.status):
            lay.addWidget(w)
        self.drawn: DrawnFigure | None = None
        self.n_views = 0
        self.report: Path | None = None
        self._pending: dict[str, Any] | None = None
        self._steps: list[Any] = []
        self._bridge = _Bridge()
        self._bridge.event.connect(self._on_event)

    # ------------------------------------------------------------------ worker thread
    def attach(self, engine: Any, on: bool) -> Any:
        """A started LiveCapture on ``engine`` when ``on`` (the box, read on the GUI thread), else None (worker thread)."""
        if not on:
            return None
        from lps_gui.pipeline.live import LiveCapture, LiveEvent

        why = LiveCapture.unsupported(engine.session)
        if why:
            self._bridge.event.emit(LiveEvent("error", why))
            return None
        live = LiveCapture(engine)
        live.subscribe(self._bridge.event.emit)
        live.start()
        return live

    def finish(self, live: Any, summary: Any) -> None:
        """The final estimate and the report of a complete capture (worker thread); a paused one waits.

        A failure here is shown in the panel: the capture itself is complete and kept.
        """
        from lps_gui.errors import LpsError
        from lps_gui.pipeline.live import LiveEvent

        if live is None:
            return
        try:
            live.finish(summary, report=True)
        except LpsError as exc:
            self._bridge.event.emit(LiveEvent("error", f"live results: {exc}"))

    # ------------------------------------------------------------------ GUI thread
    def set_planar(self, planar: bool) -> None:
        """A planar plan: no deviation-against-target plot (its axes are one-dimensional); the flags and the
        status stay. The plot of an earlier line capture goes too."""
        self.clear()
        self.plot.setVisible(not planar)

    def clear(self) -> None:
        self.flags.clear()
        self.plot.getPlotItem().clear()
        self.status.setText("")
        self.drawn, self.n_views, self.report, self._pending, self._steps = None, 0, None, None, []

    def _on_event(self, event: Any) -> None:
        if event.kind == "flag":
            self.flags.addItem(event.message)
            self.flags.scrollToBottom()
            self.flagged.emit(event.data)
        elif event.kind == "estimate":
            data = event.data
            self.status.setText(f"running estimate: {data['n_views']} views, corner noise {data['sigma_px']:.3f} px")
            self._pending = data
            if not self._steps:
                self._draw_next()
        elif event.kind == "results":  # the final estimate's positions replace the running one's
            from lps_gui.report.figures.plots import position_columns

            cols = position_columns(event.data)
            self.status.setText(f"results: {event.message}")
            self._pending = {key: cols[key] for key in ("target_mm", DEVIATION_UM, "sigma_um", SIGMA_TOTAL_UM, "outlier",
                                                        "direction") if key in cols}
            self._pending["n_views"] = len(cols["target_mm"])
            self._pending["title"] = f"Deviation ({len(cols['target_mm'])} views, final estimate)"
            if not self._steps:
                self._draw_next()
        elif event.kind == "report":
            self.report = Path(event.data)
            self.status.setText(f"report: {self.report}")
            self.report_ready.emit(self.report)
        elif event.kind == "error":
            self.status.setText(event.message)

    def _draw_next(self) -> None:
        """The latest estimate's figure, one drawing step per event-loop turn (a newer one replaces the rest)."""
        if not self._steps and self._pending is not None:
            from lps_gui.report.figures.plots import deviation_figure

            data, self._pending = self._pending, None
            cols = {"target_mm": np.asarray(data["target_mm"], float), DEVIATION_UM: np.asarray(data[DEVIATION_UM], float),
                    "sigma_um": np.asarray(data["sigma_um"], float), "outlier": np.asarray(data["outlier"], bool),
                    "direction": np.asarray(data["direction"], dtype=object)}
            if data.get(SIGMA_TOTAL_UM) is not None:  # the band draws the total sigma (plots.drawn_sigma_um)
                cols[SIGMA_TOTAL_UM] = np.asarray(data[SIGMA_TOTAL_UM], float)
            fig = deviation_figure(cols, None)
            fig = replace(fig, title=data.get("title") or f"Live deviation ({data['n_views']} views)")
            self.drawn, self._steps = figure_steps(self.plot.getPlotItem(), fig)
            self.n_views = int(data["n_views"])
        if self._steps:
            self._steps.pop(0)()
            QTimer.singleShot(0, self, self._draw_next)  # dropped with the panel
