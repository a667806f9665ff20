"""The capture panel's live results: the deviation plot grows stop by stop, a fault is listed at its frame,
the capture ends in the report, and the window stays responsive throughout."""
from __future__ import annotations

import threading

import pytest

from lps_gui.core.planning.plan import Plan
from lps_gui.sim.faults import Fault, InjectedFaults
from tests.gui.test_capture_flow import capture_window

pytestmark = pytest.mark.gui

LIVE_PLAN = Plan(start_mm=0.0, stop_mm=22.0, step_mm=2.0, directions="+", runs=1, settle_s=0.5, overshoot_mm=1.0)


def test_live_plot_grows_flags_a_fault_and_ends_in_the_report(qtbot, make_window, tmp_path, gap_meter):
    folder = tmp_path / "live"
    window, cap = capture_window(qtbot, make_window, LIVE_PLAN, folder)
    window.camera_panel.sim_camera.faults = InjectedFaults([Fault("exposure", 7, 1.3)])
    live = cap.live_panel
    assert live.enabled.isChecked()
    sizes: list[int] = []
    live._bridge.event.connect(lambda e: sizes.append(live.n_views) if e.kind == "estimate" else None)
    with gap_meter() as meter:
        with qtbot.waitSignal(live.report_ready, timeout=90000) as ready:
            cap.start_btn.click()
    assert meter.max_busy_cpu_s < 0.050, f"GUI thread busy {meter.max_busy_cpu_s * 1000:.0f} ms between two event-loop ticks"
    assert ready.args[0] == folder / "report.pdf" and ready.args[0].stat().st_size > 10000
    assert (folder / "results.json").exists()
    assert sizes == sorted(sizes) and len(set(sizes)) >= 3, sizes  # it grew stop by stop
    qtbot.waitUntil(lambda: live.n_views == 12 and not live._steps, timeout=5000)  # then the final estimate's 12
    assert live.drawn is not None and live.drawn.point_count("deviation") == live.n_views and live.drawn.bands
    texts = [live.flags.item(i).text() for i in range(live.flags.count())]
    assert any(t.startswith("frame 7: exposure jumped") for t in texts), texts
    qtbot.waitUntil(lambda: cap.start_btn.isEnabled(), timeout=5000)


class FaultsThatWaitForTheFlag(InjectedFaults):
    """Injected faults, and a capture that takes frames past ``after`` only once the live check has flagged one.

    On simulated time the capture thread runs as fast as it can: on a loaded machine (the other xdist worker busy)
    it took all 12 frames in 0.9 s, before the live detection had flagged frame 5, and ended without pausing. A
    real capture waits for its stage and settling; this waits (at most 60 s, never a hang) for the flag instead.
    """

    def __init__(self, faults, after: int) -> None:
        super().__init__(faults)
        self.after = after
        self.flagged = threading.Event()

    def at(self, index: int) -> None:
        super().at(index)
        if index > self.after:
            self.flagged.wait(timeout=60.0)


def test_pause_at_a_flag_then_resume_completes(qtbot, make_window, tmp_path):
    folder = tmp_path / "paused"
    window, cap = capture_window(qtbot, make_window, LIVE_PLAN, folder)
    faults = FaultsThatWaitForTheFlag([Fault("board_leaves_view", 5, 400.0)], after=5)
    window.camera_panel.sim_camera.faults = faults
    cap.live_panel.flagged.connect(lambda _flag: faults.flagged.set())
    cap.live_panel.pause_on_flag.setChecked(True)
    cap.start_btn.click()
    qtbot.waitUntil(lambda: cap.engine is not None and cap.engine.state == "paused", timeout=60000)
    assert cap.live_panel.flags.item(0).text().startswith("frame 5: board not found")
    assert cap.resume_btn.isEnabled()
    cap.live_panel.pause_on_flag.setChecked(False)  # "fixed": go on
    with qtbot.waitSignal(cap.session_done, timeout=90000):
        cap.resume_btn.click()
    qtbot.waitUntil(lambda: cap.start_btn.isEnabled(), timeout=30000)
