"""One capture up close: its image, the detected corners and the reprojection residuals.

The residual of a corner is detected minus predicted, where the prediction
is the fitted LPS line at the view's estimated position (t_i = l0 + s_i n,
SPEC 3). Vectors are magnified so sub-pixel residuals are visible.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QLabel, QVBoxLayout, QWidget

from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.models.lps_model import LpsLine
from lps_gui.errors import InputError
from lps_gui.io.image_file import decode_image
from lps_gui.io.results.keys import MEASURED_MM
from lps_gui.io.results.model import Results
from lps_gui.io.results.sections import Position

ARROW_GAIN = 50.0  # residual vectors drawn this many times longer than they are


@dataclass
class ViewResiduals:
    """Corners of one view and their residual vectors (px)."""

    detected_px: np.ndarray  # shape (N, 2), NaN where missing
    predicted_px: np.ndarray  # shape (N, 2)
    rms_px: float  # per corner, the residual as a vector (the estimate reports per coordinate: this / sqrt 2)

    @property
    def residual_px(self) -> np.ndarray:
        return self.detected_px - self.predicted_px  # shape (N, 2)


def view_residuals(results: Results, row: Position, detected_px: np.ndarray,
                   object_points: np.ndarray) -> ViewResiduals | None:
    """Residuals of one view under the fitted line, or None when the results lack the line.

    ``measured_mm`` may be reported relative to the gauge view; both readings
    are tried and the one that reproduces the view better is kept.
    """
    from lps_gui.io.intrinsics_file import intrinsics_from_dict

    p = results.parameters.raw  # the fitted line's vectors
    try:
        line = LpsLine(np.asarray(p["R_cam_board"], float).reshape(3, 3), np.asarray(p["l0_cam_mm"], float),
                       np.asarray(p["n_cam"], float))
        intr = intrinsics_from_dict(results.intrinsics.raw if results.intrinsics else {}, "results.json")
        s_mm = float(row.raw[MEASURED_MM])
    except (KeyError, TypeError, ValueError, InputError):
        return None
    first = min(results.positions, key=lambda r: r.index)
    candidates = {s_mm, s_mm - (first.number(MEASURED_MM) or 0.0)}
    best: ViewResiduals | None = None
    for s in candidates:
        t = line.translations(np.array([s]))[0]
        pred = project_board(line.R_cam_board, t, object_points, intr)  # shape (N, 2)
        r = detected_px - pred
        ok = np.isfinite(r).all(axis=1)
        rms = float(np.sqrt(np.mean(np.sum(r[ok] ** 2, axis=1)))) if ok.any() else np.inf
        if best is None or rms < best.rms_px:
            best = ViewResiduals(detected_px, pred, rms)
    return best


class ViewDetail(QWidget):
    """Shows the clicked capture: image, corners (green), residuals x ARROW_GAIN (red)."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.title = QLabel("Click a point in a plot to see its image and residuals.")
        self.title.setWordWrap(True)
        self.view = pg.GraphicsLayoutWidget()
        self.view.setBackground("#202020")
        self.box = self.view.addViewBox(lockAspect=True, invertY=True)
        self.image = pg.ImageItem(axisOrder="row-major")
        self.box.addItem(self.image)
        self.corners = pg.ScatterPlotItem(size=5, pen=pg.mkPen("#00e000"), brush=None)
        self.box.addItem(self.corners)
        self.arrows = pg.PlotCurveItem(pen=pg.mkPen("#ff4040", width=1.5), connect="pairs")
        self.sensor = pg.PlotCurveItem(pen=pg.mkPen("#808080", width=1, style=Qt.PenStyle.DashLine))
        self.box.addItem(self.sensor)
        self.box.addItem(self.arrows)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self.title)
        lay.addWidget(self.view, 1)
        self.shown_index: int | None = None

    def clear(self) -> None:
        """Nothing shown: new results came (the previous session's view must not stay beside them)."""
        self.shown_index = None
        self.image.clear()
        for item in (self.corners, self.arrows, self.sensor):
            item.setData([], [])
        self.title.setText("Click a point in a plot to see its image and residuals.")

    def show_view(self, session_dir: Path | None, results: Results, row: Position,
                  detected_px: np.ndarray | None, object_points: np.ndarray | None) -> None:
        self.shown_index = row.index

        def value(key: str) -> float:
            v = row.number(key)
            return np.nan if v is None else v

        text = (f"view {row.index}  run {row.run} {row.direction}  "
                f"target {value('target_mm'):.3f} mm  deviation {value('deviation_um'):.2f} µm  "
                f"RMS per coordinate {value('rms_px'):.3f} px")
        if row.outlier:
            text += f"  — OUTLIER: {row.outlier_reason or 'flagged'}"
        image = None
        if session_dir is not None and row.file:
            path = Path(session_dir) / row.file
            if path.exists():
                from lps_gui.io.session_paths import read_session_file

                try:  # inside the session, size and pixel count checked before decoding
                    image = decode_image(read_session_file(session_dir, row.file), str(path))
                except InputError:
                    image = None
        self.sensor.setData([], [])
        if image is not None:
            self.image.setImage(image, autoLevels=False, levels=(0, 255))
            self.box.setRange(xRange=(0, image.shape[1]), yRange=(0, image.shape[0]), padding=0.0)
        else:
            self.image.clear()
            text += "  (image not in the session)"
            size = results.intrinsics.image_size if results.intrinsics else ()
            if size:  # show where the corners sit on the sensor
                w, h = float(size[0]), float(size[1])
                self.sensor.setData([0, w, w, 0, 0], [0, 0, h, h, 0])
                self.box.setRange(xRange=(0, w), yRange=(0, h), padding=0.02)
        if detected_px is not None and object_points is not None:
            ok = np.isfinite(detected_px).all(axis=1)
            self.corners.setData(detected_px[ok, 0], detected_px[ok, 1])
            res = view_residuals(results, row, detected_px, object_points)
            if res is not None:
                tips = res.detected_px + ARROW_GAIN * res.residual_px
                pairs = np.stack([res.detected_px[ok], tips[ok]], axis=1).reshape(-1, 2)  # shape (2M, 2)
                self.arrows.setData(pairs[:, 0], pairs[:, 1], connect="pairs")
                text += (f"\nresiduals ×{ARROW_GAIN:g} (red), recomputed RMS per coordinate "
                         f"{res.rms_px / np.sqrt(2.0):.3f} px (per corner, as a vector: {res.rms_px:.3f} px)")
            else:
                self.arrows.setData([], [])
        else:
            self.corners.setData([], [])
            self.arrows.setData([], [])
            text += "\nno detected corners for this view (corners.vnl missing)"
        self.title.setText(text)
