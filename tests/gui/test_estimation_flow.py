"""Estimation from the GUI on simulated sessions: worker thread, plots, click, export, cancel, errors."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from lps_gui.core.truth.simulate import preset
from lps_gui.sim.points import simulate_point_session

pytestmark = pytest.mark.gui

REPLACED_VIEW = 7  # the simulator swaps this view's corners for another position's: an outlier


@pytest.fixture(scope="module")
def session_dir(tmp_path_factory) -> Path:
    """A 2-run, both-direction session of the small rig (4 x 30 views) with one replaced view."""
    folder = tmp_path_factory.mktemp("gui-est") / "session"
    spec = preset("small", replaced_views=(REPLACED_VIEW,))
    spec = replace(spec, plan=replace(spec.plan, directions="both", runs=2))
    simulate_point_session(spec, folder)
    return folder


def run_estimation(qtbot, window, folder: Path, gap_meter=None):
    panel = window.estimation_panel
    panel.session.set_text(str(folder))
    assert panel.run_btn.isEnabled()
    if gap_meter is None:
        with qtbot.waitSignal(panel.results_ready, timeout=60000):
            panel.run_btn.click()
        qtbot.waitUntil(lambda: panel.run_btn.isEnabled() and not window.results_panel.drawing, timeout=10000)
        return None
    with gap_meter() as meter:
        with qtbot.waitSignal(panel.results_ready, timeout=60000):
            panel.run_btn.click()
    qtbot.waitUntil(lambda: panel.run_btn.isEnabled(), timeout=10000)
    qtbot.waitUntil(lambda: not window.results_panel.drawing, timeout=10000)
    return meter


def test_estimate_plots_click_and_export(qtbot, window, session_dir, tmp_path, gap_meter):
    meter = run_estimation(qtbot, window, session_dir, gap_meter)
    # the UI stayed responsive while the estimator ran in its thread
    assert meter.ticks > 3
    assert meter.max_busy_cpu_s < 0.050, f"GUI thread busy {meter.max_busy_cpu_s * 1000:.0f} ms between two event-loop ticks during estimation"

    rp = window.results_panel
    K = 4 * 30
    assert len(rp.results.positions) == K
    drawn = rp.drawn
    assert drawn["positions"].point_count("measured") == K
    assert drawn["residuals"].point_count("RMS") == K
    assert drawn["deviation"].point_count("runs") == K  # two runs per direction: every capture drawn
    # the replaced view is flagged and marked with a red cross at its capture index
    crosses = drawn["residuals"].outliers
    assert len(crosses) == 1
    x, _ = crosses[0].getData()
    assert REPLACED_VIEW in set(int(v) for v in x)
    # accuracy, three pairs of figures, residuals, error motions (SPEC 14), positions table
    assert [rp.tabs.tabText(i) for i in range(rp.tabs.count())][-2:] == ["Error motions", "Table"]
    assert rp.tabs.count() == 7 and rp.tabs.usesScrollButtons() and rp.target_table.rowCount() > 0
    assert rp.position_table.rowCount() == K
    assert window.estimation_panel.table.rowCount() > 5

    # clicking near the outlier in the residual plot shows that view with its residual vectors
    rms = [r.number("rms_px") for r in rp.results.positions if r.index == REPLACED_VIEW][0]
    assert rp.show_view_at("residuals", REPLACED_VIEW, rms) == REPLACED_VIEW
    assert "OUTLIER" in rp.detail.title.text()
    # the corners are read on a worker thread; the residual vectors appear when they arrive
    qtbot.waitUntil(lambda: rp.detail.arrows.getData()[0] is not None and len(rp.detail.arrows.getData()[0]) > 0,
                    timeout=10000)
    ax, _ = rp.detail.arrows.getData()
    assert len(ax) == 2 * 54  # one vector per corner of the 9x6 board

    # export: CSV copies, PDF in a worker
    out = tmp_path / "export"
    files = window.export_csv(out)
    assert [f.name for f in files] == ["positions.csv", "summary.csv"]
    assert len((out / "positions.csv").read_text().strip().splitlines()) == K + 1
    job = window.export_pdf(out / "report.pdf")
    with qtbot.waitSignal(job.finished, timeout=60000):
        pass
    assert (out / "report.pdf").read_bytes()[:5] == b"%PDF-"


def test_clicking_a_plotted_point_opens_its_view(qtbot, window, session_dir):
    from PySide6.QtCore import QPointF, Qt

    if not (session_dir / "results.json").exists():
        run_estimation(qtbot, window, session_dir)
    assert window.open_session(session_dir)
    qtbot.waitUntil(lambda: not window.results_panel.drawing, timeout=10000)
    rp = window.results_panel
    plot = rp.plots["residuals"]
    rp.show_figure("residuals")
    qtbot.waitUntil(lambda: plot.isVisible(), timeout=5000)
    row = [r for r in rp.results.positions if r.index == 40][0]
    scene_pt = plot.getPlotItem().vb.mapViewToScene(QPointF(40.0, row.number("rms_px")))
    qtbot.mouseClick(plot.viewport(), Qt.MouseButton.LeftButton, pos=plot.mapFromScene(scene_pt))
    qtbot.waitUntil(lambda: rp.detail.shown_index == 40, timeout=5000)
    assert rp.detail.title.text().startswith("view 40")


def test_cancel_leaves_no_results(qtbot, window, session_dir, tmp_path):
    import shutil

    folder = tmp_path / "copy"
    shutil.copytree(session_dir, folder, ignore=shutil.ignore_patterns("results.json", "*.csv", "report.pdf"))
    panel = window.estimation_panel
    panel.session.set_text(str(folder))
    panel.run_btn.click()
    job = panel.job
    assert job is not None and panel.cancel_btn.isEnabled()
    with qtbot.waitSignal(job.finished, timeout=60000):
        panel.cancel_btn.click()
    assert job.token.cancelled and job.result is None
    assert "cancelled" in panel.message.text()
    assert not (folder / "results.json").exists()
    assert window.results_panel.results is None
    assert window.last_error is None  # a cancel is not an error
    assert panel.run_btn.isEnabled()


def test_broken_session_shows_the_cause_and_keeps_data(qtbot, window, session_dir, tmp_path):
    run_estimation(qtbot, window, session_dir)
    before = window.results_panel.results
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "session.json").write_text('{"format": "lps-session/1", "board": ')  # torn by a crash
    (broken / "captures.jsonl").write_text("")
    panel = window.estimation_panel
    panel.session.set_text(str(broken))
    panel.run_btn.click()
    qtbot.waitUntil(lambda: window.last_error is not None, timeout=30000)
    title, message = window.last_error
    assert title == "Estimate failed"
    assert "session.json" in message and "\n" not in message
    assert window.results_panel.results is before  # the previous results stay on screen
    assert (broken / "session.json").read_text() == '{"format": "lps-session/1", "board": '
    log_text = window.log_panel.text()  # the cause went to the log, without a traceback (a user error, no bug)
    assert "not valid JSON" in log_text and "Traceback" not in log_text
    qtbot.waitUntil(lambda: panel.run_btn.isEnabled(), timeout=5000)


def test_hybrid_method_with_its_options(qtbot, window, session_dir, tmp_path):
    import shutil

    folder = tmp_path / "hyb"
    shutil.copytree(session_dir, folder, ignore=shutil.ignore_patterns("results.json", "*.csv", "report.pdf"))
    panel = window.estimation_panel
    panel.method.setCurrentIndex(panel.method.findData("hybrid"))
    assert panel.grid_window.isEnabled()
    opts = panel.options()
    assert opts["grid_window_mm"] == 0.5 and opts["threshold_px"] is None
    run_estimation(qtbot, window, folder)
    res = window.results_panel.results
    assert res.method == "hybrid" and len(res.positions) == 120
    assert window.last_error is None


def test_open_session_with_results_and_screenshot(qtbot, window, session_dir, tmp_path):
    from lps_gui.gui.app import main

    if not (session_dir / "results.json").exists():
        run_estimation(qtbot, window, session_dir)
    assert window.open_session(session_dir)
    qtbot.waitUntil(lambda: not window.results_panel.drawing, timeout=10000)
    assert window.results_panel.drawn["positions"].point_count("measured") == 120
    png = tmp_path / "shot.png"
    assert main(["--screenshot", str(png), "--session", str(session_dir), "--size", "1200x800",
                 "--settings", str(tmp_path / "s.ini")]) == 0
    from PySide6.QtGui import QImage

    img = QImage(str(png))
    assert (img.width(), img.height()) == (1200, 800)
