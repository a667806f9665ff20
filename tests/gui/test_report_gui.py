"""GUI parts of issue 14: spec/environment/identification entry, ISO preset, results leading with the answer."""
from __future__ import annotations

import json

import numpy as np
import pytest

from lps_gui.core.planning.plan import Plan

pytestmark = pytest.mark.gui


def test_capture_panel_writes_spec_environment_identification(qtbot, make_window, tmp_path):
    from lps_gui.core.clock import SimClock
    from tests.gui.conftest import connect_sim

    window = make_window(sim_clock=SimClock())
    connect_sim(qtbot, window)
    cam = window.camera_panel
    qtbot.waitUntil(lambda: cam.sim_camera is not None, timeout=5000)
    assert cam.start()
    cap = window.capture_panel
    cap.set_plan(Plan(start_mm=0.0, stop_mm=4.0, step_mm=2.0, directions="+", runs=1))
    box = cap.report_setup
    box.select_preset("paper")
    assert box.spec["accuracy_um"].value() == 20.0 and box.spec["straightness_um"].value() == 38.0
    box.env["board_temperature_c"].setValue(23.0)
    box.env["board_cte_ppm_per_k"].setValue(23.0)
    box.ident["operator"].setText("A. Meier")
    folder = tmp_path / "s"
    cap.folder.set_text(str(folder))
    with qtbot.waitSignal(cap.session_done, timeout=60000):
        cap.start_btn.click()
    meta = json.loads((folder / "session.json").read_text())
    assert meta["stage_spec"] == {"accuracy_um": 20.0, "repeatability_um": 5.0, "straightness_um": 38.0}
    assert meta["environment"] == {"board_temperature_c": 23.0, "board_cte_ppm_per_k": 23.0}  # unrecorded left out
    assert meta["identification"] == {"operator": "A. Meier"}
    box.spec["accuracy_um"].setValue(15.0)
    assert box.preset.currentData() == ""  # edited by hand: custom


def test_iso_preset_gives_five_runs_both_ways_non_uniform(qtbot, window):
    cap = window.capture_panel
    cap.set_plan(Plan(start_mm=0.0, stop_mm=100.0, step_mm=5.0, directions="+", runs=1))
    cap.pitch_mm.setValue(5.0)
    cap.apply_iso_plan()
    plan = cap.plan()
    t = plan.targets()
    assert plan.runs == 5 and plan.directions == "both" and t[0] == 0.0 and t[-1] == 100.0
    assert np.ptp(np.diff(t)) > 1.0  # non-uniform
    assert np.ptp(np.mod(t[1:-1], 5.0)) > 4.0  # spread over the pitch
    assert "ISO 230-2" in cap.summary.text()
    assert cap.estimate_s(plan) > 0


def test_results_open_on_accuracy_with_limit_drawn_and_open_report(qtbot, window, tmp_path):
    from tests.report.conftest import make_results

    results, truth = make_results()
    folder = tmp_path / "session"
    folder.mkdir()
    (folder / "session.json").write_text(json.dumps({"format": "lps-session/1", "truth": truth,
                                                     "stage_spec": {"accuracy_um": 20.0, "repeatability_um": 5.0}}))
    (folder / "results.json").write_text(json.dumps(results))
    rp = window.results_panel
    assert not rp.open_report_btn.isEnabled()
    with qtbot.waitSignal(rp.drawing_done, timeout=20000):
        rp.set_results(results, folder, folder)
    assert rp.tabs.currentWidget() is rp.accuracy_page
    assert rp.iso_table.item(0, 2) is not None and "\u00b1" in rp.iso_table.item(0, 2).text()
    assert "Positional accuracy" in rp.verdict.text() and "indicative" in rp.verdict.text()
    labels = [s.label for s in rp.drawn["deviation"].spec.series]
    assert any("accuracy limit" in label for label in labels)
    assert not rp.open_report_btn.isEnabled()
    (folder / "report.pdf").write_bytes(b"%PDF-1.4")
    rp.set_report(folder / "report.pdf")
    assert rp.open_report_btn.isEnabled() and rp.report_path == folder / "report.pdf"


def test_results_show_every_column_all_tabs_and_the_per_target_table(qtbot, window, tmp_path, monkeypatch):
    """Issue 26 item 10: U (k = 2) and Unit in sight, no tab behind scroll arrows, the ISO per-target table."""
    from tests.report.conftest import make_results

    results, _truth = make_results()
    import lps_gui.gui.main_window as main_window

    monkeypatch.setattr(main_window, "clamp_to_screen", lambda w: None)  # a 1600 px screen, not offscreen's 800
    window.resize(1600, 960)
    window.default_layout()  # the first start's layout
    rp = window.results_panel
    window.show_panel("results")
    with qtbot.waitSignal(rp.drawing_done, timeout=20000):
        rp.set_results(results, None, None)
    qtbot.wait(50)
    table = rp.iso_table
    assert [table.horizontalHeaderItem(c).text() for c in range(4)] == ["Figure", "Value", "U (k = 2)", "Unit"]
    for c in (1, 2, 3):  # wholly inside the visible part of the table
        assert table.columnViewportPosition(c) + table.columnWidth(c) <= table.viewport().width(), c
    bar = rp.tabs.tabBar()
    assert rp.tabs.count() <= 7 and bar.sizeHint().width() <= rp.tabs.width()
    assert rp.target_table.isVisibleTo(rp) and rp.target_table.rowCount() == len(
        results["figures"]["iso230_2"]["per_target"]["target_mm"])
