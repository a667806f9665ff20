"""The layout-time clipping check: every string drawn is measured against its box, in every kind of PDF."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.report.pdf.text_fit import fit_widths
from tests.report.conftest import make_results, with_unresolved_extremes, write_session
from tests.report.test_intrinsics_report import BOARD, INTR, corners  # noqa: F401  (the calibration fixture)

pytestmark = pytest.mark.gui
SPEC = {"accuracy_um": 20, "repeatability_um": 5, "straightness_um": 38}


_session = write_session


def test_fit_widths_takes_slack_first_then_room():
    assert fit_widths([88, 26], [60, 26], 180) == [88, 26]  # everything fits: unchanged
    w = fit_widths([88, 26], [60, 44], 114)  # 18 mm short, 28 mm of slack in the first column
    assert w == pytest.approx([70, 44]) and sum(w) == pytest.approx(114)
    w = fit_widths([20, 10], [20, 40], 50)  # no slack: grows up to the room, then the caller wraps
    assert w == pytest.approx([20, 30])
    w = fit_widths([78, 30, 12, 60], [92.8, 47, 8, 45], 180)  # slack and room together never pass max_total
    assert sum(w) == pytest.approx(180) and w[2] == pytest.approx(8) and w[3] == pytest.approx(45)


def test_the_demos_cut_cell_is_an_overflow_and_widening_removes_it(tmp_path):
    """`lps demo --quick` page 2 printed "not resolved (σ 2321 µrad)" in a 26 mm column, read as "ved (σ ...)"."""
    from PySide6.QtCore import QRectF, Qt

    from lps_gui.report.pdf.layout import PdfFlow, ensure_gui_app
    from lps_gui.report.pdf.text_fit import draw_text, font

    ensure_gui_app()
    flow = PdfFlow(tmp_path / "t.pdf", "t", "t")
    cell = "not resolved (noise max 2321 \u00b5rad)"
    flow.painter.setFont(font(8.0))
    assert not draw_text(flow.painter, QRectF(0, 0, 24 * flow.mm, 4.2 * flow.mm), int(Qt.AlignmentFlag.AlignRight),
                         cell, flow.log.text, "table")  # the old fixed column: caught
    assert flow.log.clipped == [f"page 1: {cell}"]
    flow.log.text.texts.clear()
    flow.table(["figure", "value", "U (k = 2)", "unit"], [["Max |roll|", cell, "", "\u00b5rad"]], [88, 26, 22, 16])
    assert flow.log.clipped == []  # the table widened the value column from the name column's slack
    flow.table(None, [["x", "W" * 60]], [10, 10],
               max_width_mm=30)
    flow.finish()
    assert len(flow.log.clipped) == 1  # neither widened nor wrapped enough: reported


def test_a_long_axis_label_is_set_smaller_to_fit(tmp_path):
    from lps_gui.report.figures.spec import FigureSpec, Series
    from lps_gui.report.pdf.layout import PdfFlow, ensure_gui_app

    ensure_gui_app()
    flow = PdfFlow(tmp_path / "t.pdf", "t", "t")
    series = [Series(np.arange(5.0), np.arange(5.0) ** 2, "a series")]
    flow.figure(FigureSpec("k", "title", "x [mm]", "measured step \u2212 commanded step [\u00b5m]", series), 82.0)
    assert flow.log.clipped == []
    flow.figure(FigureSpec("k", "title", "x [mm]", "a y label " * 30, series), 82.0)
    flow.finish()
    assert [t.where for t in flow.log.text.overflows()] == ["axis"]


@pytest.fixture(scope="module")
def planar_session(small_planar_estimated, tmp_path_factory):
    """The shared estimated planar session (tests/conftest.py), copied: a report is written into it."""
    import shutil

    folder = tmp_path_factory.mktemp("planar") / "s"
    shutil.copytree(small_planar_estimated, folder)
    return folder


@pytest.mark.parametrize("kind", ["line with spec", "line without spec", "line, demo's unresolved figures"])
def test_no_string_of_a_line_report_is_clipped(tmp_path, kind):
    from lps_gui.report.pdf.document import render_report

    results, truth = make_results()
    if "demo" in kind:
        with_unresolved_extremes(results)
    info = render_report(_session(tmp_path / "s", results, truth, None if "without" in kind else SPEC))
    assert info.clipped == ()
    assert info.texts  # the check saw the strings: tables, headings, ticks and axis labels
    assert {"table", "heading", "paragraph", "axis", "title", "legend", "footer"} <= {t.where for t in info.texts}


def test_no_string_of_a_planar_report_is_clipped(planar_session):
    from lps_gui.report.pdf.document import render_report

    info = render_report(planar_session)
    assert info.clipped == ()
    assert {"table", "axis", "title"} <= {t.where for t in info.texts}


def test_no_string_of_a_compare_report_is_clipped(tmp_path):
    from lps_gui.report.pdf.compare import write_comparison

    before, truth = make_results(seed=3)
    after, truth2 = make_results(seed=4)
    clipped: list[str] = ["sentinel"]
    write_comparison(_session(tmp_path / "b", before, truth), _session(tmp_path / "a", after, truth2),
                     tmp_path / "c.pdf", clipped)
    assert clipped == ["sentinel"]


def test_no_string_of_an_intrinsics_report_is_clipped(corners, tmp_path):  # noqa: F811
    from lps_gui.core.intrinsics.calibration import calibrate_intrinsics
    from lps_gui.core.intrinsics.crossval import cross_validate
    from lps_gui.report.pdf.intrinsics import write_intrinsics_report

    cal = calibrate_intrinsics(BOARD.flat_points(), corners, INTR.image_size)
    clipped: list[str] = []
    write_intrinsics_report(cal, tmp_path / "i.pdf", cross_validate(BOARD.flat_points(), corners, INTR.image_size),
                            clipped=clipped)
    assert clipped == []
