"""The light field's report page (issue 38): the epipolar check as pictures and numbers.

An epipolar-plane image (EPI) stacks one image row of every view of a row of the light field: a scene
point traces a line whose slope is its disparity per view. Before rectification the lines wander (lens
distortion, the camera's turn off the motion, the stage's tilts); after it each is straight. The page
shows both (the whole row, and a 4x enlargement of its middle), the check's numbers (lightfield.json
``check``) and the grid test of the positions. Qt is imported inside the function.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from lps_gui.errors import InputError

REPORT_FILE = "report.pdf"
PICTURE_WIDTH_MM = 180.0
ZOOM = 4
ZOOM_WIDTH_PX = 180


def _qimage(gray: np.ndarray) -> Any:
    from PySide6.QtGui import QImage

    a = np.ascontiguousarray(gray, dtype=np.uint8)
    return QImage(a.data, a.shape[1], a.shape[0], a.shape[1], QImage.Format.Format_Grayscale8).copy()


def epipolar_rows(check: dict[str, Any] | None) -> list[tuple[str, str]]:
    """The epipolar check's numbers as (what, value) rows: the one formatting the report's light-field page, the
    GUI's light field tab and the console print (issue 37: a figure on two pages is produced once)."""
    if not check:
        return []
    v = check["vertical_disparity_rms_px"]
    where = ", within rows of views" if "within" in check else ""
    rows = [(f"vertical disparity RMS, before ({check['n_points']} known scene points{where})", f"{v['before']:.3f} px"),
            ("vertical disparity RMS, after", f"{v['after']:.4f} px")]
    h = check.get("horizontal_disparity_rms_px")
    if h:
        rows += [("horizontal disparity RMS within columns of views, before", f"{h['before']:.3f} px"),
                 ("horizontal disparity RMS within columns of views, after", f"{h['after']:.4f} px")]
    for p in check.get("disparity_vs_position", []):
        rows += [(f"{p['plane']} at {p['depth_mm']:.0f} mm: disparity residual, measured positions",
                  f"{p['residual_rms_px_measured']:.4f} px"),
                 (f"{p['plane']}: disparity residual, nominal positions", f"{p['residual_rms_px_nominal']:.4f} px"),
                 (f"{p['plane']}: depth from the disparity slope", f"{p['depth_from_slope_mm_measured']:.1f} mm")]
    return rows


def check_rows(doc: dict[str, Any]) -> list[list[str]]:
    """The numbers of lightfield.json as table rows (what, value)."""
    rows = []
    u = doc.get("uniform") or {}
    rows.append(["grid of views", " x ".join(str(v) for v in u.get("grid", []))])
    rows.append(["spacing (fitted)", ", ".join(f"{v:.5f} mm" for v in u.get("spacing_mm", []))])
    rows.append(["largest deviation from a uniform grid", f"{u.get('max_sigmas', float('nan')):.1f} sigma"])
    rows.append(["HCI layout", "written" if u.get("hci") else "not written (see below)"])
    rows.append(["view rotations from", str(doc.get("rotation_source", ""))])
    rows += [[what, value] for what, value in epipolar_rows(doc.get("check"))]  # the console's and the GUI's too
    return rows


def write_lightfield_report(doc: dict[str, Any], before: np.ndarray, after: np.ndarray, out: Path | str,
                            clipped: list[str] | None = None) -> int:
    """One page (or two) of EPIs and numbers; returns the number of pages. A failure leaves no partial file.

    ``clipped``, when given, receives every string that does not fit its box (the layout check).
    """
    from lps_gui import __version__
    from lps_gui.report.pdf.layout import ensure_gui_app, pdf_file

    out = Path(out)
    if not out.parent.is_dir():
        raise InputError(f"{out.parent}: folder not found; choose another --out")
    ensure_gui_app()
    w = before.shape[1]
    x0 = max(0, w // 2 - ZOOM_WIDTH_PX // 2)
    crop = slice(x0, x0 + ZOOM_WIDTH_PX)

    def zoom(a: np.ndarray) -> np.ndarray:
        return np.repeat(np.repeat(a[:, crop], ZOOM, axis=1), max(1, ZOOM // 2), axis=0)

    with pdf_file(out, "Light field report", f"lps-calib {__version__} \u00b7 light field") as flow:
        flow.heading("Light field \u2014 the epipolar check", 15)
        flow.paragraph(f"Measurement: {(doc.get('measurement_session') or {}).get('path', '')}. "
                       f"Scene: {doc.get('scene_session', '')}. {len(doc.get('views', []))} views rectified to one "
                       "virtual camera whose image plane is parallel to the motion; each view keeps its measured position.")
        flow.table(["", ""], check_rows(doc), [135, 45], align_left=(0, 1))
        refusal = (doc.get("uniform") or {}).get("refusal")
        if refusal:
            flow.paragraph(refusal, color="#a04000")
        flow.space(3.0)
        row = doc.get("epi_row", 0)
        for caption, pic in ((f"EPI before rectification (raw row {row}, views top to bottom)", before),
                             (f"EPI after rectification (row {row})", after)):
            image = _qimage(pic)
            flow.ensure(PICTURE_WIDTH_MM * image.height() / max(image.width(), 1) + 8)
            flow.log.add(f"picture:{caption}")
            flow.space(flow.image(image, 0.0, PICTURE_WIDTH_MM, caption) + 2.0)
        for caption, pic in ((f"before, middle {ZOOM_WIDTH_PX} px x{ZOOM}", zoom(before)),
                             (f"after, middle {ZOOM_WIDTH_PX} px x{ZOOM}", zoom(after))):
            image = _qimage(pic)
            flow.ensure(85.0 * image.height() / max(image.width(), 1) + 8)
            flow.log.add(f"picture:{caption}")
            h = flow.image(image, 0.0 if caption.startswith("before") else 92.0, 85.0, caption)
            if caption.startswith("after"):
                flow.space(h + 2.0)
    if clipped is not None:
        clipped.extend(flow.log.clipped)
    return flow.page
