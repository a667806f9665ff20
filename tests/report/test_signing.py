"""Issue 37: a report a lab can sign: laboratory, certificate number, the instruments' identifiers and
certificates (board, thermometer, camera), dates and an approval line, from `lps capture` switches or the GUI."""
import argparse

import pytest
from pypdf import PdfReader

from lps_gui.cli.capture.setup import add_setup_arguments, setup_meta
from lps_gui.report.pages.signing import NOT_RECORDED, SIGN_LINE, SIGNING_FIELDS, signing_rows
from tests.report.conftest import make_results, write_session

SWITCHES = ["--lab", "Metrology Lab A", "--certificate", "C-2026-017", "--board-id", "B-12", "--board-cert", "DKD-99",
            "--thermometer", "PT100 #4", "--thermometer-cert", "T-123", "--camera-serial", "SN 4711",
            "--camera-cert", "K-7", "--approved-by", "Dr. Q. Head"]


def _meta(argv):
    p = argparse.ArgumentParser()
    add_setup_arguments(p)
    return setup_meta(p.parse_args(argv))


def test_capture_switches_fill_the_signing_block():
    meta = _meta(SWITCHES)
    rows = dict(signing_rows({**meta, "created": "2026-12-01T10:00:00"}, make_results()[0], today="2026-12-03"))
    assert rows["Laboratory"] == "Metrology Lab A" and rows["Certificate no."] == "C-2026-017"
    assert rows["Board"] == "B-12, certificate DKD-99" and rows["Thermometer"] == "PT100 #4, certificate T-123"
    assert rows["Camera"] == "SN 4711, certificate K-7"
    assert rows["Measured on"] == "2026-12-01T10:00:00" and rows["Report issued"] == "2026-12-03"
    assert rows["Approved by"] == "Dr. Q. Head" and rows["Signature and date"] == SIGN_LINE


def test_nothing_recorded_says_so_and_leaves_lines_to_sign():
    rows = dict(signing_rows({}, make_results()[0]))
    assert rows["Laboratory"] == rows["Board"] == rows["Thermometer"] == NOT_RECORDED
    assert rows["Approved by"] == SIGN_LINE


@pytest.mark.gui
def test_the_gui_asks_for_every_signing_field(qtbot):
    from lps_gui.gui.capture.report_setup import ReportSetupBox

    box = ReportSetupBox()
    qtbot.addWidget(box)
    assert len(SIGNING_FIELDS) == 9 and {key for key, _, _ in SIGNING_FIELDS} <= set(box.ident)


@pytest.mark.gui
def test_the_pdf_prints_the_signing_block(tmp_path):
    from lps_gui.report.pdf.document import render_report

    results, truth = make_results()
    folder = write_session(tmp_path / "s", results, truth, {"accuracy_um": 20, "repeatability_um": 5, "straightness_um": 38})
    import json

    meta = json.loads((folder / "session.json").read_text())
    meta["identification"] = _meta(SWITCHES)["identification"]
    (folder / "session.json").write_text(json.dumps(meta))
    info = render_report(folder)
    assert info.clipped == ()
    text = " ".join(PdfReader(info.path).pages[0].extract_text().split()).replace("\ufb01", "fi")  # on page 1
    for want in ("Certificate and approval", "Metrology Lab A", "C-2026-017", "B-12, certificate DKD-99",
                 "PT100 #4, certificate T-123", "SN 4711, certificate K-7", "Dr. Q. Head"):
        assert want in text, want
