"""The error-motions page (SPEC 14): six curves with sigma bands, resolved or not, the tool point's Abbe term."""
from __future__ import annotations

import pytest

from lps_gui.pipeline.estimate import estimate_session
from lps_gui.report.pages.error_motions import error_motion_figures, error_motion_rows
from lps_gui.report.pdf.document import render_report
from tests.pipeline.test_error_motion_results import _board_session

pytestmark = pytest.mark.gui


def test_the_report_has_an_error_motions_page_with_the_tool_point(tmp_path):
    folder = _board_session(tmp_path / "s", {"offset_mm": [0.0, 80.0, 120.0], "frame": "stage"})
    results = estimate_session(folder)
    figures = error_motion_figures(results)
    assert [f.key for f in figures] == ["error_motions_angular", "error_motions_linear", "error_motions_tool"]
    angular = figures[0]
    labels = [s.label for s in angular.series]
    assert labels[0].startswith("EAX roll (about X): not resolved (noise p-v")
    assert "ECX yaw (about Z)" in labels and "truth ECX" in labels
    ecx = angular.series[labels.index("ECX yaw (about Z)")]
    assert ecx.band_low is not None and (ecx.band_high - ecx.band_low)[1:].min() > 0
    rows = error_motion_rows(results)
    assert [r[0] for r in rows] == ["EXX", "EYX", "EZX", "EAX", "EBX", "ECX"]
    assert [r[-1] for r in rows] == ["not resolved"] * 5 + ["resolved"]
    info = render_report(folder)
    page = next(p for p in info.pages if p and p[0].startswith("Error motions"))
    assert page[0] == "Error motions of the X axis (ISO 230-1)"
    assert [w for w in page if w.startswith("figure:")][:2] == ["figure:error_motions_angular",
                                                                 "figure:error_motions_linear"]
    assert any("figure:error_motions_tool" in p for p in info.pages)
    assert info.clipped == ()


def test_two_estimators_tell_one_story(tmp_path):
    """Issue 37: page 2 said "Max |yaw| not resolved" and the error-motions page "ECX resolved" with no word
    between them; now each quantity names where it is reported and gives the cross-check beside it."""
    from pypdf import PdfReader

    from lps_gui.report.pages.reconcile import PAGE2_NOTE, reconciliation_lines

    folder = _board_session(tmp_path / "s", {"offset_mm": [0.0, 80.0, 120.0], "frame": "stage"})
    results = estimate_session(folder)
    lines = reconciliation_lines(results)
    assert [line[:4] for line in lines] == ["EYX:", "EZX:", "EAX:", "EBX:", "ECX:"]
    ecx = lines[-1]
    assert "reported on this page, p-v" in ecx and "resolved" in ecx and "page 2's Max |yaw|" in ecx
    assert lines[0].startswith("EYX: reported on page 2, Max straightness v1")
    info = render_report(folder)
    text = " ".join(" ".join(p.extract_text().split()) for p in PdfReader(info.path).pages)
    text = text.replace("\ufb01", "fi").replace("\ufb02", "fl")
    assert PAGE2_NOTE in text and "ECX: reported on this page" in text
    assert info.clipped == ()
