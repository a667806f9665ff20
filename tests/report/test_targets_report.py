"""A target session's report (SPEC 13): the targets' stretches on the deviation, the table of targets, their scale terms."""
from __future__ import annotations

import numpy as np
import pytest
from pypdf import PdfReader

from lps_gui.pipeline.estimate import estimate_session
from lps_gui.report.figures.plots import figure_by_key, figures_from_results
from lps_gui.report.figures.targets import TARGET_LABEL, lanes
from lps_gui.report.pages.targets import WORLD_FRAME, target_table
from lps_gui.report.pdf.document import render_report
from tests.pipeline.test_estimate_targets import point_session

pytestmark = pytest.mark.gui


@pytest.fixture(scope="module")
def row(tmp_path_factory):
    session, _ = point_session(tmp_path_factory.mktemp("row") / "row")  # the small-row preset: 3 targets
    session.meta["targets"][2]["square_mm_uncertainty_um"] = 2.0
    session.save_meta()
    results = estimate_session(session.folder)
    return session.folder, results, np.array([p["target_mm"] for p in results["positions"]])


def test_the_deviation_marks_the_stretch_each_target_was_seen_over(row):
    _, results, x = row
    figure = figure_by_key(figures_from_results(results), "deviation")
    bars = [s for s in figure.series if s.label.startswith(TARGET_LABEL)]
    assert [s.label for s in bars] == [f"{TARGET_LABEL} T{j}" for j in range(3)]
    index = np.array([p["index"] for p in results["positions"]])
    for bar, target in zip(bars, results["targets"]):
        seen = x[np.isin(index, target["seen_by"])]
        assert bar.x.tolist() == [seen.min(), seen.max()] and bar.y[0] == bar.y[1]
    data_low = min(np.nanmin(s.band_low) for s in figure.series if s.band_low is not None)
    assert all(bar.y[0] < data_low for bar in bars)  # below the data, never over it
    plain = figure_by_key(figures_from_results({k: v for k, v in results.items() if k != "targets"}), "deviation")
    assert [s.label for s in plain.series] == [s.label for s in figure.series[: len(figure.series) - len(bars)]]


def test_overlapping_stretches_get_their_own_lanes():
    assert lanes([("T0", 0, 340), ("T1", 0, 670), ("T2", 160, 1010), ("T3", 500, 1360), ("T4", 830, 1524)]) == [
        0, 1, 2, 0, 1]


def test_the_table_lists_views_ties_pose_sigma_and_the_budgets_scale_term(row):
    _, results, _ = row
    header, rows, widths = target_table(results)
    assert len(header) == len(widths) and [r[0] for r in rows] == ["T0", "T1", "T2"]
    budget = {b["source"]: b for b in results["uncertainty"]["budget"]}
    for cells, target in zip(rows, results["targets"]):
        assert cells[2:4] == [str(target["views"]), str(target["ties"])]
    assert rows[0][6] == rows[0][7] == WORLD_FRAME
    sigma = [float(v) for v in rows[1][7].split(" / ")]
    assert sigma == pytest.approx(1e3 * np.array(results["targets"][1]["p_sigma_mm"]), rel=0.05)  # 2 digits
    assert float(rows[2][8]) == pytest.approx(budget["target scale T2"]["contribution_um"], rel=1e-3)
    assert rows[1][8] == "\u2014"  # its print's uncertainty is not stated: no term
    assert target_table({k: v for k, v in results.items() if k != "targets"}) is None  # one board: no table


def test_the_report_has_the_targets_page_and_nothing_of_it_is_clipped(row):
    folder, results, _ = row
    info = render_report(folder, results)
    assert not [c for c in info.clipped if c.startswith(("page 1:", "page 2:", "page 5:"))]  # the pages with targets
    assert "Targets (3)" in info.pages[1]
    pages = [p.extract_text().replace("\t", " ") for p in PdfReader(info.path).pages[:2]]  # Qt's word gaps
    front, text = pages
    assert "T2" in text and "world frame" in text
    assert f"{TARGET_LABEL} T0" in front and "3 ChArUco targets" in front


def test_a_constellation_lists_both_axes_scale_terms_and_its_stretch_in_the_plane():
    def target(j):
        return {"id": f"T{j}", "first_marker": 44 * j, "views": 10, "ties": 8, "rvec_sigma_rad": [1e-4] * 3,
                "p_sigma_mm": [0.004, 0.005, 0.02], "stretch_mm": [[0.0, 0.0], [381.0, 254.0]], "covered_fraction": 0.5}

    budget = {axis: {"budget": [{"source": f"target scale T{j}", "contribution_um": 0.5 + j + k}
                                for j in range(2)]} for k, axis in enumerate("XY")}
    positions = [{"index": 0, "target_x_mm": 0.0, "target_y_mm": 0.0, "measured_x_mm": 0.0, "measured_y_mm": 0.0}]
    _, rows, _ = target_table({"format": "lps-results/1", "axes": ["X", "Y"], "positions": positions,
                               "targets": [target(0), target(1)], "uncertainty": {"per_axis": budget}})
    assert rows[1][4] == "(0, 0) \u2013 (381.0, 254.0)" and rows[1][8] == "1.50 / 2.50" and rows[1][5] == "50 %"


def test_a_row_has_no_board_plane_curves_only_the_pointer_to_the_error_motions(row):
    """No per-view straightness or angles from the row model: the truth's 1e-10 curves are not drawn either."""
    from lps_gui.report.figures.plots import figure_by_key, figures_from_results

    _, results, _ = row
    figures = figures_from_results(results)
    for key in ("straightness", "angles"):
        f = figure_by_key(figures, key)
        assert f.series == [] and "error motions" in f.notes
    assert figure_by_key(figures, "deviation").series  # the positions are drawn


def test_the_row_report_speaks_iso_and_gum_without_internal_names_or_template_dashes(row):
    """Issue 37: customer pages named "SPEC 11/13/14" and raw keys, and printed "median 1 sigma is - um (v1)"."""
    import re

    folder, results, _ = row
    info = render_report(folder, results)
    text = " ".join(" ".join(p.extract_text().split()) for p in PdfReader(info.path).pages)
    assert not re.search(r"SPEC \d", text)
    assert "square_mm_uncertainty_um" not in text and "stage_spec" not in text
    assert not re.search("\u2014 \u00b5m \\(v[12]\\)", text), "a template with no numbers"
    # a row's straightness and angles come from the stops' poses, the one estimator it has: named, never a dash
    assert "Straightness EYX (peak-to-valley, error motions)" in text and "Yaw ECX (peak-to-valley, error motions)" in text
    assert "Max straightness v1 (peak-to-valley) \u2014" not in text


def test_the_targets_print_scales_say_how_they_combine():
    """Issue 37: several targets' print-scale terms were combined in quadrature without saying so."""
    from lps_gui.core.metrology.target_scale import target_scale_rows

    targets = [{"id": f"T{i}", "covered_fraction": 1 / 3, "square_mm": 10.0, "square_mm_uncertainty_um": 1.0}
               for i in range(3)]
    rows = target_scale_rows(targets, 300.0)
    each = rows[0].contribution_um
    assert each == pytest.approx(10.0)
    note = rows[0].note
    assert "uncorrelated" in note and "one printer" in note
    assert f"{np.sqrt(3) * each:.3g} \u00b5m" in note and f"{3 * each:.3g} \u00b5m" in note
