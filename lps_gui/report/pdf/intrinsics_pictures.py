"""Pictures of an intrinsics calibration, painted into QImages for the GUI panel and the PDF alike.

- residual vector field: every corner's reprojection error as an arrow at
  its place in the image, magnified (rejected corners red);
- per-view residual magnitudes: RMS and largest error of each view (flagged
  views red);
- projection-uncertainty map: worst-direction sigma (px) over the image,
  log colour scale, after the best-fitting rotation is taken out;
- coverage map: corners per image cell;
- cross-validation: the difference of the two halves' projections over the
  image in units of their combined sigma.

Heat maps are coloured by OpenCV's viridis map and carry a colour bar.
Qt is imported inside functions only (the report layer's rule).
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from lps_gui.report.pdf.text_fit import TextLog, draw_text, font

if TYPE_CHECKING:
    from lps_gui.core.intrinsics.calibration import IntrinsicsCalibration
    from lps_gui.core.intrinsics.crossval import CrossValidation

PICTURE_PX = (1500, 1000)  # width, height of every picture
BLUE, RED, GREY = "#1f5fa8", "#d00000", "#808080"


def _viridis(values01: np.ndarray) -> np.ndarray:
    """RGB uint8 (..., 3) of values in [0, 1] (NaN -> grey)."""
    import cv2

    v = np.nan_to_num(np.clip(values01, 0.0, 1.0), nan=0.0)
    rgb = cv2.applyColorMap((v * 255).astype(np.uint8).reshape(-1, 1), cv2.COLORMAP_VIRIDIS)[:, 0, ::-1]
    rgb = rgb.reshape(np.shape(values01) + (3,)).copy()
    rgb[~np.isfinite(values01)] = (200, 200, 200)
    return rgb


class _Canvas:
    """A white picture with a title, an image-shaped frame and room for a colour bar on the right."""

    def __init__(self, title: str, image_size: tuple[int, int] | None, colour_bar: bool = False,
                 log: TextLog | None = None) -> None:
        from PySide6.QtCore import QRectF
        from PySide6.QtGui import QColor, QImage, QPainter

        from lps_gui.report.pdf.layout import ensure_gui_app

        ensure_gui_app()
        self.log = log
        w, h = PICTURE_PX
        self.image = QImage(w, h, QImage.Format.Format_RGB32)
        self.image.fill(QColor("#ffffff"))
        self.p = QPainter(self.image)
        self.p.setRenderHint(QPainter.RenderHint.Antialiasing)
        self.text(QRectF(20, 8, w - 40, 60), title, 15, bold=True)
        left, top, right, bottom = 130, 80, (230 if colour_bar else 40), 150
        avail_w, avail_h = w - left - right, h - top - bottom
        if image_size is None:
            self.frame = QRectF(left, top, avail_w, avail_h)
        else:
            scale = min(avail_w / image_size[0], avail_h / image_size[1])
            fw, fh = image_size[0] * scale, image_size[1] * scale
            self.frame = QRectF(left + (avail_w - fw) / 2, top + (avail_h - fh) / 2, fw, fh)
            self.scale = scale
        self.bar = QRectF(self.frame.right() + 40, self.frame.top(), 40, self.frame.height()) if colour_bar else None

    def text(self, rect: Any, s: str, size: float = 11, bold: bool = False, align: Any = None, color: str = "#000000") -> None:
        from PySide6.QtCore import Qt
        from PySide6.QtGui import QColor

        self.p.setFont(font(size * 1.5, bold))  # the pictures are shown ~8x smaller than their pixels
        self.p.setPen(QColor(color))
        flags = align if align is not None else (Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter)
        draw_text(self.p, rect, int(flags), s, self.log, "picture")

    def to_frame(self, uv: np.ndarray) -> np.ndarray:
        return np.column_stack([self.frame.left() + uv[:, 0] * self.scale, self.frame.top() + uv[:, 1] * self.scale])

    def image_axes(self, image_size: tuple[int, int]) -> None:
        """Frame outline and pixel ticks along the top-left origin image axes."""
        from PySide6.QtCore import QLineF, QRectF, Qt
        from PySide6.QtGui import QColor, QPen

        from lps_gui.report.figures.axes import nice_ticks

        self.p.setPen(QPen(QColor("#000000"), 2))
        self.p.setBrush(Qt.BrushStyle.NoBrush)
        self.p.drawRect(self.frame)
        for t in nice_ticks(0, image_size[0], 6):
            if 0 <= t <= image_size[0]:
                x = self.frame.left() + t * self.scale
                self.p.drawLine(QLineF(x, self.frame.bottom(), x, self.frame.bottom() + 8))
                self.text(QRectF(x - 60, self.frame.bottom() + 8, 120, 30), f"{t:g}", 11, align=Qt.AlignmentFlag.AlignCenter)
        for t in nice_ticks(0, image_size[1], 5):
            if 0 <= t <= image_size[1]:
                y = self.frame.top() + t * self.scale
                self.p.drawLine(QLineF(self.frame.left() - 8, y, self.frame.left(), y))
                self.text(QRectF(self.frame.left() - 100, y - 15, 88, 30), f"{t:g}", 11,
                          align=Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        self.text(QRectF(self.frame.left(), self.frame.bottom() + 36, self.frame.width(), 30), "u [px]", 11,
                  align=Qt.AlignmentFlag.AlignCenter)
        self.p.save()
        self.p.translate(self.frame.left() - 110, self.frame.center().y())
        self.p.rotate(-90)
        self.text(QRectF(-100, -20, 200, 40), "v [px]", 11, align=Qt.AlignmentFlag.AlignCenter)
        self.p.restore()
        self.p.setPen(QColor("#000000"))

    def heat(self, values: np.ndarray, lo: float, hi: float, log: bool = False) -> None:
        """Cells of ``values`` (rows, cols) over the frame."""
        from PySide6.QtCore import Qt
        from PySide6.QtGui import QImage

        v = np.log10(np.maximum(values, 1e-12)) if log else np.asarray(values, float)
        a, b = (np.log10(lo), np.log10(hi)) if log else (lo, hi)
        rgb = np.ascontiguousarray(_viridis((v - a) / max(b - a, 1e-12)))
        img = QImage(rgb.data, rgb.shape[1], rgb.shape[0], 3 * rgb.shape[1], QImage.Format.Format_RGB888).copy()
        self.p.drawImage(self.frame, img.scaled(int(self.frame.width()), int(self.frame.height()),
                                                Qt.AspectRatioMode.IgnoreAspectRatio, Qt.TransformationMode.FastTransformation))

    def colour_bar(self, lo: float, hi: float, label: str, log: bool = False) -> None:
        from PySide6.QtCore import QLineF, QRectF, Qt
        from PySide6.QtGui import QColor, QImage, QPen

        from lps_gui.report.figures.axes import log_ticks, nice_ticks

        r = self.bar
        ramp = np.ascontiguousarray(np.repeat(_viridis(np.linspace(1, 0, 256))[:, None, :], 8, axis=1))
        img = QImage(ramp.data, 8, 256, 24, QImage.Format.Format_RGB888).copy()
        self.p.drawImage(r, img)
        self.p.setPen(QPen(QColor("#000000"), 2))
        self.p.drawRect(r)
        ticks = log_ticks(lo, hi) if log else nice_ticks(lo, hi, 6)
        for t in ticks:
            if not lo <= t <= hi:
                continue
            f = (np.log10(t) - np.log10(lo)) / (np.log10(hi) - np.log10(lo)) if log else (t - lo) / max(hi - lo, 1e-12)
            y = r.bottom() - f * r.height()
            self.p.drawLine(QLineF(r.right(), y, r.right() + 8, y))
            self.text(QRectF(r.right() + 12, y - 15, 110, 30), f"{t:g}", 11)
        self.p.save()
        self.p.translate(r.right() + 150, r.center().y())
        self.p.rotate(90)
        self.text(QRectF(-r.height() / 2, -20, r.height(), 40), label, 11, align=Qt.AlignmentFlag.AlignCenter)
        self.p.restore()

    def note(self, s: str) -> None:
        from PySide6.QtCore import QRectF, Qt

        self.text(QRectF(20, PICTURE_PX[1] - 70, PICTURE_PX[0] - 40, 64), s, 11, color="#333333",
                  align=Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignTop | Qt.TextFlag.TextWordWrap)

    def done(self) -> Any:
        self.p.end()
        return self.image


def residual_field(cal: "IntrinsicsCalibration", log: TextLog | None = None) -> Any:
    """Arrows of every corner's reprojection error, magnified so the larger ones are ~4 % of the image."""
    from PySide6.QtCore import QLineF, QPointF
    from PySide6.QtGui import QColor, QPen

    size = cal.intrinsics.image_size
    c = _Canvas("Reprojection residuals over the image", size, log=log)
    rejected = {(r.view, r.corner) for r in cal.rejected_corners}
    pts, res, bad = [], [], []
    for k in cal.used_views:
        uv, r = cal.image_points[k], cal.residuals_px[k]
        ok = np.all(np.isfinite(uv), axis=1) & np.all(np.isfinite(r), axis=1)
        for j in np.flatnonzero(ok):
            pts.append(uv[j])
            res.append(r[j])
            bad.append((k, int(j)) in rejected)
    pts, res, bad = np.array(pts).reshape(-1, 2), np.array(res).reshape(-1, 2), np.array(bad, dtype=bool)
    mag = np.linalg.norm(res, axis=1)
    typical = float(np.percentile(mag[~bad], 95)) if np.any(~bad) else 1.0
    gain = 0.04 * size[0] / max(typical, 1e-9)
    # a rejected corner's arrow is drawn at most twice the typical length (its size is in the listing)
    shown = res * np.minimum(1.0, 2.0 * typical / np.maximum(mag, 1e-12))[:, None]
    a, b = c.to_frame(pts), c.to_frame(pts + gain * np.where(bad[:, None], shown, res))
    for color, sel in ((BLUE, ~bad), (RED, bad)):
        c.p.setPen(QPen(QColor(color), 2 if color == BLUE else 4))
        for (x0, y0), (x1, y1) in zip(a[sel], b[sel]):
            c.p.drawLine(QLineF(x0, y0, x1, y1))
        c.p.setBrush(QColor(color))
        for x0, y0 in a[sel]:
            c.p.drawEllipse(QPointF(x0, y0), 2.5, 2.5)
    c.image_axes(size)
    c.note(f"arrows: observed minus projected, magnified {gain:.0f}x (95 % are shorter than {typical:.3f} px); "
           f"{int(bad.sum())} rejected corner(s) in red, their arrows cut to twice that; RMS {cal.rms_px:.3f} px")
    return c.done()


def per_view_errors(cal: "IntrinsicsCalibration", log: TextLog | None = None) -> Any:
    """Bars of each view's RMS error, a tick at its largest corner error; flagged views red."""
    from PySide6.QtCore import QLineF, QRectF, Qt
    from PySide6.QtGui import QColor, QPen

    from lps_gui.report.figures.axes import nice_ticks

    c = _Canvas("Residual magnitude per view", None, log=log)
    V = len(cal.per_view_rms_px)
    rms = np.asarray(cal.per_view_rms_px, float)
    worst = np.array([np.nanmax(np.linalg.norm(r, axis=1)) if k in cal.used_views else np.nan
                      for k, r in enumerate(cal.residuals_px)]) if cal.residuals_px else rms
    top = float(np.nanmax(worst)) * 1.08 if np.any(np.isfinite(worst)) else 1.0
    f = c.frame
    ys = lambda v: f.bottom() - v / top * f.height()  # noqa: E731
    c.p.setPen(QPen(QColor("#000000"), 2))
    c.p.drawRect(f)
    for t in nice_ticks(0, top, 6):
        if 0 <= t <= top:
            c.p.drawLine(QLineF(f.left() - 8, ys(t), f.left(), ys(t)))
            c.text(QRectF(f.left() - 100, ys(t) - 15, 88, 30), f"{t:g}", 11, align=Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
    width = f.width() / max(V, 1)
    flagged = set(cal.flagged_views)
    for k in range(V):
        x = f.left() + k * width
        if np.isfinite(rms[k]):
            color = QColor(RED if k in flagged else BLUE)
            c.p.fillRect(QRectF(x + 0.15 * width, ys(rms[k]), 0.7 * width, f.bottom() - ys(rms[k])), color)
        if np.isfinite(worst[k]):
            c.p.setPen(QPen(QColor("#000000"), 3))
            c.p.drawLine(QLineF(x + 0.1 * width, ys(worst[k]), x + 0.9 * width, ys(worst[k])))
        if V <= 40 or k % 5 == 0:
            c.text(QRectF(x, f.bottom() + 6, width, 30), str(k), 10, align=Qt.AlignmentFlag.AlignCenter)
    c.text(QRectF(f.left(), f.bottom() + 36, f.width(), 30), "view", 11, align=Qt.AlignmentFlag.AlignCenter)
    c.p.save()
    c.p.translate(30, f.center().y())
    c.p.rotate(-90)
    c.text(QRectF(-f.height() / 2, -20, f.height(), 40), "error [px]", 11, align=Qt.AlignmentFlag.AlignCenter)
    c.p.restore()
    c.note("bars: RMS reprojection error of the view; black tick: its largest corner error; red: flagged view")
    return c.done()


def uncertainty_picture(cal: "IntrinsicsCalibration", grid: tuple[int, int] = (32, 24), log: TextLog | None = None) -> Any:
    """Worst-direction projection sigma over the image (log colour scale)."""
    from lps_gui.core.intrinsics.crossval import uncertainty_map

    size = cal.intrinsics.image_size
    c = _Canvas("Projection uncertainty (worst-direction sigma)", size, colour_bar=True, log=log)
    _, sigma = uncertainty_map(cal.intrinsics, grid)
    finite = sigma[np.isfinite(sigma)]
    lo = max(float(finite.min()), 1e-4) if finite.size else 0.01
    hi = min(max(float(finite.max()), 2 * lo), 100 * lo) if finite.size else 1.0
    c.heat(np.clip(sigma, lo, hi), lo, hi, log=True)
    c.image_axes(size)
    c.colour_bar(lo, hi, "sigma [px]", log=True)
    seen = cal.coverage_on(grid) > 0
    med = float(np.nanmedian(sigma[seen])) if seen.any() else float("nan")
    c.note(f"median {med:.3f} px where the corners were; from the intrinsics' covariance with the best-fitting "
           "rotation taken out, so the same at every distance; colours clipped at 100x the smallest; grey: beyond the model's reach")
    return c.done()


def coverage_picture(cal: "IntrinsicsCalibration", log: TextLog | None = None) -> Any:
    """Corners per image cell with a colour bar."""
    size = cal.intrinsics.image_size
    c = _Canvas("Coverage of the image by corners", size, colour_bar=True, log=log)
    counts = np.asarray(cal.coverage, float)
    hi = max(float(counts.max()), 1.0)
    c.heat(counts, 0.0, hi)
    c.image_axes(size)
    c.colour_bar(0.0, hi, "corners per cell")
    c.note(f"{100 * cal.coverage_fraction():.0f} % of the {counts.shape[1]} x {counts.shape[0]} cells hold corners")
    return c.done()


def crossval_picture(cv: "CrossValidation", log: TextLog | None = None) -> Any:
    """The two halves' projection difference in units of their combined sigma."""
    size = cv.even.intrinsics.image_size
    c = _Canvas("Cross-validation: even views against odd views", size, colour_bar=True, log=log)
    norm = np.where(cv.diff.judged, cv.diff.normalized, np.nan)
    hi = max(3.0, float(np.nanmax(norm)) if np.any(np.isfinite(norm)) else 3.0)
    c.heat(norm, 0.0, hi)
    c.image_axes(size)
    c.colour_bar(0.0, hi, "difference / combined sigma")
    c.note(cv.diff.verdict() + "; grey: cells not seen by both halves")
    return c.done()


def intrinsics_pictures(cal: "IntrinsicsCalibration", crossval: "CrossValidation | None" = None,
                        log: TextLog | None = None) -> list[tuple[str, Any]]:
    """(caption, QImage) of every picture of a calibration, in the report's order; strings drawn go to ``log``."""
    out = [
        ("Residual vector field", residual_field(cal, log=log)),
        ("Per-view residuals", per_view_errors(cal, log=log)),
        ("Projection uncertainty", uncertainty_picture(cal, log=log)),
        ("Coverage", coverage_picture(cal, log=log)),
    ]
    if crossval is not None:
        out.append(("Cross-validation", crossval_picture(crossval, log=log)))
    return out
