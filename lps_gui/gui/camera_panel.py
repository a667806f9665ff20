"""Camera panel: source choice, live preview with the detected board, focus figure.

The picture comes from :class:`PreviewGrabber` (a worker thread); a GUI timer
shows the newest frame with ``ImageItem.setImage(..., autoLevels=False)``, so
the preview never blocks the window whatever the camera does.
"""
from __future__ import annotations

import logging
from typing import Callable

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QTimer, Signal
from PySide6.QtWidgets import (
    QComboBox, QGridLayout, QGroupBox, QHBoxLayout, QLabel, QProgressBar, QPushButton, QVBoxLayout, QWidget,
)

from lps_gui.camera.base import Camera
from lps_gui.core.board import Board
from lps_gui.gui.preview import PreviewGrabber
from lps_gui.gui.sources import CAMERA_FOLLOWS_STAGE, camera_choices, open_camera_source

log = logging.getLogger(__name__)

REFRESH_MS = 33  # the GUI looks for a new frame 30 times a second
SHARPNESS_FULL_SCALE = 2000.0  # Laplacian-variance figure shown as a full bar


class CameraPanel(QWidget):
    """Live view through the camera; the simulated camera follows the simulated stage."""

    failed = Signal(str, str)  # title, one-line cause
    _grab_failed = Signal(str)
    _opened = Signal(object)

    def __init__(self, board: Callable[[], Board], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.board = board
        self.camera: Camera | None = None
        self.sim_camera: Camera | None = None
        self.grabber: PreviewGrabber | None = None
        self._shown = 0

        self.source = QComboBox()
        self.open_btn = QPushButton("Start preview")
        top = QHBoxLayout()
        top.addWidget(QLabel("Source"))
        top.addWidget(self.source, 1)
        top.addWidget(self.open_btn)

        self.view = pg.GraphicsLayoutWidget()
        self.view.setBackground("#202020")
        self.viewbox = self.view.addViewBox(lockAspect=True, invertY=True)
        self.image = pg.ImageItem(axisOrder="row-major")
        self.viewbox.addItem(self.image)
        self.overlay = pg.ScatterPlotItem(size=7, pen=pg.mkPen("#00e000", width=1.5), brush=None, symbol="o")
        self.viewbox.addItem(self.overlay)
        self.first_corner = pg.ScatterPlotItem(size=12, pen=pg.mkPen("#ff3030", width=2), brush=None, symbol="s")
        self.viewbox.addItem(self.first_corner)
        self.placeholder = pg.TextItem("no camera — choose a source and start the preview", color="#bbbbbb", anchor=(0.5, 0.5))
        self.viewbox.addItem(self.placeholder)
        self.placeholder.setPos(320, 240)
        self.viewbox.setRange(xRange=(0, 640), yRange=(0, 480))

        info = QGroupBox("Focus and detection")
        ig = QGridLayout(info)
        self.detect_label = QLabel("no frame")
        self.sharpness_bar = QProgressBar()
        self.sharpness_bar.setRange(0, 1000)
        self.sharpness_bar.setTextVisible(False)
        self.sharpness_label = QLabel("sharpness —")
        self.fps_label = QLabel("— fps")
        ig.addWidget(QLabel("Board"), 0, 0)
        ig.addWidget(self.detect_label, 0, 1, 1, 2)
        ig.addWidget(QLabel("Focus"), 1, 0)
        ig.addWidget(self.sharpness_bar, 1, 1)
        ig.addWidget(self.sharpness_label, 1, 2)
        ig.addWidget(QLabel("Rate"), 2, 0)
        ig.addWidget(self.fps_label, 2, 1)
        ig.setColumnStretch(1, 1)

        lay = QVBoxLayout(self)
        lay.setContentsMargins(6, 6, 6, 6)
        lay.addLayout(top)
        lay.addWidget(self.view, 1)
        lay.addWidget(info)

        self.timer = QTimer(self)
        self.timer.setInterval(REFRESH_MS)
        self.timer.timeout.connect(self.refresh)
        self.open_btn.clicked.connect(self.toggle)
        self._grab_failed.connect(self._on_grab_failed)
        self._opened.connect(self._on_opened)
        self.set_sim_camera(None)
        self._set_detect("no frame", "#777777")

    # ------------------------------------------------------------------ sources
    def set_sim_camera(self, camera: Camera | None) -> None:
        """The stage panel connected (or dropped) the simulated rig: offer (or withdraw) its camera."""
        if camera is None and self.camera is not None and self.camera is self.sim_camera:
            self.stop()
        self.sim_camera = camera
        current = self.source.currentData()
        self.source.clear()
        for label, spec in camera_choices(camera is not None):
            self.source.addItem(label, spec)
        # the camera riding the simulated stage is the natural choice as soon as it exists
        i = self.source.findData(CAMERA_FOLLOWS_STAGE if camera is not None else current)
        self.source.setCurrentIndex(max(i, 0))

    def toggle(self) -> None:
        if self.grabber is not None:
            self.stop()
        else:
            self.start()

    def start(self) -> bool:
        """Start the preview of the chosen source; the camera opens on the preview thread.

        Returns False when the preview already runs. A source that cannot be
        opened is reported through :attr:`failed` (one line) and the panel
        returns to its idle state.
        """
        if self.grabber is not None:
            return False
        spec = self.source.currentData()
        sim = self.sim_camera if spec == CAMERA_FOLLOWS_STAGE else None
        source = sim if sim is not None else (lambda: open_camera_source(str(spec)))
        self._shown = 0
        self.grabber = PreviewGrabber(source, self.board, on_error=self._grab_failed.emit,
                                      on_open=self._opened.emit).start()
        self.timer.start()
        self.open_btn.setText("Stop preview")
        self.source.setEnabled(False)
        self.placeholder.setVisible(False)
        log.info("camera: preview of %s", self.source.currentText())
        return True

    def _on_opened(self, camera: Camera) -> None:
        if self.grabber is not None:
            self.camera = camera

    def stop(self) -> None:
        grabber, self.grabber = self.grabber, None
        if grabber is not None:
            grabber.stop()
            if self.camera is None and grabber.camera is not None:
                self.camera = grabber.camera
        self.timer.stop()
        if self.camera is not None and self.camera is not self.sim_camera:
            self.camera.close()
        self.camera = None
        self.open_btn.setText("Start preview")
        self.source.setEnabled(True)

    def pause(self, on: bool) -> None:
        """Lend the camera to the capture engine (on) or take it back (off)."""
        if self.grabber is not None:
            self.grabber.pause(on)

    def _on_grab_failed(self, message: str) -> None:
        opened = self.camera is not None
        self.stop()
        self.image.clear()  # no frozen last frame that looks live
        self.overlay.setData([], [])
        self.first_corner.setData([], [])
        self.placeholder.setVisible(True)
        self._set_detect("camera lost" if opened else "not opened", "#d00000")
        self.failed.emit("Camera preview stopped" if opened else "Camera not opened", message)

    # ------------------------------------------------------------------ painting (GUI thread)
    def refresh(self) -> None:
        res = self.grabber.latest() if self.grabber else None
        if res is None or res.number == self._shown:
            return
        first = self._shown == 0
        self._shown = res.number
        self.image.setImage(res.image, autoLevels=False, levels=(0, 255))
        if first:
            h, w = res.image.shape[:2]
            self.viewbox.setRange(xRange=(0, w), yRange=(0, h), padding=0.0)
        if res.corners_px is not None and len(res.corners_px):
            c = res.corners_px.reshape(-1, 2)
            self.overlay.setData(c[:, 0], c[:, 1])
            self.first_corner.setData(c[:1, 0], c[:1, 1])
            self._set_detect(f"found: {len(c)} corners", "#2a9d3c")
        else:
            self.overlay.setData([], [])
            self.first_corner.setData([], [])
            if res.detection_available:
                self._set_detect("not found", "#d00000")
            else:
                self._set_detect("detection not available yet in this build", "#777777")
        if res.sharpness is not None:
            self.sharpness_bar.setValue(int(min(1.0, res.sharpness / SHARPNESS_FULL_SCALE) * 1000))
            self.sharpness_label.setText(f"sharpness {res.sharpness:.0f}")
        self.fps_label.setText(f"{res.fps:.1f} fps")

    def _set_detect(self, text: str, color: str) -> None:
        self.detect_label.setText(text)
        self.detect_label.setStyleSheet(f"QLabel {{ color: {color}; font-weight: bold; }}")

    @property
    def frames_shown(self) -> int:
        return self._shown

    def last_image(self) -> np.ndarray | None:
        return self.image.image
