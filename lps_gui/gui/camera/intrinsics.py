"""Intrinsics panel: board definition, calibration images, calibrate off the GUI thread, inspect, save/load.

Calibration is :func:`lps_gui.pipeline.intrinsics.calibrate_images` (what
``lps intrinsics`` runs). The panel shows each parameter with its standard
deviation (and the board's bow), thumbnails of the images with each one's
RMS, and the pictures of :mod:`lps_gui.report.pdf.intrinsics_pictures`
(per-view residuals, residual vector field, projection-uncertainty and
coverage maps with colour bars, the cross-validation map), the same ones the
intrinsics report prints. "Cross-validate" calibrates the even and the odd
images apart and compares the two (:mod:`lps_gui.core.intrinsics.crossval`).
"""
from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Callable

import numpy as np
from PySide6.QtCore import QSize, Qt, Signal
from PySide6.QtGui import QBrush, QColor, QIcon, QImage, QImageReader, QPixmap
from PySide6.QtWidgets import (
    QGridLayout,
    QDoubleSpinBox,
    QFileDialog,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QListWidget,
    QListWidgetItem,
    QPushButton,
    QSpinBox,
    QSplitter,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import INTRINSIC_NAMES, CameraIntrinsics
from lps_gui.gui.fit import compact_buttons
from lps_gui.gui.widgets import ValueTable, fmt
from lps_gui.gui.workers import Job, one_line

log = logging.getLogger(__name__)

IMAGE_FILTER = "Images (*.png *.jpg *.jpeg *.bmp *.tif *.tiff)"
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")
THUMB_PX = 96
UNITS = {"fx": "px", "fy": "px", "cx": "px", "cy": "px"}


def load_thumbnails(paths: list[Path], progress: Callable[..., None], cancel: Any) -> list[QImage]:
    """Scaled-down images (QImage is safe off the GUI thread; QPixmap is not)."""
    out = []
    for i, p in enumerate(paths):
        cancel.check("thumbnails")
        reader = QImageReader(str(p))
        size = reader.size()
        if size.isValid():
            reader.setScaledSize(size.scaled(THUMB_PX, THUMB_PX, Qt.AspectRatioMode.KeepAspectRatio))
        out.append(reader.read())
        progress(i + 1, len(paths), f"thumbnail {p.name}")
    return out


class PictureView(QLabel):
    """A QImage shown scaled to the label, keeping its aspect ratio."""

    def __init__(self, placeholder: str) -> None:
        super().__init__(placeholder)
        self.placeholder = placeholder
        self.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.setMinimumSize(200, 140)
        self.image: QImage | None = None

    def set_image(self, image: QImage | None) -> None:
        self.image = image
        self._rescale()

    def reset(self) -> None:
        """Back to the placeholder text: no picture of an earlier calibration stays."""
        self.image = None
        self.setPixmap(QPixmap())
        self.setText(self.placeholder)

    def resizeEvent(self, event: Any) -> None:  # noqa: N802 (Qt's name)
        super().resizeEvent(event)
        self._rescale()

    def _rescale(self) -> None:
        if self.image is None or self.image.isNull():
            return
        self.setPixmap(QPixmap.fromImage(self.image).scaled(self.size(), Qt.AspectRatioMode.KeepAspectRatio,
                                                            Qt.TransformationMode.SmoothTransformation))


class IntrinsicsPanel(QWidget):
    """Calibrate the camera from board images, or load a calibration."""

    run_requested = Signal(object)  # a Job for the main window to run, or the exception that stopped it
    intrinsics_changed = Signal(object)  # CameraIntrinsics
    saved = Signal(object)  # Path of the intrinsics file just written

    def __init__(self, start_dir: Callable[[], str] | None = None, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.start_dir = start_dir or (lambda: "")
        self.paths: list[Path] = []
        self.intrinsics: CameraIntrinsics | None = None
        self.calibration: Any = None
        self.crossval: Any = None
        self.job: Job | None = None

        self.cols = QSpinBox()
        self.cols.setRange(2, 200)
        self.cols.setValue(9)
        self.rows = QSpinBox()
        self.rows.setRange(2, 200)
        self.rows.setValue(6)
        self.square = QDoubleSpinBox()
        self.square.setRange(0.1, 1000.0)
        self.square.setDecimals(3)
        self.square.setValue(20.0)
        self.square.setSuffix(" mm")
        board_box = QGroupBox("Board (inner corners)")
        bl = QGridLayout(board_box)  # square under columns: one row of six was wider than a 1000 px screen's dock
        for i, (label, w) in enumerate((("columns", self.cols), ("rows", self.rows), ("square", self.square))):
            bl.addWidget(QLabel(label), i // 2, 2 * (i % 2))
            bl.addWidget(w, i // 2, 2 * (i % 2) + 1)
        bl.setColumnStretch(4, 1)

        self.list = QListWidget()
        self.list.setIconSize(QSize(THUMB_PX, THUMB_PX))
        self.list.setViewMode(QListWidget.ViewMode.ListMode)
        self.add_btn = QPushButton("Add images…")
        self.folder_btn = QPushButton("Add folder…")
        self.clear_btn = QPushButton("Clear")
        self.calib_btn = QPushButton("Detect && calibrate")
        self.cancel_btn = QPushButton("Cancel")
        self.cancel_btn.setEnabled(False)
        self.load_btn = QPushButton("Load…")
        self.save_btn = QPushButton("Save…")
        self.save_btn.setEnabled(False)
        self.crossval_btn = QPushButton("Cross-validate")
        self.crossval_btn.setToolTip("calibrate the even and the odd images apart and compare the two projections")
        self.crossval_btn.setEnabled(False)
        compact_buttons(self.add_btn, self.folder_btn, self.clear_btn, self.load_btn, self.save_btn, self.calib_btn,
                        self.crossval_btn, self.cancel_btn)
        row1 = QHBoxLayout()
        for b in (self.add_btn, self.folder_btn, self.clear_btn):
            row1.addWidget(b)
        files = QHBoxLayout()  # images, the intrinsics file, the actions: three rows fit a 1000 px screen's dock
        for b in (self.load_btn, self.save_btn):
            files.addWidget(b)
        files.addStretch(1)
        row2 = QHBoxLayout()
        for b in (self.calib_btn, self.crossval_btn, self.cancel_btn):
            row2.addWidget(b)
        self.message = QLabel("Add 6–30 images of the board in varied poses, then calibrate.")
        self.message.setWordWrap(True)

        self.table = ValueTable(["Parameter", "Value", "σ", "Unit"], stretch=0)
        self.pictures = {name: PictureView(f"{name}: calibrate first") for name in
                         ("Residuals per view", "Residual field", "Uncertainty", "Coverage", "Cross-validation")}
        self.pictures["Cross-validation"].setText("Cross-validation: calibrate, then press Cross-validate")
        tabs = QTabWidget()
        tabs.addTab(self.table, "Parameters")
        for name, view in self.pictures.items():
            tabs.addTab(view, name)
        self.tabs = tabs

        split = QSplitter(Qt.Orientation.Vertical)
        split.addWidget(self.list)
        split.addWidget(tabs)
        split.setStretchFactor(1, 2)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(6, 6, 6, 6)
        lay.addWidget(board_box)
        lay.addLayout(row1)
        lay.addLayout(files)
        lay.addLayout(row2)
        lay.addWidget(self.message)
        lay.addWidget(split, 1)

        self.add_btn.clicked.connect(self.add_dialog)
        self.folder_btn.clicked.connect(self.add_folder_dialog)
        self.clear_btn.clicked.connect(self.clear)
        self.calib_btn.clicked.connect(self.start)
        self.cancel_btn.clicked.connect(lambda: self.job and self.job.cancel())
        self.load_btn.clicked.connect(self.load_dialog)
        self.save_btn.clicked.connect(self.save_dialog)
        self.crossval_btn.clicked.connect(self.start_cross_validation)

    def board(self) -> Board:
        return Board(cols=self.cols.value(), rows=self.rows.value(), square_mm=self.square.value())

    def set_board(self, board: Board) -> None:
        self.cols.setValue(board.cols)
        self.rows.setValue(board.rows)
        self.square.setValue(board.square_mm)

    # ------------------------------------------------------------------ images
    def add_dialog(self) -> None:
        files, _ = QFileDialog.getOpenFileNames(self, "Calibration images", self.start_dir(), IMAGE_FILTER)
        self.add_images([Path(f) for f in files])

    def add_folder_dialog(self) -> None:
        folder = QFileDialog.getExistingDirectory(self, "Folder of calibration images", self.start_dir())
        if folder:
            self.add_images(sorted(p for p in Path(folder).iterdir() if p.suffix.lower() in IMAGE_SUFFIXES))

    def add_images(self, paths: list[Path]) -> None:
        new = [p for p in paths if p not in self.paths]
        if not new:
            return
        first = len(self.paths)
        self.paths += new
        for p in new:
            item = QListWidgetItem(p.name)
            item.setToolTip(str(p))
            self.list.addItem(item)
        job = Job("thumbnails", load_thumbnails, new)
        job.succeeded.connect(lambda images: self._set_thumbnails(first, images))
        self.run_requested.emit(job)

    def _set_thumbnails(self, first: int, images: list[QImage]) -> None:
        for k, img in enumerate(images):
            item = self.list.item(first + k)
            if item is not None and not img.isNull():
                item.setIcon(QIcon(QPixmap.fromImage(img)))

    def clear(self) -> None:
        self.paths = []
        self.list.clear()

    # ------------------------------------------------------------------ calibration
    def start(self) -> None:
        from lps_gui.pipeline.intrinsics import calibrate_images as calibrate

        if not self.paths:
            from lps_gui.errors import InputError

            self.run_requested.emit(InputError("intrinsics: add calibration images first"))
            return
        job = Job("intrinsics calibration", calibrate, list(self.paths), self.board())
        job.progress.connect(lambda d, t, m: self.message.setText(f"{m} ({d}/{t})" if m else f"{d}/{t}"))
        job.succeeded.connect(self.show_calibration)
        job.failed.connect(lambda msg, _tb: self.calibration_failed(f"failed: {msg}"))
        job.cancelled.connect(self.message.setText)
        job.finished.connect(self._finished)
        self.job = job
        self.calib_btn.setEnabled(False)
        self.cancel_btn.setEnabled(True)
        self.run_requested.emit(job)

    def calibration_failed(self, message: str) -> None:
        """A failed run leaves no parameters of an earlier one on screen, and nothing to save."""
        self.calibration = None
        self.intrinsics = None
        self.table.set_rows([])
        self.save_btn.setEnabled(False)
        self.crossval_btn.setEnabled(False)
        for picture in self.pictures.values():
            picture.reset()
        self.message.setText(message)

    def _finished(self) -> None:
        self.job = None
        self.calib_btn.setEnabled(True)
        self.crossval_btn.setEnabled(bool(getattr(self.calibration, "image_points", None)))
        self.cancel_btn.setEnabled(False)

    def start_cross_validation(self) -> None:
        from lps_gui.pipeline.intrinsics import cross_validate_calibration

        if self.calibration is None:
            return
        job = Job("cross-validation", cross_validate_calibration, self.calibration, self.board(), pass_progress=False)
        job.succeeded.connect(self.show_cross_validation)
        job.failed.connect(lambda msg, _tb: self.message.setText(f"cross-validation failed: {msg}"))
        job.finished.connect(self._finished)
        self.job = job
        self.calib_btn.setEnabled(False)
        self.crossval_btn.setEnabled(False)
        self.message.setText("cross-validating: calibrating the even and the odd images apart…")
        self.run_requested.emit(job)

    def show_cross_validation(self, crossval: Any) -> None:
        from lps_gui.report.pdf.intrinsics_pictures import crossval_picture

        self.crossval = crossval
        self.pictures["Cross-validation"].set_image(crossval_picture(crossval))
        self.tabs.setCurrentWidget(self.pictures["Cross-validation"])
        self.message.setText(crossval.diff.verdict())

    def show_calibration(self, calib: Any) -> None:
        """Show an IntrinsicsCalibration: parameters with std, per-view RMS, coverage, flagged views."""
        self.calibration = calib
        self.set_intrinsics(calib.intrinsics)
        rms = np.asarray(getattr(calib, "per_view_rms_px", []), float)  # shape (V,)
        flagged = set(int(i) for i in (getattr(calib, "flagged_views", None) or []))
        for i in range(self.list.count()):
            item = self.list.item(i)
            bad = i in flagged
            text = self.paths[i].name if i < len(self.paths) else item.text()
            if i < rms.size:
                text += f"   {rms[i]:.3f} px" + ("   ⚠ flagged" if bad else "")
            item.setText(text)
            item.setForeground(QBrush(QColor("#d00000" if bad else "#000000")))
        self._show_pictures(calib)
        self.crossval_btn.setEnabled(self.job is None and bool(getattr(calib, "image_points", None)))
        warnings = list(getattr(calib, "warnings", None) or [])
        self.message.setText(
            f"RMS {fmt(calib.intrinsics.rms_px)} px over {rms.size} views; {len(flagged)} flagged; "
            f"{len(getattr(calib, 'rejected_corners', []))} corner(s) rejected."
            + ("  " + " ".join(warnings) if warnings else ""))

    def _show_pictures(self, calib: Any) -> None:
        from lps_gui.report.pdf.intrinsics_pictures import (
            coverage_picture,
            per_view_errors,
            residual_field,
            uncertainty_picture,
        )

        if not getattr(calib, "residuals_px", None):
            return
        for name, draw in (("Residual field", residual_field), ("Residuals per view", per_view_errors),
                           ("Uncertainty", uncertainty_picture), ("Coverage", coverage_picture)):
            try:
                self.pictures[name].set_image(draw(calib))
            except Exception as exc:  # a picture that cannot be drawn must not hide the calibration
                log.warning("intrinsics picture %s not drawn: %s", name, one_line(exc))
        self.pictures["Cross-validation"].set_image(None)
        self.pictures["Cross-validation"].setPixmap(QPixmap())
        self.pictures["Cross-validation"].setText("Cross-validation: press Cross-validate")

    def set_intrinsics(self, intr: CameraIntrinsics) -> None:
        self.intrinsics = intr
        std = intr.std()
        values = intr.vector()
        rows = [(n, f"{v:.6g}", fmt(std[i], 3) if std is not None else "—", UNITS.get(n, ""))
                for i, (n, v) in enumerate(zip(INTRINSIC_NAMES, values))]
        bow, bow_sigma = intr.extra.get("board_warp_mm"), intr.extra.get("board_warp_sigma_mm")
        if bow is not None:
            for axis, v, sv in zip("xy", bow, bow_sigma or [None, None]):
                rows.append((f"board bow {axis}", f"{v:+.4f}", fmt(sv, 3) if sv is not None else "—", "mm"))
        rows.append(("image size", f"{intr.image_size[0]} × {intr.image_size[1]}", "", "px"))
        self.table.set_rows(rows)
        self.save_btn.setEnabled(True)
        self.intrinsics_changed.emit(intr)

    # ------------------------------------------------------------------ files
    def load_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Load intrinsics", self.start_dir(),
                                              "Intrinsics (*.json *.yaml *.yml *.xml *.cameramodel)")
        if path:
            self.load(Path(path))

    def load(self, path: Path) -> None:
        from lps_gui.io.intrinsics_file import read_intrinsics

        try:
            self.set_intrinsics(read_intrinsics(path))
            self.message.setText(f"loaded {path.name}")
        except Exception as exc:
            self.run_requested.emit(exc)

    def save_dialog(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Save intrinsics", str(Path(self.start_dir()) / "intrinsics.json"),
                                              "JSON (*.json);;OpenCV YAML (*.yaml);;mrcal (*.cameramodel)")
        if path:
            self.save(Path(path))

    def save(self, path: Path) -> None:
        from lps_gui.io.intrinsics_file import write_intrinsics

        if self.intrinsics is None:
            return
        try:
            write_intrinsics(path, self.intrinsics)
            self.message.setText(f"saved {path.name}")
            log.info("intrinsics saved to %s", path)
            self.saved.emit(path)
        except Exception as exc:
            log.error("intrinsics not saved: %s", one_line(exc))
            self.run_requested.emit(exc)
