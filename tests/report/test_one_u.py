"""One figure, one U: every page prints the U (k = 2) of results.json ``uncertainty.figures_k2`` for a figure."""
from __future__ import annotations

import json

import pytest

from lps_gui.report.pages.summary import fmt, summary_rows, u_key
from lps_gui.report.pages.verdict import verdicts
from lps_gui.report.pdf.document import render_report
from tests.report.conftest import make_results, with_unresolved_extremes

pytestmark = pytest.mark.gui
SPEC = {"accuracy_um": 20, "repeatability_um": 5, "straightness_um": 38}


def _cells_after(texts: list[str], name: str, n: int) -> list[str]:
    """The ``n`` table cells drawn after the cell ``name`` (a row's cells are drawn left to right)."""
    i = texts.index(name)
    return texts[i + 1:i + 1 + n]


def _table_texts(info, page: int) -> list[str]:
    return [t.text for t in info.texts if t.page == page and t.where == "table"]


def test_the_same_figure_carries_the_same_u_on_every_page_and_in_results(tmp_path):
    results, truth = with_unresolved_extremes(make_results()[0]), make_results()[1]
    folder = tmp_path / "s"
    folder.mkdir()
    (folder / "session.json").write_text(json.dumps({"format": "lps-session/1", "truth": truth, "stage_spec": SPEC}))
    (folder / "results.json").write_text(json.dumps(results))
    info = render_report(folder)
    k2 = results["uncertainty"]["figures_k2"]

    page2 = _table_texts(info, 2)
    printed_u: dict[str, str] = {}
    for row in summary_rows(results):
        value, u_cell, unit = _cells_after(page2, row.name, 3)
        assert value == row.text() and u_cell == row.u_text() and unit == row.unit
        if row.unresolved:  # "not resolved (noise p-v X)" states no value, hence no U (never one smaller than X)
            assert u_cell == "" and row.u_k2 is None
            continue
        want = k2.get("mean_step_um") * 1e-3 if row.key == "mean_step" else k2.get(u_key(row.key))
        assert row.u_k2 == want, row.name  # results.json is the one source
        printed_u[row.key] = u_cell
    assert printed_u["iso230_2_A"] == f"\u00b1 {fmt(k2['A_um'], 2)}"
    assert printed_u["straightness_span_1"] == f"\u00b1 {fmt(k2['straightness_span_1'], 2)}"

    page1 = _table_texts(info, 1)
    rows = {v.name: v for v in verdicts(results, SPEC)}
    accuracy = rows["Positional accuracy"]
    measured, u_cell = _cells_after(page1, "Positional accuracy", 2)
    assert measured.startswith("A/2 = ")  # the quantity the U belongs to is named
    assert accuracy.u_k2 == pytest.approx(0.5 * k2["A_um"], rel=1e-12)  # U(A/2) = U(A)/2, A's U is page 2's
    assert u_cell == f"\u00b1 {fmt(accuracy.u_k2)} \u00b5m"
    straight = rows["Straight-line accuracy"]
    measured, u_cell = _cells_after(page1, "Straight-line accuracy", 2)
    assert measured.startswith("p-v v2 = ") and straight.u_k2 == k2["straightness_span_2"]  # the larger span's U

    page3 = [t.text for t in info.texts if t.page == 3]
    assert any(f"expanded U = k u_c = {fmt(k2['A_um'])} \u00b5m" in t for t in page3)  # the budget's U is A's


def test_without_a_stage_spec_page_one_shows_the_measured_figures_with_u(tmp_path):
    from lps_gui.report.pages.sections import FRONT_FIGURES

    results, truth = make_results()
    folder = tmp_path / "s"
    folder.mkdir()
    (folder / "session.json").write_text(json.dumps({"format": "lps-session/1", "truth": truth}))
    (folder / "results.json").write_text(json.dumps(results))
    info = render_report(folder)
    page1 = _table_texts(info, 1)
    shown = [r for r in summary_rows(results) if r.key in FRONT_FIGURES]
    assert {r.key for r in shown} >= {"iso230_2_A", "iso230_2_R", "iso230_2_E", "max_abs_deviation", "scale"}
    for row in shown:
        value, u_cell, unit = _cells_after(page1, row.name, 3)
        assert value == row.text() and unit == row.unit
        assert u_cell == row.u_text()  # with U (k = 2) where assessed, the same as page 2's
        assert row.key not in ("iso230_2_A", "iso230_2_E", "max_abs_deviation") or u_cell.startswith("\u00b1 ")
        assert _cells_after(_table_texts(info, 2), row.name, 3)[1] == u_cell


from tests.report.test_layout_fit import planar_session  # noqa: E402,F401  (a simulated, estimated planar session)


def _planar_with_budget(folder, tmp_path, spec=None):
    """The planar session's results with an ``environment`` and an ``uncertainty`` section (as the one estimation path gives)."""
    import shutil

    from lps_gui.core.geometry.board import Board
    from lps_gui.core.metrology.environment import Environment, thermal_record
    from tests.report.conftest import ENVIRONMENT

    out = tmp_path / "planar"
    shutil.copytree(folder, out)
    results = json.loads((out / "results.json").read_text())
    results["environment"] = thermal_record(Board(9, 6, 20.0), Environment.from_dict(ENVIRONMENT))
    results["uncertainty"] = {"budget": make_results()[0]["uncertainty"]["budget"], "combined_standard_um": 1.5,
                              "coverage_factor": 2.0, "expanded_k2_um": 3.0,
                              "figures_k2": {"squareness_urad": 41.5, "scale_x_ppm": 33.0, "scale_y_ppm": 34.0}}
    (out / "results.json").write_text(json.dumps(results))
    if spec:
        meta = json.loads((out / "session.json").read_text())
        meta["stage_spec"] = spec
        (out / "session.json").write_text(json.dumps(meta))
    return out, results


def test_a_planar_figure_carries_the_u_of_results_on_every_page(planar_session, tmp_path):  # noqa: F811
    from lps_gui.report.pages.planar import planar_summary_rows

    folder, results = _planar_with_budget(planar_session, tmp_path, SPEC)
    info = render_report(folder)
    assert info.clipped == ()
    page1 = _table_texts(info, 1)
    rows = {r.key: r for r in planar_summary_rows(results) if r.key}
    for key, want in (("squareness_urad", 41.5), ("squareness_um_per_m", 41.5), ("scale_x_ppm", 33.0)):
        assert rows[key].u_k2 == want
        assert _cells_after(page1, rows[key].name, 2)[1] == f"\u00b1 {fmt(want, 2)}"
    words = [w for page in info.pages for w in page]
    # the line report's sections, painted for the planar session because its results hold them
    assert {"Verdict", "Environment", "Uncertainty budget (GUM, ISO/TR 230-9)"} <= set(words)
    assert any(w.startswith("ISO 230-2 per target, X axis") for w in words)
    assert "X: Positional accuracy" in page1 and "Y: Repeatability" in page1
    stage = _cells_after([t.text for t in info.texts if t.where == "table"], "Stage", 1)[0]
    assert stage.endswith("axes X, Y")


def test_planar_u_without_a_budget_is_two_sigma_and_a_truth_beyond_u_is_not_trusted(planar_session):  # noqa: F811
    from lps_gui.report.pages.planar import planar_summary_rows

    results = json.loads((planar_session / "results.json").read_text())
    results.pop("uncertainty", None)
    pl = results["figures"]["planar"]
    results["truth_comparison"].update(squareness_error_urad=5 * pl["squareness_sigma_urad"], squareness_z=5.0)
    sq = next(r for r in planar_summary_rows(results) if r.key == "squareness_urad")
    assert sq.u_k2 == pytest.approx(2 * pl["squareness_sigma_urad"])
    assert "not trusted" in sq.note and "5.0 \u03c3" in sq.note


def test_the_planar_report_paints_each_axis_budget_the_one_path_writes(planar_session):  # noqa: F811
    """The estimate writes one budget per axis (uncertainty.per_axis); the report shows both, and the scales' U."""
    from lps_gui.report.pages.planar import planar_summary_rows

    results = json.loads((planar_session / "results.json").read_text())
    per_axis = results["uncertainty"]["per_axis"]
    assert set(per_axis) == {"X", "Y"} and "figures_k2" not in results["uncertainty"]
    info = render_report(planar_session)
    words = [w for page in info.pages for w in page]
    assert {"Uncertainty budget (GUM, ISO/TR 230-9), X axis", "Uncertainty budget (GUM, ISO/TR 230-9), Y axis"} <= set(words)
    rows = {r.key: r for r in planar_summary_rows(results) if r.key}
    assert rows["scale_x_ppm"].u_k2 == pytest.approx(per_axis["X"]["figures_k2"]["scale_ppm"])
    assert rows["scale_y_ppm"].u_k2 == pytest.approx(per_axis["Y"]["figures_k2"]["scale_ppm"])
