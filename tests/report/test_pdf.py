"""The PDF opens, has the planned pages, and prints the numbers of results.json."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from pdfminer.high_level import extract_pages
from pdfminer.layout import LTTextContainer
from pypdf import PdfReader

from lps_gui.errors import InputError
from lps_gui.report.pages.summary import summary_rows
from lps_gui.report.pdf.document import render_report, write_report
from tests.report.conftest import make_results, write_session

pytestmark = pytest.mark.gui


def _session(tmp_path: Path, results: dict, truth: dict | None, spec: dict | None = None) -> Path:
    return write_session(tmp_path / "session", results, truth, spec)


def _page_text(path: Path, page: int) -> str:
    """Text of page ``page`` (1-based) laid out as printed: a table row stays one line (pypdf, pip-installed)."""
    text = PdfReader(path).pages[page - 1].extract_text(extraction_mode="layout")
    return text.replace("\t", " ").replace("\ufb01", "fi").replace("\ufb02", "fl")  # Qt's word gaps, ligatures


def _pdf_pages(path: Path) -> int:
    data = path.read_bytes()
    assert data.startswith(b"%PDF-"), "not a PDF"
    assert data.rstrip().endswith(b"%%EOF")
    return len(re.findall(rb"/Type\s*/Page(?!s)", data))


def test_pdf_has_the_planned_pages_and_opens(tmp_path):
    results, truth = make_results()
    folder = _session(tmp_path, results, truth, {"accuracy_um": 20, "repeatability_um": 5, "straightness_um": 38})
    info = render_report(folder)
    assert info.path == folder / "report.pdf"
    # verdict page, figures, uncertainty, method, three pages of plots (the last with outliers), table, truth
    assert _pdf_pages(info.path) == info.n_pages == len(info.pages) == 9
    assert info.pages[0] == ["Linear positioning stage \u2014 measurement report", "Verdict", "figure:deviation",
                             "Identification", "Certificate and approval"]
    assert info.pages[1] == ["Measured figures", "ISO 230-2 per target"]
    assert info.pages[2] == ["Environment", "Uncertainty budget (GUM, ISO/TR 230-9)"]
    assert info.pages[3] == ["Method and camera", "What limits this result"]
    assert info.clipped == ()
    figs = [w for page in info.pages[1:] for w in page if w.startswith("figure:")]
    assert figs == ["figure:positions", "figure:deviation", "figure:step", "figure:straightness", "figure:angles",
                    "figure:residuals", "figure:spectrum"]
    assert info.pages[-2] == ["Per-position results"]
    assert info.pages[-1] == ["Simulator truth (simulated session only)"]
    reader = PdfReader(info.path)  # a PDF parser agrees: every page's content stream reads
    assert len(reader.pages) == info.n_pages
    assert all(page.extract_text() for page in reader.pages)


def test_long_table_is_paged(tmp_path):
    results, truth = make_results(runs=2, views=60)  # 240 rows
    info = render_report(_session(tmp_path, results, truth), out=tmp_path / "r.pdf")
    table_pages = [p for p in info.pages if p == [] or p == ["Per-position results"]]
    assert len(table_pages) >= 3
    assert _pdf_pages(tmp_path / "r.pdf") == info.n_pages


def test_printed_summary_numbers_come_from_results(tmp_path):
    results, truth = make_results()
    results["figures"]["single_run"]["scale_ppm"] = 123.456
    results["figures"]["single_run"]["periodic_period_mm"] = 7.77
    folder = _session(tmp_path, results, truth)
    path = write_report(folder)
    text = _page_text(path, 2)
    for row in summary_rows(results):
        line = next((ln for ln in text.splitlines() if ln.strip().startswith(row.name)), None)
        assert line is not None, row.name
        assert row.text() in line, (row.name, line)
    assert "123" in text and "7.77" in text


def test_thumbnails_of_outlier_views_are_embedded_when_images_exist(tmp_path):
    results, truth = make_results()
    folder = _session(tmp_path, results, truth)
    no_images = write_report(folder, out=tmp_path / "a.pdf").read_bytes()
    assert b"/Subtype /Image" not in no_images and b"/Subtype/Image" not in no_images
    import cv2

    (folder / "images").mkdir()
    img = np.full((120, 160), 200, np.uint8)
    img[40:80, 60:100] = 20
    cv2.imwrite(str(folder / "images" / "00005.png"), img)
    with_images = write_report(folder, out=tmp_path / "b.pdf").read_bytes()
    assert re.search(rb"/Subtype\s*/Image", with_images)


def test_missing_results_is_one_line_error(tmp_path):
    folder = tmp_path / "s"
    folder.mkdir()
    with pytest.raises(InputError, match="run `lps estimate"):
        write_report(folder)
    (folder / "results.json").write_text("{}")
    with pytest.raises(InputError, match="not an lps-results/1 file"):
        write_report(folder)
    (folder / "results.json").write_text('{"format": "lps-results/1"}')
    with pytest.raises(InputError, match="no per-position table"):
        write_report(folder)


def test_failed_render_keeps_the_previous_report(tmp_path):
    results, truth = make_results()
    folder = _session(tmp_path, results, truth)
    good = write_report(folder)
    before = good.read_bytes()
    results["positions"] = "broken"
    with pytest.raises(Exception):
        write_report(folder, results)
    assert good.read_bytes() == before
    assert not list(folder.glob(".report.pdf*"))


def test_page_one_states_the_verdict_with_expanded_uncertainty_and_nothing_is_clipped(tmp_path):
    from lps_gui.report.pages.verdict import verdicts
    from lps_gui.report.pdf.layout import ensure_gui_app

    results, truth = make_results()  # 2 runs per direction: indicative
    spec = {"accuracy_um": 20, "repeatability_um": 5, "straightness_um": 38}
    folder = _session(tmp_path, results, truth, spec)
    info = render_report(folder)
    assert info.clipped == ()  # every table cell fits its column (measured with the painter's font metrics)
    text = _page_text(info.path, 1)
    assert "Verdict" in text and "U (k = 2)" in text
    rows = verdicts(results, spec)
    assert len(rows) == 3
    for v in rows:
        line = next((ln for ln in text.splitlines() if ln.strip().startswith(v.name)), None)
        assert line is not None, v.name
        assert v.verdict in line
        if v.u_k2 is not None:
            from lps_gui.report.pages.summary import fmt
            assert f"\u00b1 {fmt(v.u_k2)}" in line
    assert "(indicative)" in text and "FAIL\n" not in text.replace(" ", "")  # fewer than 5 runs: never a bare FAIL
    assert "Truth:" not in text  # simulator truth has its own page
    assert "RigStage" not in text
    last = _page_text(info.path, info.n_pages)
    assert "Simulator truth" in last and "Truth: position error RMS" in last
    # every text box of page 1 lies inside the page's text area (nothing runs off the page), as pdfminer lays it out
    ensure_gui_app()
    xs = [box.x1 for box in next(extract_pages(info.path, page_numbers=[0])) if isinstance(box, LTTextContainer)]
    assert xs and max(xs) <= 595.0 - 15 / 25.4 * 72 + 1.0


@pytest.mark.parametrize("umask", [0o022, 0o027])
def test_report_pdf_is_written_with_the_users_umask(tmp_path, umask):
    import os
    import stat

    results, truth = make_results()
    folder = _session(tmp_path, results, truth)
    old = os.umask(umask)
    try:
        path = write_report(folder)
    finally:
        os.umask(old)
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o666 & ~umask  # not mkstemp's 0600


def test_page_one_shows_a_session_flag_such_as_the_lens_model(tmp_path):
    """A flag of the whole session (index None: the lens model does not fit) is on page 1 and in the GUI's verdict."""
    from lps_gui.gui.results.panel import verdict_html
    from lps_gui.io.results.model import as_results

    results, truth = make_results()
    message = ("lens model does not fit the intrinsics calibration: ... recalibrate with `lps intrinsics --model "
               "rational`")
    results["flags"] = list(results.get("flags") or []) + [{"index": None, "kind": "lens_model", "message": message}]
    info = render_report(_session(tmp_path, results, truth))
    text = " ".join(_page_text(info.path, 1).split())
    assert "lens model does not fit the intrinsics calibration" in text and "--model rational" in text
    assert "lens model does not fit" in verdict_html(as_results(results), None)
