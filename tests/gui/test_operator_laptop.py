"""Issue 37, GUI items: each reproduced as an operator met it, and checked fixed.

The window on a real X display at laptop sizes is driven by
``test_real_window.py``; these tests pin each item on its own widget.
"""
from __future__ import annotations

import json
import os
import threading
import time
from pathlib import Path

import pytest
from PySide6.QtCore import QEvent
from PySide6.QtWidgets import QApplication, QMessageBox

from lps_gui.core.planning.plan import Plan
from lps_gui.core.progress import CancelToken
from lps_gui.core.truth.simulate import small_spec
from lps_gui.errors import Cancelled
from lps_gui.pipeline.estimate import estimate_session
from tests.gui.conftest import connect_sim
from tests.gui.test_capture_flow import SMALL_PLAN, capture_window
from tests.pipeline.test_estimate_targets import point_session

pytestmark = pytest.mark.gui


@pytest.fixture(scope="module")
def row_results(tmp_path_factory):
    """A row session of three targets (small-row preset) and its estimate."""
    session, _ = point_session(tmp_path_factory.mktemp("gui37") / "row")
    return session.folder, estimate_session(session.folder)


@pytest.fixture(scope="module")
def board_results(tmp_path_factory):
    """A one-board session of the small rig (corners.vnl written) and its estimate."""
    from lps_gui.core.truth.simulate import preset
    from lps_gui.sim.points import simulate_point_session

    folder = tmp_path_factory.mktemp("gui37") / "board"
    simulate_point_session(preset("small"), folder)
    return folder, estimate_session(folder)


def show_results(qtbot, panel, results, folder):
    with qtbot.waitSignal(panel.drawing_done, timeout=30000):
        panel.set_results(results, folder, folder)
    qtbot.waitUntil(lambda: not panel.drawing, timeout=10000)


def narrow_panel(qtbot, width=320, height=600):
    from lps_gui.gui.results.panel import ResultsPanel

    panel = ResultsPanel()
    qtbot.addWidget(panel)
    panel.resize(width, height)
    panel.show()
    return panel


# ---------------------------------------------------------------------------- stage panel
def test_refresh_keeps_the_source_list_and_connect_still_works(qtbot, window):
    sp = window.stage_panel
    n = sp.source.count()
    sp.refresh_btn.click()  # clicked(bool) used to arrive as the list of choices: TypeError, list emptied
    assert sp.source.count() == n and sp.current_source() == "sim"
    connect_sim(qtbot, window)


def test_a_double_click_on_connect_leaves_the_stage_connected(qtbot, window):
    interval = QApplication.doubleClickInterval()
    QApplication.setDoubleClickInterval(60000)  # however slow the machine, the second click counts as one
    try:
        sp = window.stage_panel
        sp.connect_btn.click()
        qtbot.waitUntil(lambda: window.stage_ctl.connected, timeout=10000)
        sp.connect_btn.click()  # the double-click's second click reaches the button, now "Disconnect"
        qtbot.wait(100)
        assert window.stage_ctl.connected and sp.connect_btn.text() == "Disconnect"
    finally:
        QApplication.setDoubleClickInterval(interval)
    sp._connect_at = time.monotonic() - 3600  # a later, deliberate click disconnects
    sp.connect_btn.click()
    qtbot.waitUntil(lambda: not window.stage_ctl.connected, timeout=10000)


# ---------------------------------------------------------------------------- window size
def test_the_window_goes_down_to_a_1000_px_screen_with_results_and_everything_expanded(qtbot, window, row_results):
    folder, results = row_results
    window.capture_panel.report_setup.toggle.setChecked(True)
    window.capture_panel.planar_editor.enabled.setChecked(True)
    show_results(qtbot, window.results_panel, results, folder)
    qtbot.wait(50)
    assert window.minimumSizeHint().width() <= 1000 - 40, window.minimumSizeHint()  # 1179 px before
    for name, dock in window.docks.items():
        assert dock.minimumSizeHint().width() <= 320, (name, dock.minimumSizeHint())


def test_docks_keep_shares_of_a_small_window_after_reset_layout(qtbot, window):
    from lps_gui.gui.main_window import DOCK_SHARES

    window.resize(1000, 700)
    window.default_layout()
    qtbot.wait(50)
    stage, results = window.docks["stage"].width(), window.docks["results"].width()
    assert results >= 0.8 * DOCK_SHARES[1] * window.width() and stage <= 1.2 * DOCK_SHARES[0] * window.width() + 20


def test_the_planar_plan_editor_fits_the_capture_dock_of_a_1000_px_window(qtbot, window):
    from lps_gui.gui.main_window import DOCK_SHARES

    editor = window.capture_panel.planar_editor
    editor.enabled.setChecked(True)
    qtbot.wait(20)
    left_dock = DOCK_SHARES[0] * 1000 - 20  # less its scroll bar
    assert editor.minimumSizeHint().width() <= left_dock, editor.minimumSizeHint()  # X and Y side by side: cut off
    assert window.capture_panel.minimumSizeHint().width() <= left_dock, window.capture_panel.minimumSizeHint()


# ---------------------------------------------------------------------------- results
def test_the_accuracy_table_shows_every_header_in_a_narrow_panel(qtbot, row_results):
    folder, results = row_results
    panel = narrow_panel(qtbot, 360)
    show_results(qtbot, panel, results, folder)
    table = panel.iso_table
    hh = table.horizontalHeader()
    for c in range(table.columnCount()):
        text = table.horizontalHeaderItem(c).text()
        assert hh.sectionSize(c) >= hh.fontMetrics().horizontalAdvance(text), (text, hh.sectionSize(c))
    shown = sum(hh.sectionSize(c) for c in range(table.columnCount() - 1))
    assert shown <= table.viewport().width()  # the U column is in view, not scrolled off to the right
    assert table.item(0, 0).toolTip() == table.item(0, 0).text()  # an elided figure name reads whole on hover


def test_plots_fit_a_narrow_results_dock_and_the_clicked_view_opens_beside_them(qtbot, row_results):
    folder, results = row_results
    panel = narrow_panel(qtbot, 330, 700)
    assert panel.split.sizes()[1] == 0  # no empty clicked-view pane squeezing the plots
    show_results(qtbot, panel, results, folder)
    for key in ("deviation", "straightness", "angles"):
        panel.show_figure(key)
        qtbot.wait(50)
        plot = panel.plots[key]
        item = plot.getPlotItem()
        assert item.geometry().width() <= plot.viewport().width() + 1, (key, item.geometry(), plot.viewport().size())
    panel.show_view(results["positions"][2]["index"])
    assert panel.split.sizes()[1] > 0


def test_a_new_result_starts_unscrolled_and_without_the_previous_view(qtbot, row_results):
    folder, results = row_results
    panel = narrow_panel(qtbot, 330)
    show_results(qtbot, panel, results, folder)
    panel.tabs.setCurrentWidget(panel.position_table)
    qtbot.waitUntil(lambda: panel.position_table.model_.rowCount() > 0, timeout=10000)
    bar = panel.position_table.horizontalScrollBar()
    assert bar.maximum() > 0
    bar.setValue(bar.maximum())
    index = results["positions"][2]["index"]
    panel.show_view(index)
    assert panel.detail.shown_index == index
    show_results(qtbot, panel, results, folder)  # the next results
    assert bar.value() == 0
    assert panel.detail.shown_index is None and panel.detail.title.text().startswith("Click a point")


def test_the_two_rms_figures_of_a_view_say_which_is_which(qtbot, board_results):
    folder, results = board_results
    panel = narrow_panel(qtbot, 700)
    show_results(qtbot, panel, results, folder)
    panel.show_view(results["positions"][0]["index"])
    qtbot.waitUntil(lambda: "recomputed RMS" in panel.detail.title.text(), timeout=10000)
    text = panel.detail.title.text()
    assert "RMS per coordinate" in text and "as a vector" in text
    first, second = text.split("RMS per coordinate ")[1:3]
    recomputed = float(second.split(" px")[0])
    vector = float(text.split("as a vector: ")[1].split(" px")[0])
    assert vector == pytest.approx(recomputed * 2 ** 0.5, abs=0.002)


def test_the_stale_report_note_goes_after_an_export(qtbot, tmp_path):
    from tests.report.conftest import make_results

    results, truth = make_results()
    folder = tmp_path / "session"
    folder.mkdir()
    (folder / "session.json").write_text(json.dumps({"format": "lps-session/1", "truth": truth}))
    (folder / "report.pdf").write_bytes(b"%PDF-1.4")
    (folder / "results.json").write_text(json.dumps(results))
    os.utime(folder / "report.pdf", (time.time() - 100, time.time() - 100))
    panel = narrow_panel(qtbot, 700)
    show_results(qtbot, panel, results, folder)
    assert "report.pdf is older" in panel.header.text()
    (folder / "report.pdf").write_bytes(b"%PDF-1.4 exported again")  # the export writes it anew
    panel.set_report(folder / "report.pdf")
    assert "report.pdf is older" not in panel.header.text() and panel.header.text()


def test_open_report_without_a_pdf_viewer_says_so(qtbot, window, tmp_path, monkeypatch):
    from PySide6.QtGui import QDesktopServices

    monkeypatch.setattr(QDesktopServices, "openUrl", staticmethod(lambda url: False))
    pdf = tmp_path / "report.pdf"
    pdf.write_bytes(b"%PDF-1.4")
    window.results_panel.set_report(pdf)
    assert window.results_panel.open_report() is False
    assert window.last_error is not None and window.last_error[0] == "Report not opened"
    assert "PDF viewer" in window.last_error[1]


def test_opening_a_folder_that_is_no_session_says_so(qtbot, window, tmp_path):
    assert window.open_session(tmp_path) is False
    assert window.last_error == ("Not a session", f"{tmp_path}: no session.json here; choose a folder made by a "
                                                  "capture (or by `lps simulate`)")
    assert window.estimation_panel.session.text() != str(tmp_path)


def test_a_worker_that_outlives_its_panel_is_cancelled_and_silent(qtbot, row_results, monkeypatch):
    """The flaky teardown of test_targets_gui: "format positions" finished after the panel was deleted."""
    from lps_gui.gui.results.panel import ResultsPanel
    from lps_gui.gui.workers import running_jobs
    from lps_gui.report import registry

    folder, results = row_results
    release = threading.Event()
    real = registry.position_table

    def slow(r):  # the machine under load: the job ends after the panel is gone
        assert release.wait(30)
        return real(r)

    monkeypatch.setattr(registry, "position_table", slow)
    panel = ResultsPanel()
    panel.show()
    panel.set_results(results, folder, folder)
    qtbot.waitUntil(lambda: any(j.name == "format positions" for j in running_jobs()), timeout=20000)
    job = next(j for j in running_jobs() if j.name == "format positions")
    panel.close()
    panel.deleteLater()
    QApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete)
    release.set()
    assert job.wait(20000)
    qtbot.waitUntil(lambda: job not in running_jobs(), timeout=10000)
    assert job.token.cancelled
    QApplication.processEvents()  # before: RuntimeError "TextTable already deleted" from the slot


# ---------------------------------------------------------------------------- estimation
@pytest.fixture
def image_session(tmp_path):
    from lps_gui.sim.images import simulate_image_session

    folder = tmp_path / "images"
    simulate_image_session(small_spec(views=10), folder, workers=1)
    return folder


def cancelled_detection(folder: Path) -> None:
    from lps_gui.pipeline.detect import detect_session

    token = CancelToken()

    def progress(done, total, _message=""):
        if done >= 3:
            token.cancel()

    with pytest.raises(Cancelled):
        detect_session(folder, progress=progress, cancel=token, workers=1)


def test_a_cancelled_detection_is_finished_by_the_next_estimate(qtbot, image_session):
    from lps_gui.gui.results.estimation import corners_needed, detect_and_estimate

    cancelled_detection(image_session)  # corners.vnl now newer than captures.jsonl, yet partial
    assert (image_session / "corners.vnl").stat().st_mtime >= (image_session / "captures.jsonl").stat().st_mtime
    assert corners_needed(image_session)
    results = detect_and_estimate(image_session, "joint", {}, None, progress=lambda *a: None, cancel=CancelToken())
    assert results.parameters.n_used == 10


def test_the_detect_action_completes_the_corners(qtbot, window, image_session):
    from lps_gui.io.corners.vnl import read_corners_vnl
    from lps_gui.io.session import Session

    cancelled_detection(image_session)
    est = window.estimation_panel
    est.set_session(image_session)
    est.detect_btn.click()
    qtbot.waitUntil(lambda: est.job is None and est.message.text().startswith("corners:"), timeout=60000)
    assert est.message.text() == "corners: 10 of 10 views detected; estimate next"
    session = Session.open(image_session)
    assert len(read_corners_vnl(session.corners_path, session.board().n_corners).names) == 10
    assert est.progress.value() == est.progress.maximum()


def test_a_finished_estimate_shows_a_full_progress_bar(qtbot, window, image_session, monkeypatch):
    import lps_gui.gui.results.estimation as estimation_panel

    real = estimation_panel.detect_and_estimate

    def reports_early(*args, progress, cancel):
        out = real(*args, progress=lambda *a: None, cancel=cancel)
        progress(2, 100, "")  # an estimator whose last report is not its end
        return out

    monkeypatch.setattr(estimation_panel, "detect_and_estimate", reports_early)
    est = window.estimation_panel
    est.set_session(image_session)
    with qtbot.waitSignal(est.results_ready, timeout=60000):
        est.run_btn.click()
    qtbot.waitUntil(lambda: est.job is None, timeout=10000)
    assert est.progress.value() == est.progress.maximum() and est.message.text() == "done"


# ---------------------------------------------------------------------------- capture and camera
def test_a_finished_live_capture_shows_its_results(qtbot, make_window, tmp_path):
    folder = tmp_path / "live"
    window, cap = capture_window(qtbot, make_window, SMALL_PLAN, folder)
    assert cap.live_panel.enabled.isChecked()
    with qtbot.waitSignal(cap.session_done, timeout=60000):
        cap.start_btn.click()
    assert (folder / "results.json").exists()
    rp = window.results_panel
    assert rp.results is not None and rp.session_dir == folder
    assert cap.progress.value() == cap.progress.maximum()
    qtbot.waitUntil(lambda: not rp.drawing and cap.start_btn.isEnabled(), timeout=20000)


def test_quitting_during_a_capture_asks_first(qtbot, make_window, tmp_path, monkeypatch):
    window, cap = capture_window(qtbot, make_window, Plan(start_mm=0.0, stop_mm=60.0, step_mm=2.0, settle_s=0.5),
                                 tmp_path / "long")
    asked = []
    answer = [QMessageBox.StandardButton.No]
    monkeypatch.setattr(QMessageBox, "question", staticmethod(lambda *a, **k: (asked.append(a[1]), answer[0])[1]))
    cap.start_btn.click()
    qtbot.waitUntil(lambda: cap.job is not None and cap.job.running, timeout=10000)
    window.close()
    assert asked == ["Capture running"] and window.isVisible() and cap.job is not None and cap.job.running
    answer[0] = QMessageBox.StandardButton.Yes
    window.close()
    assert len(asked) == 2 and not window.isVisible()


def test_the_eta_after_a_resume_counts_only_this_runs_frames(qtbot, window, monkeypatch):
    import lps_gui.gui.capture.panel as capture_panel

    now = [1000.0]
    monkeypatch.setattr(capture_panel.time, "monotonic", lambda: now[0])
    cap = window.capture_panel
    cap._t0 = now[0]
    cap._eta_base = None
    cap._on_progress(10, 20, "")  # resumed: 10 frames were taken in an earlier run
    now[0] += 2.0
    cap._on_progress(11, 20, "")  # this run: 2 s per frame, 9 to go
    assert cap.remaining_s(11, 20) == pytest.approx(18.0)
    assert "left" in cap.eta.text()


def test_the_camera_display_is_cleared_when_the_stage_disconnects(qtbot, window):
    connect_sim(qtbot, window)
    cam = window.camera_panel
    qtbot.waitUntil(lambda: cam.sim_camera is not None, timeout=5000)
    assert cam.start()
    qtbot.waitUntil(lambda: cam.frames_shown >= 2 and cam.fps_label.text() != "— fps", timeout=20000)
    # a deliberate click, not a double-click's second (the preview can be up within the double-click interval)
    window.stage_panel._connect_at = time.monotonic() - 3600
    window.stage_panel.connect_btn.click()  # disconnect: the simulated camera goes with its stage
    qtbot.waitUntil(lambda: not window.stage_ctl.connected, timeout=10000)
    qtbot.waitUntil(lambda: cam.grabber is None, timeout=5000)
    assert cam.last_image() is None and cam.fps_label.text() == "— fps" and cam.placeholder.isVisible()
    assert cam.detect_label.text() == "no frame"


def test_the_grbl_emulator_comes_with_the_simulated_camera(qtbot, window):
    panel, cam = window.stage_panel, window.camera_panel
    panel.select_source("emulator")
    assert cam.source.findData("sim") >= 0  # offered before connecting, as with the simulated stage
    panel.connect_btn.click()
    qtbot.waitUntil(lambda: window.stage_ctl.connected and window.stage_ctl.last_status is not None, timeout=15000)
    qtbot.waitUntil(lambda: cam.sim_camera is not None, timeout=5000)
    assert cam.source.currentData() == "sim" and cam.start()
    qtbot.waitUntil(lambda: cam.frames_shown >= 2 and cam.detect_label.text().startswith("found"), timeout=30000)


def test_a_planar_plan_shows_no_one_dimensional_live_plot(qtbot, window):
    live = window.capture_panel.live_panel
    window.show_panel("capture")
    live.plot.getPlotItem().plot([0.0, 1.0], [0.0, 2.0])  # the last line capture's live deviation
    window.capture_panel.planar_editor.enabled.setChecked(True)
    assert not live.plot.isVisible() and not live.plot.getPlotItem().listDataItems()
    window.capture_panel.planar_editor.enabled.setChecked(False)
    assert live.plot.isVisible()


def test_a_status_that_arrives_after_disconnect_is_not_shown(qtbot, window):
    from concurrent.futures import Future

    connect_sim(qtbot, window)
    ctl = window.stage_ctl
    stage, late = ctl.stage, Future()
    late.set_result(ctl.last_status)
    poll = threading.Thread(target=ctl._on_polled, args=(stage, late))  # the status thread's last poll ...
    poll.start()
    poll.join()
    ctl.detach("disconnected by the operator")  # ... is delivered after the operator disconnected
    qtbot.wait(50)
    assert window.status_state.text() == "\u2014" and window.status_pos.text() == "X \u2014 mm"
    assert ctl.last_status is None
