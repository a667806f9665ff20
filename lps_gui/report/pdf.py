"""The measurement report as a vector PDF (A4), painted with Qt's QPdfWriter offscreen.

Page 1 says what was measured with what, and the verdict: title block,
summary figures, pass/fail against the stage specification, method and
intrinsics. Then the plots (the same :mod:`lps_gui.report.figures`
definitions the GUI shows), outlier views with thumbnails, what limits the
result, and the per-position table. Qt is imported inside functions only.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lps_gui.core.progress import ProgressFn, no_progress
from lps_gui.errors import InputError
from lps_gui.io.atomic import commit_temp, temp_path
from lps_gui.io.jsonfile import read_json
from lps_gui.report import summary as S
from lps_gui.report.figures import figures_from_results

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


def load_results(session_dir: Path) -> dict[str, Any]:
    """results.json of a session, or a one-line error telling the user to estimate first."""
    from lps_gui.io.results_file import read_results

    if not Path(session_dir).is_dir():
        raise InputError(f"{session_dir}: session folder not found; check the path")
    results = read_results(Path(session_dir) / RESULTS_FILE)
    if not isinstance(results.get("positions"), list):
        raise InputError(f"{Path(session_dir) / RESULTS_FILE}: has no per-position table; re-run `lps estimate`")
    return results


def load_session_meta(session_dir: Path) -> dict[str, Any]:
    """session.json as a dict; an empty dict when the folder holds results only."""
    path = Path(session_dir) / "session.json"
    if not path.exists():
        return {}
    meta = read_json(path, "session file")
    return meta if isinstance(meta, dict) else {}


def write_report(session_dir: Path, results: dict | None = None, out: Path | None = None,
                 progress: ProgressFn = no_progress) -> Path:
    """Write the PDF report of a session; returns its path (default SESSION/report.pdf).

    Parameters
    ----------
    session_dir : Path
        The session folder (session.json for the title block, truth and stage
        spec; images for outlier thumbnails).
    results : dict, optional
        results.json content; read from the session folder when omitted.
    out : Path, optional
        Where to write the PDF.
    """
    return render_report(session_dir, results, out, progress).path


def render_report(session_dir: Path, results: dict | None = None, out: Path | None = None,
                  progress: ProgressFn = no_progress) -> ReportInfo:
    """:func:`write_report` that also returns the page plan (for tests and the GUI)."""
    from lps_gui import __version__
    from lps_gui.report.layout import PdfFlow, ensure_gui_app

    session_dir = Path(session_dir)
    results = results if results is not None else load_results(session_dir)
    meta = load_session_meta(session_dir)
    out = Path(out) if out is not None else session_dir / REPORT_FILE
    if not out.parent.is_dir():
        raise InputError(f"{out.parent}: folder not found; create it or choose another --out")
    ensure_gui_app()
    tmp = temp_path(out)
    name = (results.get("inputs") or {}).get("session") or session_dir.name
    flow = PdfFlow(tmp, f"LPS measurement report: {name}",
                   f"lps-calib {__version__} \u00b7 {name} \u00b7 {results.get('created', '')}")
    steps = ("front pages", "plots", "outliers", "table")
    try:
        progress(0, len(steps), "front pages")
        _front_page(flow, meta, results, __version__)
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
        progress(2, len(steps), "outliers")
        _outliers(flow, session_dir, results)
        progress(3, len(steps), "table")
        flow.new_page()
        flow.heading("Per-position results")
        header, rows, widths = S.position_table(results)
        colors = ["#c00000" if r[-1] else None for r in rows]
        flow.table(header, rows, widths, size_pt=6.3, row_mm=3.35, align_right_from=0, colors=colors)
        n_pages = flow.finish()
    except BaseException:
        flow.abort()
        tmp.unlink(missing_ok=True)
        raise
    commit_temp(tmp, out, ends_with=b"%%EOF")  # a half-written report never takes the place of a good one
    progress(len(steps), len(steps), f"wrote {out}")
    return ReportInfo(out, n_pages, flow.log.pages)


def _front_page(flow: Any, meta: dict[str, Any], results: dict[str, Any], version: str) -> None:
    flow.heading("Linear positioning stage \u2014 measurement report", 15)
    flow.space(1)
    title = S.title_rows(meta, results, version)
    flow.table(None, [[k, v] for k, v in title], [32, 148], size_pt=8.5, row_mm=4.6, align_right_from=9)

    flow.heading("Summary figures", 11)
    rows = S.summary_rows(results)
    flow.table(["figure", "value", "unit"], [[r.name, r.text(), r.unit] for r in rows], [80, 30, 16])
    for note in S.figure_notes(results):
        flow.paragraph(note, size_pt=7.5, color="#555555")

    checks = S.spec_checks(results, meta.get("stage_spec") or results.get("stage_spec"))
    flow.heading("Stage specification", 11)
    if checks:
        cells, colors = [], []
        for c in checks:
            verdict = "PASS" if c.passed else ("FAIL" if c.passed is False else "not measured")
            cells.append([c.name, S.fmt(c.measured), f"{S.fmt(c.limit)} {c.unit}", verdict, c.note])
            colors.append("#007a1f" if c.passed else ("#c00000" if c.passed is False else "#555555"))
        flow.table(["criterion", "measured", "limit", "verdict", "how it is judged"], cells, [36, 18, 20, 24, 82],
                   colors=colors, align_right_from=1, align_left=(4,))
    else:
        flow.paragraph("No stage specification in session.json (key \"stage_spec\", e.g. "
                       "{\"accuracy_um\": 20, \"repeatability_um\": 5, \"straightness_um\": 38}); no verdict given.",
                       color="#555555")



def _method_page(flow: Any, results: dict[str, Any]) -> None:
    """Method and its settings beside the intrinsics used (with their std)."""
    method = [[k, v] for k, v in S.method_rows(results)]
    intr = [list(r) for r in S.intrinsics_rows(results)]
    row_mm = 3.9
    flow.heading("Method and camera", 11)
    flow.ensure(row_mm * (max(len(method), len(intr) + 1) + 1))
    top = flow.y
    flow.table(None, method, [30, 70], size_pt=7.5, row_mm=row_mm, align_right_from=9)
    below_method = flow.y
    flow.y = top
    flow.table(["intrinsic", "value", "std"], intr, [16, 30, 24], size_pt=7.5, row_mm=row_mm, x_mm=110)
    flow.y = max(flow.y, below_method)


def _outliers(flow: Any, session_dir: Path, results: dict[str, Any]) -> None:
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
