"""Capture a small plan from the GUI on the simulated rig; pause/resume/abort; resume a session."""
from __future__ import annotations

import json

import pytest

from lps_gui.core.clock import SimClock
from lps_gui.core.planning.plan import Plan
from tests.gui.conftest import connect_sim

pytestmark = pytest.mark.gui

SMALL_PLAN = Plan(start_mm=0.0, stop_mm=8.0, step_mm=2.0, directions="+", runs=1, settle_s=0.5, overshoot_mm=1.0)


def capture_window(qtbot, make_window, plan, folder):
    """A window on the simulated rig (simulated time), previewing, with ``plan`` and ``folder`` set."""
    window = make_window(sim_clock=SimClock())  # settle and moves take simulated time
    connect_sim(qtbot, window)
    cam = window.camera_panel
    qtbot.waitUntil(lambda: cam.sim_camera is not None, timeout=5000)
    assert cam.start()
    window.capture_panel.set_plan(plan)
    window.capture_panel.folder.set_text(str(folder))
    return window, window.capture_panel


def records(folder):
    path = folder / "captures.jsonl"
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()] if path.exists() else []


def test_capture_small_plan_responsive(qtbot, make_window, tmp_path, gap_meter):
    folder = tmp_path / "run1"
    window, cap = capture_window(qtbot, make_window, SMALL_PLAN, folder)
    assert "5 targets, 5 frames" in cap.summary.text()
    with gap_meter() as meter:
        with qtbot.waitSignal(cap.session_done, timeout=60000) as done:
            cap.start_btn.click()
    assert done.args[0] == folder
    assert meter.max_busy_cpu_s < 0.050, f"GUI thread busy {meter.max_busy_cpu_s * 1000:.0f} ms between two event-loop ticks during capture"
    recs = records(folder)
    assert [r["target_mm"] for r in recs] == [0.0, 2.0, 4.0, 6.0, 8.0]
    assert all((folder / r["file"]).exists() for r in recs)
    # the estimation panel now points at the new session
    assert window.estimation_panel.session.text() == str(folder)
    qtbot.waitUntil(lambda: cap.start_btn.isEnabled(), timeout=5000)


def test_abort_keeps_frames_and_resume_completes(qtbot, make_window, tmp_path):
    folder = tmp_path / "run2"
    window, cap = capture_window(qtbot, make_window, Plan(start_mm=0.0, stop_mm=40.0, step_mm=2.0, settle_s=0.5), folder)
    cap.start_btn.click()
    job = cap.job
    assert job is not None
    qtbot.waitUntil(lambda: len(records(folder)) >= 2, timeout=30000)
    cap.pause_btn.click()  # takes effect after the frame being taken
    qtbot.waitUntil(lambda: cap.engine is not None and cap.engine.state == "paused", timeout=10000)
    n_paused = len(records(folder))
    assert cap.resume_btn.isEnabled() and not cap.pause_btn.isEnabled()
    cap.resume_btn.click()
    qtbot.waitUntil(lambda: len(records(folder)) > n_paused, timeout=10000)
    with qtbot.waitSignal(job.finished, timeout=30000):
        cap.abort_btn.click()
    kept = records(folder)
    assert 2 <= len(kept) < 21
    assert window.last_error is None
    qtbot.waitUntil(lambda: cap.start_btn.isEnabled(), timeout=5000)
    # resume the interrupted session: it continues at the first missing stop and completes the plan
    with qtbot.waitSignal(cap.session_done, timeout=60000):
        cap.resume_session(folder)
    recs = records(folder)
    assert sorted(r["index"] for r in recs) == list(range(21))
    assert recs[: len(kept)] == kept  # nothing captured before was rewritten


def test_capture_then_detect_and_estimate(qtbot, make_window, tmp_path):
    """The operator's whole run on the simulated rig: capture 12 stops, estimate, plots hold 12 points."""
    folder = tmp_path / "run3"
    window, cap = capture_window(qtbot, make_window, Plan(start_mm=0.0, stop_mm=22.0, step_mm=2.0, settle_s=0.2), folder)
    with qtbot.waitSignal(cap.session_done, timeout=60000):
        cap.start_btn.click()
    qtbot.waitUntil(lambda: cap.start_btn.isEnabled(), timeout=5000)
    est = window.estimation_panel
    assert est.session.text() == str(folder)
    with qtbot.waitSignal(est.results_ready, timeout=60000):
        est.run_btn.click()
    qtbot.waitUntil(lambda: not window.results_panel.drawing and est.run_btn.isEnabled(), timeout=10000)
    assert (folder / "corners.vnl").exists() and (folder / "results.json").exists()
    rp = window.results_panel
    assert rp.drawn["positions"].point_count("measured") == 12
    assert rp.drawn["residuals"].point_count("RMS") == 12
    # against the simulator's truth (recorded per frame during the capture): the position error is
    # consistent with the uncertainty the estimate reports
    truth = rp.results.truth_comparison
    assert truth is not None and truth.position_rms_error_um is not None
    assert truth.position_rms_error_um < 3.0 * truth.mean_sigma_um
    # clicking a view shows its captured image with the residual vectors
    assert rp.show_view(5) == 5
    assert rp.detail.image.image is not None and rp.detail.image.image.shape == (480, 640)
    qtbot.waitUntil(lambda: "recomputed RMS" in rp.detail.title.text(), timeout=10000)
    x, _ = rp.detail.arrows.getData()
    assert len(x) == 2 * 54


def test_empty_folder_gets_a_dated_session_beside_the_last_one(qtbot, make_window, tmp_path):
    last = tmp_path / "old-session"
    last.mkdir()
    (last / "session.json").write_text("{}")
    window, cap = capture_window(qtbot, make_window, SMALL_PLAN, "")
    window.remember_folder(last)
    cap.folder.set_text("")
    with qtbot.waitSignal(cap.session_done, timeout=60000) as done:
        cap.start_btn.click()
    folder = done.args[0]
    assert folder.parent == tmp_path and folder.name.startswith("session-")
    assert len(records(folder)) == 5
    qtbot.waitUntil(lambda: cap.start_btn.isEnabled(), timeout=5000)
