"""The capture panel's planar mode: the grid editor and its drawing, the rig prediction, a capture on
the simulated gantry from the GUI, resume after an abort, and the planar results in the results panel."""
from __future__ import annotations

import json
import re

import numpy as np
import pyqtgraph as pg
import pytest

from lps_gui.core.clock import SimClock
from lps_gui.core.geometry.board import Board
from lps_gui.gui.capture.planar_plan_editor import PlanarPlanEditor, planar_duration_s

pytestmark = pytest.mark.gui

SHARED = {"directions": "+", "runs": 1, "overshoot_mm": 1.0, "settle_s": 0.1, "frames_per_stop": 1, "feed_mm_min": 3000.0}


def records(folder):
    path = folder / "captures.jsonl"
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()] if path.exists() else []


@pytest.fixture
def editor(qtbot):
    ed = PlanarPlanEditor(lambda: dict(SHARED), lambda: Board(cols=9, rows=6, square_mm=20.0), lambda: None)
    qtbot.addWidget(ed)
    ed.resize(640, 700)
    ed.show()
    return ed


def items(ed, kind):
    return [i for i in ed.plot.getPlotItem().items if isinstance(i, kind)]


def test_editor_builds_the_grid_and_draws_its_visiting_order(editor):
    editor.enabled.setChecked(True)
    editor.stop_x.setValue(30.0)
    editor.stop_y.setValue(10.0)
    editor.refresh()
    plan = editor.plan()
    assert plan.planar and plan.targets().tolist() == [
        [0, 0], [10, 0], [20, 0], [30, 0], [30, 10], [20, 10], [10, 10], [0, 10]]  # serpentine
    numbers = sorted(int(t.textItem.toPlainText()) for t in items(editor, pg.TextItem))
    assert numbers == list(range(1, 9))
    assert len(items(editor, pg.ArrowItem)) == 7  # one per move
    assert "8 targets per pass" in editor.order_note.text()
    editor.pattern.setCurrentIndex(editor.pattern.findData("raster"))
    assert editor.plan().targets()[4].tolist() == [0, 10]
    assert planar_duration_s(editor.plan()) > 8 * SHARED["settle_s"]


def test_iso_lines_preset_and_an_invalid_grid(editor):
    editor.enabled.setChecked(True)
    editor.iso_lines.setChecked(True)
    plan = editor.plan()
    assert plan.directions == "both" and plan.runs == 5 and len(plan.targets()) == 5 * 3 + 3 * 3
    editor.start_x.setValue(40.0)  # start == stop on X and on Y: fewer than 3 targets
    editor.start_y.setValue(20.0)
    editor.iso_lines.setChecked(False)
    editor.refresh()
    assert "fewer than 3 targets" in editor.order_note.text()


def test_rig_prediction_readout_on_the_simulated_gantry_and_without_intrinsics(editor):
    editor.enabled.setChecked(True)
    editor.refresh()
    assert "calibrate the camera" in editor.prediction.text()  # a real stage, no intrinsics yet
    editor.gantry.setCurrentIndex(editor.gantry.findData("paper-planar"))
    editor.refresh()
    text = editor.prediction.text()
    assert "board in view at every target" in text and "expected position sigma" in text
    sigma = float(re.search(r"sigma ([0-9.]+) µm median", text).group(1))
    editor.noise_px.setValue(0.2)  # the Cramér-Rao sigma scales with the corner noise
    editor.refresh()
    assert float(re.search(r"sigma ([0-9.]+) µm median", editor.prediction.text()).group(1)) == pytest.approx(2 * sigma, rel=0.01)
    editor.stop_x.setValue(900.0)  # far beyond the paper camera's view at 600 mm
    editor.refresh()
    assert "board leaves the view" in editor.prediction.text()


def test_planar_capture_on_the_simulated_gantry_then_estimate_and_resume(qtbot, make_window, tmp_path):
    window = make_window(sim_clock=SimClock())
    cap = window.capture_panel
    cap.planar_editor.clock = SimClock()
    cap.planar_editor.apply_demo_preset()
    assert cap.directions.currentData() == "both" and "15 targets, 30 frames" in cap.summary.text()
    assert not cap.start_mm.isEnabled()  # the line plan's fields are not used in planar mode
    folder = tmp_path / "xy"
    cap.folder.set_text(str(folder))
    with qtbot.waitSignal(cap.session_done, timeout=120000):
        cap.start_btn.click()
    qtbot.waitUntil(lambda: cap.start_btn.isEnabled(), timeout=5000)
    recs = records(folder)
    assert len(recs) == 30 and recs[6]["target_mm"] == [30.0, 10.0]
    meta = json.loads((folder / "session.json").read_text())
    assert meta["plan"]["axes"] == ["X", "Y"] and len(meta["truth"]["plane_mm"]) == 30

    est = window.estimation_panel
    assert est.session.text() == str(folder)
    with qtbot.waitSignal(est.results_ready, timeout=120000):
        est.run_btn.click()
    rp = window.results_panel
    qtbot.waitUntil(lambda: not rp.drawing and est.run_btn.isEnabled(), timeout=20000)
    assert rp.results.axes == ("X", "Y")
    assert "error_map" in rp.drawn
    arrows = next(item for spec, item in zip(rp.drawn["error_map"].spec.series, rp.drawn["error_map"].items)
                  if spec.label == "mean error")
    x, _ = arrows.getData()
    assert np.isfinite(x).sum() == 2 * 15 and np.isnan(x).sum() == 15  # 15 separate arrows, not one line
    names = [rp.iso_table.item(r, 0).text() for r in range(rp.iso_table.rowCount())]
    assert any(n.startswith("Squareness") for n in names) and any(n.startswith("Truth:") for n in names)

    # abort a second planar capture part-way, then resume it from the panel on the rebuilt gantry
    folder2 = tmp_path / "xy2"
    cap.folder.set_text(str(folder2))
    cap.start_btn.click()
    qtbot.waitUntil(lambda: len(records(folder2)) >= 5, timeout=60000)
    cap.abort_btn.click()
    qtbot.waitUntil(lambda: cap.start_btn.isEnabled(), timeout=20000)
    kept = len(records(folder2))
    assert 5 <= kept < 30
    cap.planar_editor.enabled.setChecked(False)  # resuming restores the session's planar plan in the editor
    with qtbot.waitSignal(cap.session_done, timeout=120000):
        cap.resume_session(folder2)
    qtbot.waitUntil(lambda: cap.start_btn.isEnabled(), timeout=5000)
    assert cap.planar_editor.active()
    recs2 = records(folder2)
    assert [r["index"] for r in recs2] == list(range(30))
    assert [r["target_mm"] for r in recs2] == [r["target_mm"] for r in recs]
    truth2 = json.loads((folder2 / "session.json").read_text())["truth"]
    assert np.allclose(truth2["plane_mm"], meta["truth"]["plane_mm"])  # same seed, same gantry: same true path


def test_planar_plan_on_the_single_axis_simulated_rig_says_what_to_choose(qtbot, make_window, tmp_path):
    from tests.gui.conftest import connect_sim

    window = make_window(sim_clock=SimClock())
    connect_sim(qtbot, window)
    cap = window.capture_panel
    cap.planar_editor.enabled.setChecked(True)  # stage: "Connected stage and camera" (the 1-D simulated rig)
    cap.folder.set_text(str(tmp_path / "nope"))
    with qtbot.waitSignal(cap.run_requested, timeout=5000) as sig:
        cap.start_btn.click()
    assert "Simulated gantry" in str(sig.args[0])
    assert not (tmp_path / "nope").exists()
