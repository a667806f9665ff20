"""Camera panel: source choice, live preview with the detected board, focus figure.

The picture comes from :class:`PreviewGrabber` (a worker thread); a GUI timer
shows the newest frame with ``ImageItem.setImage(..., autoLevels=False)``, so
the preview never blocks the window whatever the camera does.
Exposure, gain, focus and white balance are offered where the device has them
(``camera/controls.py``) and locked while a capture borrows the camera; a jump
of brightness or sharpness between frames (an auto mode at work) is warned
about; "Grab view" stores the current frame as an intrinsics view.
"""
from __future__ import annotations

import logging
from pathlib import Path
from typing import Callable

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFileDialog,
    QGridLayout,
    QGroupBox,
    QLabel,
    QProgressBar,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

from lps_gui.camera import controls
from lps_gui.camera.base import Camera
from lps_gui.camera.frame_watch import FrameWatch
from lps_gui.core.geometry.board import Board
from lps_gui.gui.camera.preview import PreviewGrabber
from lps_gui.gui.fit import compact_buttons, guard_wheel
from lps_gui.gui.stage.sources import CAMERA_FOLLOWS_STAGE, camera_choices, open_camera_source

log = logging.getLogger(__name__)

REFRESH_MS = 33  # the GUI looks for a new frame 30 times a second
SHARPNESS_FULL_SCALE = 2000.0  # Laplacian-variance figure shown as a full bar


def _stream(camera: Camera, on: bool) -> None:
    """Continuous acquisition for the preview, fresh frames for a capture (SDK cameras; others have one mode)."""
    fn = getattr(camera, "set_streaming", None)
    if callable(fn):
        fn(on)


class CameraPanel(QWidget):
    """Live view through the camera; the simulated camera follows the simulated stage."""

    failed = Signal(str, str)  # title, one-line cause
    view_grabbed = Signal(object)  # Path of an image stored by "Grab view"
    _grab_failed = Signal(str)
    _opened = Signal(object)

    def __init__(self, board: Callable[[], Board], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.board = board
        self.camera: Camera | None = None
        self.sim_camera: Camera | None = None
        self.sim_expected = True  # the simulated stage is the default stage source: its camera is the default here
        self.grabber: PreviewGrabber | None = None
        self._shown = 0
        self.watch = FrameWatch()
        self.views_folder: Path | None = None
        self._views = 0
        self._locked = False
        self.control_widgets: dict[str, tuple[QDoubleSpinBox, QCheckBox | None]] = {}
        self.choice_widgets: dict[str, QComboBox] = {}

        self.source = QComboBox()
        self.source.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
        self.source.setMinimumContentsLength(12)  # a long label elides; the dock keeps its width
        self.open_btn = QPushButton("Start preview")
        top = QGridLayout()  # the button under the source: side by side they pushed Start preview off a laptop's screen
        top.addWidget(QLabel("Source"), 0, 0)
        top.addWidget(self.source, 0, 1)
        top.addWidget(self.open_btn, 1, 1, Qt.AlignmentFlag.AlignLeft)
        top.setColumnStretch(1, 1)

        self.view = pg.GraphicsLayoutWidget()
        self.view.setBackground("#202020")
        self.viewbox = self.view.addViewBox(lockAspect=True, invertY=True)
        self.image = pg.ImageItem(axisOrder="row-major")
        self.viewbox.addItem(self.image)
        self.overlay = pg.ScatterPlotItem(size=7, pen=pg.mkPen("#00e000", width=1.5), brush=None, symbol="o")
        self.viewbox.addItem(self.overlay)
        self.first_corner = pg.ScatterPlotItem(size=12, pen=pg.mkPen("#ff3030", width=2), brush=None, symbol="s")
        self.viewbox.addItem(self.first_corner)
        self.placeholder = pg.TextItem("no camera\nchoose a source,\nthen start the preview", color="#bbbbbb",
                                       anchor=(0.5, 0.5))  # short lines: a narrow dock does not clip them
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
        self.jump_label = QLabel("")
        self.jump_label.setWordWrap(True)
        self.jump_label.setStyleSheet("QLabel { color: #b00020; font-weight: bold; }")
        ig.addWidget(self.jump_label, 3, 0, 1, 3)
        self.grab_btn = QPushButton("Grab view")
        self.grab_btn.setToolTip("Store the current frame as a view for the intrinsics calibration")
        self.grab_btn.setEnabled(False)
        self.grab_btn.clicked.connect(self.grab_view)
        ig.addWidget(self.grab_btn, 2, 2)
        ig.setColumnStretch(1, 1)
        # what a frame says must not widen the dock (it scrolled sideways at 1000 px once a board was found)
        self.detect_label.setWordWrap(True)
        self.sharpness_bar.setMinimumWidth(40)
        compact_buttons(self.grab_btn)

        self.controls_box = QGroupBox("Camera controls")
        self.controls_grid = QGridLayout(self.controls_box)
        self.controls_note = QLabel("no adjustable controls (start a device preview)")
        self.controls_note.setStyleSheet("QLabel { color: #777777; }")
        self.controls_grid.addWidget(self.controls_note, 0, 0, 1, 3)

        lay = QVBoxLayout(self)
        lay.setContentsMargins(6, 6, 6, 6)
        lay.addLayout(top)
        lay.addWidget(self.view, 1)
        lay.addWidget(info)
        lay.addWidget(self.controls_box)
        self.controls_box.setVisible(False)

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
        for label, spec in camera_choices(camera is not None or self.sim_expected):
            self.source.addItem(label, spec)
        # the camera riding the simulated stage is the natural choice as soon as it exists (or is expected)
        i = self.source.findData(CAMERA_FOLLOWS_STAGE if camera is not None or current is None else current)
        self.source.setCurrentIndex(max(i, 0))

    def expect_sim_camera(self, on: bool) -> None:
        """The stage source is (or is no longer) the simulated rig: offer its camera before it connects."""
        if on != self.sim_expected:
            self.sim_expected = on
            self.set_sim_camera(self.sim_camera)
            if on and self.grabber is None:
                self.source.setCurrentIndex(max(self.source.findData(CAMERA_FOLLOWS_STAGE), 0))

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
        if spec == CAMERA_FOLLOWS_STAGE and self.sim_camera is None:
            self.failed.emit("Camera not opened", "simulated camera: it rides the simulated stage; connect that first "
                                                  "(Stage: Connect)")
            return False
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
            _stream(camera, not self._locked)  # an SDK camera previews at the device's own rate
            self.show_controls(camera)
            self.grab_btn.setEnabled(True)

    # ------------------------------------------------------------------ controls
    def show_controls(self, camera: Camera | None) -> None:
        """One spin box (and an "auto" box) per control the device reports; none for simulated or file cameras."""
        while self.controls_grid.count() > 1:
            item = self.controls_grid.takeAt(1)
            if item.widget() is not None:
                item.widget().deleteLater()
        self.control_widgets = {}
        self.choice_widgets = {}
        values = controls.available(camera) if camera is not None else {}
        autos = controls.auto_modes(camera) if camera is not None else {}
        choices = controls.choice_controls(camera) if camera is not None else {}
        self.controls_note.setVisible(not values and not choices)
        self.controls_box.setVisible(bool(values or choices))  # simulated and file cameras have none: no empty box
        for row, (name, value) in enumerate(values.items(), start=1):
            spin = QDoubleSpinBox()
            spin.setRange(-100000.0, 100000.0)
            spin.setDecimals(2)
            spin.setValue(value)
            spin.setKeyboardTracking(False)
            spin.valueChanged.connect(lambda v, n=name: self._set_control(n, v))
            auto = None
            if name in autos:
                auto = QCheckBox("auto")
                auto.setChecked(autos[name])
                auto.setToolTip("Automatic mode: changes between frames spoil a measurement; switch it off")
                auto.toggled.connect(lambda on, n=name: self._set_auto(n, on))
                spin.setEnabled(not autos[name])
            self.controls_grid.addWidget(QLabel(name.capitalize()), row, 0)
            self.controls_grid.addWidget(spin, row, 1)
            if auto is not None:
                self.controls_grid.addWidget(auto, row, 2)
            self.control_widgets[name] = (spin, auto)
        for row, (name, (value, offered)) in enumerate(choices.items(), start=len(values) + 1):
            combo = QComboBox()  # an SDK's enumerated control: pixel format, trigger, ISO, shutter speed...
            combo.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
            combo.setMinimumContentsLength(8)  # long symbolic names do not widen the window
            combo.addItems(list(offered))
            combo.setCurrentText(value)
            combo.currentTextChanged.connect(lambda v, n=name: self._set_control(n, v))
            self.controls_grid.addWidget(QLabel(name.capitalize()), row, 0)
            self.controls_grid.addWidget(combo, row, 1)
            self.choice_widgets[name] = combo
        guard_wheel(self.controls_box)  # built per camera: after the window guarded its own fields
        self.lock_controls(self._locked)

    def _set_control(self, name: str, value: float | str) -> None:
        if self.camera is not None and not controls.set_control(self.camera, name, value):
            log.warning("camera: the device refused %s = %s", name, value)
        self.watch.reset()

    def _set_auto(self, name: str, on: bool) -> None:
        if self.camera is not None and not controls.set_auto(self.camera, name, on):
            log.warning("camera: the device refused automatic %s %s", name, "on" if on else "off")
        spin, _ = self.control_widgets[name]
        spin.setEnabled(not on and not self._locked)
        self.watch.reset()

    def lock_controls(self, locked: bool) -> None:
        """During a capture nothing about the picture may change: the controls are read-only."""
        self._locked = locked
        for spin, auto in self.control_widgets.values():
            spin.setEnabled(not locked and not (auto is not None and auto.isChecked()))
            if auto is not None:
                auto.setEnabled(not locked)
        for combo in self.choice_widgets.values():
            combo.setEnabled(not locked)
        self.grab_btn.setEnabled(not locked and self.grabber is not None)

    # ------------------------------------------------------------------ intrinsics views
    def set_views_folder(self, folder: Path | str) -> None:
        self.views_folder = Path(folder)
        self.views_folder.mkdir(parents=True, exist_ok=True)
        self._views = len(list(self.views_folder.glob("view_*.png")))

    def grab_view(self) -> Path | None:
        """Store the frame on screen as ``view_NNN.png`` in the views folder (asked for once)."""
        image = self.last_image()
        if image is None:
            return None
        if self.views_folder is None:
            folder = QFileDialog.getExistingDirectory(self, "Folder for the intrinsics views")
            if not folder:
                return None
            self.set_views_folder(folder)
        import cv2

        from lps_gui.io.atomic import write_bytes_atomic

        assert self.views_folder is not None
        path = self.views_folder / f"view_{self._views:03d}.png"
        ok, buf = cv2.imencode(".png", np.ascontiguousarray(image))
        if not ok:
            self.failed.emit("View not stored", f"{path}: the frame could not be encoded")
            return None
        write_bytes_atomic(path, buf.tobytes())
        self._views += 1
        log.info("camera: view %d stored as %s", self._views, path)
        self.view_grabbed.emit(path)
        return path

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
        self.grab_btn.setEnabled(False)
        self.show_controls(None)
        self.watch.reset()
        self.jump_label.setText("")
        self.clear_display()

    def pause(self, on: bool) -> None:
        """Lend the camera to the capture engine (on) or take it back (off); the controls lock meanwhile."""
        if self.grabber is not None:
            self.grabber.pause(on)
        if self.camera is not None:
            _stream(self.camera, not on)  # a capture takes fresh frames, one acquisition each
        self.lock_controls(on)

    def clear_display(self) -> None:
        """No frozen last frame that looks live, nor the figures of that frame (after a stop, a lost camera,
        a disconnected stage)."""
        self.image.clear()
        self.overlay.setData([], [])
        self.first_corner.setData([], [])
        self.placeholder.setVisible(True)
        self.sharpness_bar.setValue(0)
        self.sharpness_label.setText("sharpness —")
        self.fps_label.setText("— fps")
        self._set_detect("no frame", "#777777")

    def _on_grab_failed(self, message: str) -> None:
        opened = self.camera is not None
        self.stop()
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
        jump = self.watch.check(res.image, res.sharpness if res.sharpness is not None else -1.0)  # -1: no figure
        if jump:
            if jump.split(":")[0] != self.jump_label.text().split(":")[0]:
                log.warning("camera: %s", jump)
            self.jump_label.setText(jump)
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
