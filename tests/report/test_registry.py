"""The registry of result sections (issue 34): the PDF and the GUI show what report/registry.py lists, so a
new section is one module plus one line there."""
from __future__ import annotations

import dataclasses

import pytest

from lps_gui.io.results.model import Results, as_results
from lps_gui.report import registry
from lps_gui.report.pages.content import SectionContent
from lps_gui.report.registry import AFTER_FIGURES, AFTER_PLOTS, REPORT, SECTIONS, ResultSection, present, tab_contents
from tests.report.conftest import make_results, write_session

EXTRA = ResultSection("extra", lambda r: True, lambda r: [], AFTER_PLOTS,
                      lambda flow, r, h: flow.heading("An extra section"), lambda r, figures: SectionContent("Extra", figures))


def test_every_section_is_a_results_json_section_with_a_place():
    fields = {f.name for f in dataclasses.fields(Results)}
    assert [s.name for s in SECTIONS] == ["targets", "error_motions", "asme_b5_64", "planar"]
    for s in SECTIONS:
        assert s.place in (AFTER_FIGURES, AFTER_PLOTS, REPORT)
        if s.place == REPORT:  # a report of its own: its pages and the panel's tables instead of the line's
            assert s.report is not None and s.table is not None and s.positions is not None
        else:
            assert s.name in fields and s.paint is not None


def test_a_planar_session_has_its_own_report_and_tables_from_the_registry(small_planar_estimated):
    from lps_gui.io.results.model import read_results
    from lps_gui.report.pages.planar import planar_position_table, planar_summary_rows

    planar = read_results(small_planar_estimated / "results.json")
    assert registry.own_report(planar).name == "planar"
    rows = registry.figure_table(planar)
    assert [r[0] for r in rows][:len(planar_summary_rows(planar))] == [r.name for r in planar_summary_rows(planar)]
    assert registry.position_table(planar) == planar_position_table(planar)[:2]
    line = as_results(make_results()[0])
    assert registry.own_report(line) is None and registry.figure_table(line) is None
    assert registry.position_table(line)[0] != registry.position_table(planar)[0]


def test_a_light_field_folder_is_a_folder_section(tmp_path):
    """The light field tab's content comes from its registry line: the folder's numbers and its EPIs, or one line."""
    import json

    from lps_gui.errors import InputError

    section = registry.folder_section("lightfield")
    with pytest.raises(InputError, match="no lightfield.json here"):
        section.content(tmp_path)
    check = {"n_points": 40, "vertical_disparity_rms_px": {"before": 0.5, "after": 0.01}}
    (tmp_path / "lightfield.json").write_text(json.dumps({"views": [{}] * 9, "axes": ["X", "Y"], "check": check,
                                                          "uniform": {"hci": True}}))
    content = section.content(tmp_path)
    assert content.lines == ["9 views on X and Y", "vertical disparity RMS, before (40 known scene points): 0.500 px",
                             "vertical disparity RMS, after: 0.0100 px", "HCI layout written"]
    assert [p for p, _ in content.pictures] == [str(tmp_path / "epi_before.png"), str(tmp_path / "epi_after.png")]


def test_results_without_the_sections_have_none():
    results = as_results(make_results()[0])
    assert present(results) == [] and tab_contents(results) == []


@pytest.mark.gui
def test_a_registered_section_reaches_the_pdf_and_the_gui(tmp_path, monkeypatch):
    from lps_gui.report.pdf.document import render_report

    results, truth = make_results()
    folder = write_session(tmp_path / "s", results, truth, None)
    before = render_report(folder, out=tmp_path / "before.pdf")
    monkeypatch.setattr(registry, "SECTIONS", (*SECTIONS, EXTRA))
    after = render_report(folder, out=tmp_path / "after.pdf")
    assert not any("An extra section" in p for p in before.pages)
    page = next(i for i, p in enumerate(after.pages) if "An extra section" in p)
    assert "Plots" in sum(after.pages[:page + 1], [])  # at its place: after the plots
    assert [c.title for c in tab_contents(as_results(results))] == ["Extra"]


@pytest.mark.gui
def test_the_pdf_paints_the_planar_report_the_registry_names(small_planar_estimated, tmp_path, monkeypatch):
    from lps_gui.report.pdf.document import render_report

    stand_in = dataclasses.replace(registry.SECTIONS[-1], report=lambda flow, meta, r, title, h: flow.heading("Stand-in"))
    monkeypatch.setattr(registry, "SECTIONS", (*registry.SECTIONS[:-1], stand_in))
    info = render_report(small_planar_estimated, out=tmp_path / "planar.pdf")
    assert info.n_pages == 1 and "Stand-in" in info.pages[0]
