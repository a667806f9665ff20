"""Targets in the GUI (SPEC 13): the capture panel defines them into session.json, the results panel shows them."""
from __future__ import annotations

import json

import pytest

from lps_gui.cli import main as lps_main
from lps_gui.core.geometry.board import Board
from lps_gui.errors import InputError
from lps_gui.gui.capture.targets_editor import TargetsEditor, add_targets
from lps_gui.pipeline.estimate import estimate_session
from tests.gui.test_capture_flow import SMALL_PLAN, capture_window, records
from tests.pipeline.test_estimate_targets import point_session

pytestmark = pytest.mark.gui

ROW_BOARD = Board(10, 7, 30.0, type="charuco", marker_mm=22.0, dictionary="DICT_5X5_1000")


def test_first_markers_are_assigned_so_the_ranges_stay_disjoint():
    six = add_targets([], 6, ROW_BOARD)
    assert [t.first_marker for t in six] == [0, 44, 88, 132, 176, 220]
    kept = [t for t in six if t.id != "T2"]
    again = add_targets(kept, 1, ROW_BOARD)  # T2's id is free again, its old range is not reused past others
    assert again[-1].id == "T2" and again[-1].first_marker == 264
    other = add_targets(again, 1, Board(5, 4, 20.0, type="charuco", marker_mm=15.0, dictionary="DICT_4X4_1000"))
    assert other[-1].first_marker == 0  # its own dictionary starts at 0


def test_the_editor_loads_make_targets_output_and_an_empty_list_is_an_error(qtbot, tmp_path, capsys):
    assert lps_main(["make-targets", str(tmp_path / "row"), "--count", "3", "--inner-corners", "10x7",
                     "--square-mm", "30", "--marker-mm", "22"]) == 0
    editor = TargetsEditor()
    qtbot.addWidget(editor)
    assert editor.targets() is None  # unchecked: the one board
    editor.setChecked(True)
    with pytest.raises(InputError, match="list is empty"):
        editor.targets()
    editor.load(tmp_path / "row" / "targets.json")
    targets = editor.targets()
    assert [t.id for t in targets] == ["T0", "T1", "T2"] and editor.table.rowCount() == 3
    assert editor.table.item(2, 3).text() == "88\u2013131" and editor.table.item(2, 1).text() == "10x7, 30 mm, marker 22"


def test_targets_defined_in_the_capture_panel_go_into_session_json(qtbot, make_window, tmp_path, monkeypatch):
    folder = tmp_path / "row"
    window, cap = capture_window(qtbot, make_window, SMALL_PLAN, folder)
    cap.targets_editor.setChecked(True)
    cap.targets_editor.set_targets(add_targets([], 3, ROW_BOARD))
    errors = []
    cap.run_requested.connect(lambda job: errors.append(job) if isinstance(job, Exception) else None)
    cap.start_btn.click()  # the simulated rig renders one board: a one-line refusal, nothing written
    assert errors and "simulated rig renders one board" in str(errors[0]) and not (folder / "session.json").exists()
    monkeypatch.setattr("lps_gui.gui.capture.panel.is_simulated_rig", lambda stage, camera: False)
    with qtbot.waitSignal(cap.session_done, timeout=60000):
        cap.start_btn.click()  # as a real rig: the session names the targets, not a board
    meta = json.loads((folder / "session.json").read_text())
    assert "board" not in meta and [t["first_marker"] for t in meta["targets"]] == [0, 44, 88]
    assert len(records(folder)) == 5


def test_the_results_panel_shows_the_targets_and_their_stretches(qtbot, tmp_path):
    from lps_gui.gui.results.panel import ResultsPanel

    session, _ = point_session(tmp_path / "row")  # the small-row preset: 3 targets
    results = estimate_session(session.folder)
    panel = ResultsPanel()
    qtbot.addWidget(panel)
    panel.resize(1200, 800)
    panel.show()
    with qtbot.waitSignal(panel.drawing_done, timeout=20000):
        panel.set_results(results, session.folder)
    assert panel.mounted_targets.isVisible() and panel.mounted_targets.table.rowCount() == 3
    assert panel.mounted_targets.table.model_.rows[1][2] == str(results["targets"][1]["views"])
    labels = [item.opts.get("name") for item in panel.plots["deviation"].getPlotItem().listDataItems()]
    assert [n for n in labels if n and n.startswith("seen by")] == ["seen by T0", "seen by T1", "seen by T2"]


def test_a_stitched_plan_pauses_to_move_the_board_and_resume_continues(qtbot, make_window, tmp_path):
    from lps_gui.core.planning.plan import Plan

    folder = tmp_path / "stitched"
    plan = Plan(start_mm=0.0, stop_mm=16.0, step_mm=2.0, directions="+", runs=1, settle_s=0.0, overshoot_mm=1.0)
    window, cap = capture_window(qtbot, make_window, plan, folder)
    cap.stitch.segment_stops.setValue(5)
    cap.stitch.overlap_stops.setValue(2)
    assert cap.plan().segments == ((0.0, 8.0), (6.0, 14.0), (12.0, 16.0)) and "13 frames" in cap.summary.text()
    moves = []
    cap.board_move.connect(lambda message: (moves.append(message), cap.resume_btn.click()))
    with qtbot.waitSignal(cap.session_done, timeout=60000):
        cap.start_btn.click()
    assert len(moves) == 2 and moves[0].startswith("segment 2 of 3: move the board 6 mm")
    assert [r["segment"] for r in records(folder)] == [0] * 5 + [1] * 5 + [2] * 3
