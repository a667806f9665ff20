"""The results tabs of error motions (SPEC 14) and an ASME B5.64 test: shown when results have them, else absent."""
from __future__ import annotations

import json
import shutil

import pytest
from PySide6.QtCore import Qt

from lps_gui.io.results.model import as_results
from lps_gui.report.pages.asme import finding_lines, section, tur_cells
from lps_gui.report.pages.error_motions import error_motion_rows

pytestmark = pytest.mark.gui

PLAIN_TABS = ["Accuracy", "Deviation", "Steps", "Straightness, angles", "Residuals", "Table"]


@pytest.fixture(scope="module")
def min_step_session(min_step_demo, tmp_path_factory):
    """``lps demo --test min-step``: 2 um steps on a stage with a 3 um dead band (the run's one demo,
    tests/conftest.py), copied: the panel is given its folder."""
    folder = tmp_path_factory.mktemp("demo") / "session"
    shutil.copytree(min_step_demo.session_dir, folder)
    return folder, json.loads((folder / "results.json").read_text())


def _panel(qtbot):
    from lps_gui.gui.results.panel import ResultsPanel

    panel = ResultsPanel()
    qtbot.addWidget(panel)
    panel.resize(800, 900)
    panel.show()
    return panel


def _show(qtbot, panel, results, folder=None):
    with qtbot.waitSignal(panel.drawing_done, timeout=20000):
        panel.set_results(results, folder)
    qtbot.waitUntil(lambda: not panel.drawing, timeout=20000)  # the position table's worker too


def _tab_names(panel) -> list[str]:
    return [panel.tabs.tabText(i) for i in range(panel.tabs.count())]


def test_error_motions_and_asme_tabs_show_the_reports_figures_and_rows(qtbot, min_step_session):
    folder, raw = min_step_session
    results = as_results(raw)
    panel = _panel(qtbot)
    _show(qtbot, panel, results, folder)
    assert _tab_names(panel) == PLAIN_TABS[:-1] + ["Error motions", "ASME B5.64", "Table"]

    motions = panel.section_pages["Error motions"]
    assert {"error_motions_angular", "error_motions_linear"} <= set(panel.drawn)
    assert panel.drawn["error_motions_angular"].point_count("EAX") == len(results.positions)
    rows = error_motion_rows(results)
    assert motions.table.model_.rows == rows and [r[0] for r in rows] == ["EXX", "EYX", "EZX", "EAX", "EBX", "ECX"]
    model = motions.table.model_
    for i, row in enumerate(rows):  # not resolved: grey, as in the report's table
        color = model.data(model.index(i, 0), Qt.ItemDataRole.ForegroundRole)
        assert (color is None) == (row[-1] == "resolved")
    unresolved = [r[0] for r in rows if r[-1] != "resolved"]
    assert unresolved and motions.lines.text().startswith(f"Not resolved (grey): {', '.join(unresolved)}")

    asme = panel.section_pages["ASME B5.64"]
    assert "min_step" in panel.drawn and panel.drawn["min_step"].outliers  # the stuck steps crossed
    assert {c.name() for c in panel.drawn["min_step"].outliers} == {"stuck step"}  # not "outlier"
    assert asme.lines.text().startswith("The stage sticks:")
    assert asme.lines.text().splitlines() == finding_lines(results)
    assert asme.table.model_.rows == tur_cells(section(results).test_uncertainty_ratio)
    assert asme.table.model_.rows and asme.table.model_.rows[-1][0] == "Minimum incremental motion"
    panel.show_figure("min_step")
    assert panel.tabs.currentWidget() is panel.tab_holder(asme)  # the stack of plots in its scroll area


def test_results_without_the_sections_keep_the_tab_layout(qtbot, min_step_session):
    folder, raw = min_step_session
    plain = {k: v for k, v in raw.items() if k not in ("error_motions", "asme_b5_64")}
    names_only = dict(plain, asme_b5_64={"figures": raw["asme_b5_64"]["figures"]})  # the names, no test ran
    panel = _panel(qtbot)
    _show(qtbot, panel, plain)
    assert _tab_names(panel) == PLAIN_TABS
    _show(qtbot, panel, raw, folder)  # then a session with both, then one without: the tabs go again
    assert "Error motions" in _tab_names(panel)
    _show(qtbot, panel, names_only)
    assert _tab_names(panel) == PLAIN_TABS
    bar = panel.tabs.tabBar()
    assert bar.elideMode() == Qt.TextElideMode.ElideNone and panel.tabs.usesScrollButtons()  # whole tab names


def test_legends_keep_labels_of_distinct_colours_and_fit_long_labels():
    import numpy as np

    from lps_gui.gui.results.plot_adapter import legend_columns, wants_compact_legend
    from lps_gui.report.figures.spec import FigureSpec, Series

    x = np.arange(3.0)
    moves = FigureSpec("settling", "t", "x", "y", [Series(x, x, f"{k} mm", "line", f"#00000{k}") for k in range(8)])
    shared = FigureSpec("angles", "t", "x", "y", [Series(x, x, f"c{k % 4} {d}", "line", f"#00000{k % 4}")
                                                  for k, d in enumerate(["forward"] * 4 + ["backward"] * 4 + ["truth"] * 4)])
    assert not wants_compact_legend(moves) and wants_compact_legend(shared)  # each move's colour keeps its label
    unresolved = FigureSpec("error_motions_linear", "t", "x", "y",
                            [Series(x, x, f"EYX straightness along Y: not resolved (noise p-v {k} \u00b5m)", "line", "#888")
                             for k in range(3)])
    assert legend_columns(unresolved, False) == 1 and legend_columns(moves, False) == 3
