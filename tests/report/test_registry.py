"""The registry of result sections (issue 34): the PDF and the GUI show what report/registry.py lists, so a
new section is one module plus one line there."""
from __future__ import annotations

import dataclasses

import pytest

from lps_gui.io.results.model import Results, as_results
from lps_gui.report import registry
from lps_gui.report.pages.content import SectionContent
from lps_gui.report.registry import AFTER_FIGURES, AFTER_PLOTS, SECTIONS, ResultSection, present, tab_contents
from tests.report.conftest import make_results, write_session

EXTRA = ResultSection("extra", lambda r: True, lambda r: [], AFTER_PLOTS,
                      lambda flow, r, h: flow.heading("An extra section"), lambda r, figures: SectionContent("Extra", figures))


def test_every_section_is_a_results_json_section_with_a_place():
    fields = {f.name for f in dataclasses.fields(Results)}
    assert [s.name for s in SECTIONS] == ["targets", "error_motions", "asme_b5_64"]
    for s in SECTIONS:
        assert s.name in fields and s.place in (AFTER_FIGURES, AFTER_PLOTS)


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
