"""The measurement report as a vector PDF (A4), painted with Qt's QPdfWriter offscreen.

Page 1 says what was measured with what, and the verdict: title block,
summary figures, pass/fail against the stage specification, method and
intrinsics. Then the plots (the same :mod:`lps_gui.report.figures.plots`
definitions the GUI shows), outlier views with thumbnails, what limits the
result, and the per-position table. Qt is imported inside functions only.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from lps_gui.core.progress import ProgressFn, no_progress
from lps_gui.errors import InputError
from lps_gui.io.jsonfile import read_json
from lps_gui.io.results.model import Results, as_results, read_results
from lps_gui.report.figures.plots import figure_by_key, figures_from_results, with_spec_band
from lps_gui.report.pages import asme as asme_pages
from lps_gui.report.pages import sections as R
from lps_gui.report.pages import summary as S
from lps_gui.report.registry import AFTER_FIGURES, AFTER_PLOTS, own_report, paint_sections

log = logging.getLogger(__name__)

RESULTS_FILE = "results.json"
REPORT_FILE = "report.pdf"
FIGURE_HEIGHT_MM = 82.0
MAX_THUMBNAILS = 6
THUMB_PX = 480  # thumbnails are downscaled before embedding: a small PDF


@dataclass(frozen=True)
class ReportInfo:
    """What :func:`render_report` wrote: the file and what went on which page."""

    path: Path
    n_pages: int
    pages: list[list[str]]
    clipped: tuple[str, ...] = ()  # "page N: text" of strings wider than their box (none in a good report)
    texts: tuple[Any, ...] = ()  # every drawn string (lps_gui.report.pdf.text_fit.DrawnText), page by page


def load_results(session_dir: Path) -> Results:
    """results.json of a session, or a one-line error telling the user to estimate first."""
    if not Path(session_dir).is_dir():
        raise InputError(f"{session_dir}: session folder not found; check the path")
    return read_results(Path(session_dir) / RESULTS_FILE)


def load_session_meta(session_dir: Path) -> dict[str, Any]:
    """session.json as a dict; an empty dict when the folder holds results only."""
    path = Path(session_dir) / "session.json"
    if not path.exists():
        return {}
    meta = read_json(path, "session file")
    return meta if isinstance(meta, dict) else {}


def write_report(session_dir: Path, results: Results | dict | None = None, out: Path | None = None,
                 progress: ProgressFn = no_progress) -> Path:
    """Write the PDF report of a session; returns its path (default SESSION/report.pdf).

    Parameters
    ----------
    session_dir : Path
        The session folder (session.json for the title block, truth and stage
        spec; images for outlier thumbnails).
    results : Results, optional
        results.json as read (or an estimate's dict); read from the session folder when omitted.
    out : Path, optional
        Where to write the PDF.
    """
    return render_report(session_dir, results, out, progress).path


def render_report(session_dir: Path, results: Results | dict | None = None, out: Path | None = None,
                  progress: ProgressFn = no_progress) -> ReportInfo:
    """:func:`write_report` that also returns the page plan (for tests and the GUI)."""
    from lps_gui import __version__
    from lps_gui.report.pdf.layout import ensure_gui_app, pdf_file

    session_dir = Path(session_dir)
    results = as_results(results) if results is not None else load_results(session_dir)
    meta = load_session_meta(session_dir)
    out = Path(out) if out is not None else session_dir / REPORT_FILE
    if not out.parent.is_dir():
        raise InputError(f"{out.parent}: folder not found; create it or choose another --out")
    ensure_gui_app()
    name = (results.inputs and results.inputs.session) or session_dir.name
    steps = ("front pages", "plots", "outliers", "table")
    with pdf_file(out, f"LPS measurement report: {name}",
                  f"lps-calib {__version__} \u00b7 {name} \u00b7 {results.created or ''}") as flow:
        own = own_report(results)  # a planar session's (SPEC 10): the registry's report of its own
        if own is not None and own.report is not None:
            progress(0, len(steps), f"{own.name} report")
            own.report(flow, meta, results, S.title_rows(meta, results, __version__), FIGURE_HEIGHT_MM)
        else:
            _paint_line_report(flow, session_dir, meta, results, __version__, progress, steps)
    progress(len(steps), len(steps), f"wrote {out}")
    return ReportInfo(out, flow.page, flow.log.pages, tuple(flow.log.clipped), tuple(flow.log.text.texts))


def _paint_line_report(flow: Any, session_dir: Path, meta: dict[str, Any], results: Results, version: str,
                       progress: ProgressFn, steps: tuple[str, ...]) -> None:
    """Every page of a line (single-axis) session's report."""
    progress(0, len(steps), "front pages")
    _front_page(flow, meta, results, version)
    flow.new_page()
    _figures_page(flow, results)
    paint_sections(flow, results, AFTER_FIGURES, FIGURE_HEIGHT_MM)  # a row of targets (SPEC 13), an ASME B5.64 test
    flow.new_page()
    R.uncertainty_sections(flow, results)
    flow.new_page()
    _method_page(flow, results)
    flow.heading("What limits this result", 11)
    for note in S.limits_notes(results):
        flow.paragraph(note)
    progress(1, len(steps), "plots")
    flow.new_page()
    flow.heading("Plots")
    for spec in figures_from_results(results, meta.get("truth")):
        flow.figure(spec, FIGURE_HEIGHT_MM)
    paint_sections(flow, results, AFTER_PLOTS, FIGURE_HEIGHT_MM)  # error motions (SPEC 14), when the results have them
    progress(2, len(steps), "outliers")
    _outliers(flow, session_dir, results)
    progress(3, len(steps), "table")
    flow.new_page()
    flow.heading("Per-position results")
    header, rows, widths = S.position_table(results)
    colors = ["#c00000" if r[-1] else None for r in rows]
    flow.table(header, rows, widths, size_pt=6.3, row_mm=3.35, align_right_from=0, colors=colors)
    _truth_page(flow, results)


def _front_page(flow: Any, meta: dict[str, Any], results: Results, version: str) -> None:
    """Page 1: the verdict with U (k = 2), the deviation plot with the limit drawn, the identification."""
    spec = R.stage_spec(meta, results)
    flow.heading(front_title(results), 15)
    for line in S.truth_check_lines(results):  # a simulated session whose truth contradicts the report says so first
        flow.paragraph(line, size_pt=9.0, color="#c00000")
    R.verdict_section(flow, results, spec, [r for r in S.summary_rows(results) if r.key in R.FRONT_FIGURES])
    deviation = figure_by_key(figures_from_results(results, None), "deviation")
    deviation = replace(deviation, series=[s for s in deviation.series if not s.label.startswith("truth")])  # p. 1: measured only
    limit = (spec or {}).get("accuracy_um")
    if limit is not None:
        deviation = with_spec_band(deviation, float(limit), str(spec.get("limits", "plus_minus")) == "plus_minus")
    # the identification and signing blocks stay on page 1: the plot gives way (down to 60 mm) when the verdict is long
    flow.figure(deviation, max(FRONT_FIGURE_MIN_MM, min(100.0, flow.remaining_mm() - FRONT_BLOCKS_MM)))
    title = S.title_rows(meta, results, version)
    title.append(("Results", f"{results.created or DASH_TEXT}, method {results.method or DASH_TEXT}"))
    R.identification_blocks(flow, meta, results, title)


DASH_TEXT = S.DASH


def front_title(results: Results) -> str:
    """Page 1's title: the ASME B5.64 test a test session ran (its verdict row leads), else the measurement report."""
    asme = results.asme_b5_64
    if asme is not None and asme.incremental_step is not None and asme.incremental_step.raw:
        return "Minimum incremental motion test (ASME B5.64)"
    if asme is not None and asme.settling is not None and asme.settling.raw:
        return "Settling time test (ASME B5.64)"
    return "Linear positioning stage \u2014 measurement report"


FRONT_FIGURE_MIN_MM, FRONT_BLOCKS_MM = 60.0, 96.0  # page 1's plot at least; identification + signing blocks need


def _figures_page(flow: Any, results: Results) -> None:
    """Measured figures with U (k = 2), then the ISO 230-2 per-target table."""
    flow.heading("Measured figures", 11)
    R.figure_table(flow, S.summary_rows(results))
    from lps_gui.report.pages.reconcile import page2_note

    for note in [*S.figure_notes(results), page2_note(results)]:
        if note:
            flow.paragraph(note, size_pt=7.5, color="#555555")
    flow.paragraph(U_NOTE, size_pt=7.5, color="#555555")
    R.iso_section(flow, results)
    asme_pages.names_note(flow, results)


U_NOTE = ("\u03c3 and s are 1-sigma. \u03c3 of a position is the measurement's noise only (corner noise); "
          "s is the scatter over runs (ISO 230-2). U (k = 2) is the expanded measurement uncertainty of the "
          "figure in its row (see the uncertainty budget): spans of positions (A, E, M, max |deviation|) carry "
          "U of a displacement over the travel; figures of one target (R, B, step std) carry only the noise "
          "terms, which do not cancel there; a p-v carries U of the difference of two per-target means. A "
          "figure \"not resolved\" states no value and so no U: noise alone reaches the bound it names "
          "(noise p-v, or noise max for a max |x|).")


def _truth_page(flow: Any, results: Results) -> None:
    """The simulator's truth on its own page: not part of the measurement."""
    rows = S.truth_rows(results)
    if not rows:
        return
    flow.new_page()
    flow.heading("Simulator truth (simulated session only)", 11)
    flow.paragraph("This session was simulated: the simulator knows the stage's true positions. These rows compare "
                   "the measurement with that truth; they are a check of the method, not part of a measurement "
                   "of a real stage.", color="#555555")
    flow.table(["figure against truth", "value", "unit"], [[r.name, r.text(), r.unit] for r in rows], [100, 26, 16])



def _method_page(flow: Any, results: Results) -> None:
    """Method and its settings beside the intrinsics used (with their std)."""
    method = [[k, v] for k, v in S.method_rows(results)]
    intr = [list(r) for r in S.intrinsics_rows(results)]
    row_mm = 3.9
    flow.heading("Method and camera", 11)
    flow.ensure(row_mm * (max(len(method), len(intr) + 1) + 1))
    top = flow.y
    flow.table(None, method, [30, 70], size_pt=7.5, row_mm=row_mm, align_right_from=9, max_width_mm=108)
    below_method = flow.y
    flow.y = top
    flow.table(["intrinsic", "value", "1\u03c3"], intr, [16, 30, 24], size_pt=7.5, row_mm=row_mm, x_mm=110)
    flow.y = max(flow.y, below_method)


def _outliers(flow: Any, session_dir: Path, results: Results) -> None:
    """Flagged views: a table, and thumbnails of the first few when their images exist."""
    rows = S.outlier_rows(results)
    flow.heading("Outlier views", 11)
    if not rows:
        flow.paragraph("No view was flagged: every view's residual and position agree with its neighbours.")
        return
    flow.table(["#", "file", "RMS [px]", "reason"],
               [[str(r["index"]), r["file"], S.fmt(r["rms_px"]), r["reason"]] for r in rows],
               [10, 45, 16, 109], size_pt=7.5, align_right_from=2, align_left=(3,))
    images = [(r, _thumbnail(session_dir / r["file"])) for r in rows[:MAX_THUMBNAILS] if r["file"]]
    images = [(r, im) for r, im in images if im is not None]
    if not images:
        flow.paragraph("No thumbnails: the session holds no images for these views (point-level session).",
                       color="#555555")
        return
    width_mm, gap_mm = 56.0, 6.0
    for start in range(0, len(images), 3):
        chunk = images[start:start + 3]
        h = max(width_mm * im.height() / max(im.width(), 1) for _, im in chunk) + 6.0
        flow.ensure(h)
        flow.log.add("thumbnails")
        heights = [flow.image(im, k * (width_mm + gap_mm), width_mm, f"view {r['index']}: {Path(r['file']).name}")
                   for k, (r, im) in enumerate(chunk)]
        flow.space(max(heights) + 2.0)


def _thumbnail(path: Path) -> Any:
    """A downscaled QImage of ``path``, or None when it is missing or unreadable."""
    from PySide6.QtCore import Qt
    from PySide6.QtGui import QImage

    from lps_gui.core.image_header import check_image_header

    if not path.is_file() or path.is_symlink():
        return None
    try:
        with open(path, "rb") as f:
            check_image_header(f.read(1 << 16), str(path))
    except (OSError, InputError) as exc:
        log.info("report: no thumbnail of %s: %s", path, exc)
        return None
    image = QImage(str(path))
    if image.isNull():
        log.info("report: cannot read %s for a thumbnail", path)
        return None
    if image.width() > THUMB_PX:
        image = image.scaledToWidth(THUMB_PX, Qt.TransformationMode.SmoothTransformation)
    return image
