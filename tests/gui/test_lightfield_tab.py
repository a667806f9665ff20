"""File > Open light field: the results dock's "Light field" tab shows the EPIs and the epipolar numbers (issue 38)."""
from __future__ import annotations

import pytest

pytestmark = pytest.mark.gui


@pytest.fixture
def lightfield_folder(lightfield_demo):
    return lightfield_demo.plain.out


def test_the_light_field_tab_shows_both_epis_and_the_numbers(window, lightfield_folder):
    assert window.open_lightfield(lightfield_folder)
    panel = window.results_panel
    page = panel.lightfield_page
    assert panel.tabs.currentWidget() is page and panel.tabs.tabText(panel.tabs.indexOf(page)) == "Light field"
    text = page.summary.text()
    assert "vertical disparity RMS" in text and "HCI layout not written: view" in text
    assert "depth from the disparity slope" in text
    for caption, picture in page.pictures:
        assert not picture.pixmap().isNull() and picture.pixmap().width() > 0
    assert window.open_lightfield(lightfield_folder)  # opened again: one tab, not two
    assert sum(panel.tabs.tabText(i) == "Light field" for i in range(panel.tabs.count())) == 1


def test_a_folder_without_a_light_field_is_one_line_and_changes_nothing(window, tmp_path):
    count = window.results_panel.tabs.count()
    assert not window.open_lightfield(tmp_path)
    assert window.last_error[0] == "Not a light field" and "lightfield.json" in window.last_error[1]
    assert window.results_panel.tabs.count() == count


def test_the_tab_and_the_report_page_print_the_epipolar_numbers_alike(window, lightfield_folder):
    """Issue 37: the light field's numbers are formatted once (report.pdf.lightfield.epipolar_rows): the report page's
    table and the GUI's tab show the same text for each, and the PDF prints every row."""
    import json

    from pypdf import PdfReader

    from lps_gui.report.pdf.lightfield import check_rows, epipolar_rows

    assert window.open_lightfield(lightfield_folder)
    text = window.results_panel.lightfield_page.summary.text()
    doc = json.loads((lightfield_folder / "lightfield.json").read_text())
    rows = epipolar_rows(doc.get("check"))
    assert len(rows) >= 5  # before, after, and per plane: residual measured, nominal, depth from slope
    pdf = " ".join(" ".join(page.extract_text().split()) for page in PdfReader(str(lightfield_folder / "report.pdf")).pages)
    for what, value in rows:
        assert f"{what}: {value}" in text
        assert [what, value] in check_rows(doc) and value in pdf
