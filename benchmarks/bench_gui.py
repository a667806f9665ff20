"""GUI responsiveness on the wall clock: the event loop's longest gap during a capture.

The tests assert on GUI-thread CPU time between event-loop ticks (what our
code does on the GUI thread), which a loaded machine cannot inflate. The
operator feels the wall clock; this prints it, for a capture of a small plan
on the simulated rig and for an idle event loop of the same duration in the
same process (the reference), with their ratio.

    QT_QPA_PLATFORM=offscreen .venv/bin/python benchmarks/bench_gui.py
"""
from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

from PySide6.QtCore import QEventLoop, QSettings, QTimer  # noqa: E402
from PySide6.QtWidgets import QApplication  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from lps_gui.core.clock import SimClock  # noqa: E402
from lps_gui.core.planning.plan import Plan  # noqa: E402
from tests.gui.conftest import GapMeter  # noqa: E402


def spin_until(app: QApplication, done, timeout_s: float) -> None:
    end = time.perf_counter() + timeout_s
    while not done() and time.perf_counter() < end:
        app.processEvents(QEventLoop.ProcessEventsFlag.AllEvents, 20)


def main() -> int:
    from lps_gui.gui.main_window import MainWindow

    app = QApplication.instance() or QApplication([])
    tmp = Path(tempfile.mkdtemp(prefix="lps-bench-gui-"))
    settings = QSettings(str(tmp / "bench.ini"), QSettings.Format.IniFormat)
    window = MainWindow(settings, sim_clock=SimClock())
    window.resize(1400, 900)
    window.show()
    window.stage_panel.connect_btn.click()
    spin_until(app, lambda: window.stage_ctl.connected and window.stage_ctl.last_status is not None, 10)
    cam = window.camera_panel
    spin_until(app, lambda: cam.sim_camera is not None, 5)
    cam.start()
    cap = window.capture_panel
    cap.set_plan(Plan(start_mm=0.0, stop_mm=8.0, step_mm=2.0, settle_s=0.5, overshoot_mm=1.0))
    cap.folder.set_text(str(tmp / "session"))
    finished = []
    cap.session_done.connect(lambda *a: finished.append(True))
    t0 = time.perf_counter()
    with GapMeter() as busy:
        cap.start_btn.click()
        spin_until(app, lambda: bool(finished), 120)
    duration = time.perf_counter() - t0
    cam.stop()
    with GapMeter() as idle:
        spin_until(app, lambda: False, duration)
    window.shutdown()
    print(f"capture of 5 frames: {duration:.1f} s; longest event-loop gap {busy.max_gap_s * 1000:.0f} ms "
          f"(GUI thread busy {busy.max_busy_cpu_s * 1000:.0f} ms at most between ticks)")
    print(f"idle event loop, same duration: longest gap {idle.max_gap_s * 1000:.0f} ms")
    print(f"ratio capture / idle: {busy.max_gap_s / max(idle.max_gap_s, 1e-6):.2f}  (target: gap < 50 ms on an idle machine)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
