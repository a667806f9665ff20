"""Drive the real ``lps-gui`` window on an X display, as an operator on a laptop would (issue 37).

``python -m tests.gui.real_window --out DIR`` (DISPLAY set, e.g. an Xvfb of
1000x700) opens the main window as ``lps-gui`` does, then clicks through
Refresh -> Connect -> jog -> preview -> capture -> estimate -> every results
tab with QTest on the real widgets, hides docks and resets the layout. After
each step it checks that the window lies within the screen and that every
visible table column shows its whole header text, and saves a screenshot of
every panel and results tab into DIR. It prints one JSON line: the problems
found (empty when all is well) and the screenshots written. Run by
``tests/gui/test_real_window.py`` under Xvfb at 1000x700 and 1366x768, and by
``make screenshots``.
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path
from typing import Callable

# the simulated rig runs on real time here: a fast feed and a short settle keep its 9 stops to a few seconds
# (the checks are of the layout, which neither changes)
CAPTURE_PLAN = {"start_mm": 0.0, "stop_mm": 16.0, "step_mm": 2.0, "directions": "+", "runs": 1, "settle_s": 0.05,
                "overshoot_mm": 1.0, "feed_mm_min": 3000.0}


class Driver:
    """The window, the checks made so far and the screenshots written."""

    def __init__(self, window, out: Path | None) -> None:
        self.window = window
        self.out = out
        self.problems: list[str] = []
        self.shots: list[str] = []

    # ------------------------------------------------------------------ waiting and clicking
    def wait(self, cond: Callable[[], bool], what: str, timeout_s: float = 60.0) -> bool:
        from PySide6.QtWidgets import QApplication

        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            QApplication.processEvents()
            if cond():
                return True
            time.sleep(0.005)
        if what:
            log_tail = self.window.log_panel.text().strip().splitlines()[-3:]
            self.problems.append(f"timed out waiting for {what} (log: {' | '.join(log_tail)})")
        return False

    def pause(self, seconds: float = 0.15) -> None:
        self.wait(lambda: False, "", seconds)

    def click(self, button) -> None:
        from PySide6.QtCore import Qt
        from PySide6.QtTest import QTest

        if not button.isVisible() or not button.isEnabled():
            self.problems.append(f"button {button.text()!r} is not clickable (visible {button.isVisible()}, "
                                 f"enabled {button.isEnabled()})")
            return
        self.show_widget(button)
        QTest.mouseClick(button, Qt.MouseButton.LeftButton)

    def show_widget(self, w) -> None:
        """Scroll the dock's scroll area (if any) so ``w`` is in view."""
        from PySide6.QtWidgets import QScrollArea

        p = w.parentWidget()
        while p is not None:
            if isinstance(p, QScrollArea):
                p.ensureWidgetVisible(w)
                break
            p = p.parentWidget()

    # ------------------------------------------------------------------ checks
    def check(self, step: str) -> None:
        """The window within the screen; every shown table's columns wide enough for their header text."""
        from PySide6.QtWidgets import QAbstractItemView, QHeaderView

        self.pause(0.05)
        w = self.window
        area = w.screen().availableGeometry()
        frame = w.frameGeometry()
        if frame.width() > area.width() or frame.height() > area.height():
            self.problems.append(f"{step}: window {frame.width()}x{frame.height()} exceeds the screen "
                                 f"{area.width()}x{area.height()}")
        from PySide6.QtWidgets import QScrollArea

        for name, dock in w.docks.items():  # a panel wider than its dock scrolls sideways: cut off on a laptop
            area = dock.widget()
            if isinstance(area, QScrollArea) and dock.isVisible() and area.horizontalScrollBar().isVisible():
                self.problems.append(f"{step}: the {name} dock scrolls sideways (its panel needs "
                                     f"{area.widget().minimumSizeHint().width()} px, it shows {area.viewport().width()})")
        import pyqtgraph as pg

        for plot in w.findChildren(pg.PlotWidget):
            if not plot.isVisible():
                continue
            item = plot.getPlotItem()
            need = item.geometry()  # laid out no smaller than its minimum: larger than the view is cut off
            vb = item.getViewBox().geometry()
            if (need.width() > plot.viewport().width() + 1 or need.height() > plot.viewport().height() + 1
                    or vb.height() < 40 or vb.width() < 60):
                self.problems.append(f"{step}: plot {item.titleLabel.text[:40]!r} is cut off: it needs "
                                     f"{need.width():.0f}x{need.height():.0f} px, its view is "
                                     f"{plot.viewport().width()}x{plot.viewport().height()} px, "
                                     f"data area {vb.width():.0f}x{vb.height():.0f} px")
        for view in w.findChildren(QAbstractItemView):
            header = getattr(view, "horizontalHeader", lambda: None)()
            if not isinstance(header, QHeaderView) or not view.isVisible() or view.model() is None:
                continue
            fm = header.fontMetrics()
            for c in range(header.count()):
                if header.isSectionHidden(c):
                    continue
                text = str(view.model().headerData(c, header.orientation()) or "")
                need = max((fm.horizontalAdvance(line) for line in text.split("\n")), default=0)
                if text and header.sectionSize(c) < need:
                    self.problems.append(f"{step}: column {text!r} of {view.objectName() or type(view).__name__} "
                                         f"is {header.sectionSize(c)} px, its header needs {need} px")

    def shot(self, widget, name: str) -> None:
        if self.out is None:
            return
        self.pause(0.1)
        path = self.out / f"{name}.png"
        if not widget.grab().save(str(path)):
            self.problems.append(f"screenshot {path} not written")
        self.shots.append(str(path))

    # ------------------------------------------------------------------ the operator's run
    def run(self, work: Path) -> None:
        from lps_gui.core.planning.plan import Plan

        w = self.window
        self.check("opened")
        self.shot(w, "window-opened")

        sp = w.stage_panel
        w.show_panel("stage")
        self.click(sp.refresh_btn)
        self.pause()
        if sp.current_source() != "sim":
            self.problems.append(f"after Refresh the stage source is {sp.current_source()!r}, not 'sim'")
        self.click(sp.connect_btn)
        self.wait(lambda: w.stage_ctl.connected and w.stage_ctl.last_status is not None, "the stage to connect")
        self.click(sp.jog_buttons[("X", +1)])
        self.wait(lambda: w.stage_ctl.last_status is not None and w.stage_ctl.last_status.work_mm[0] > 0.0
                  and w.stage_ctl.last_status.state == "Idle", "the jog to end")
        self.check("stage connected and jogged")
        self.shot(w.docks["stage"], "stage")

        cam = w.camera_panel
        self.wait(lambda: cam.sim_camera is not None, "the simulated camera")
        self.click(cam.open_btn)
        self.wait(lambda: cam.frames_shown >= 2, "camera frames")
        self.check("camera preview")
        self.shot(w.docks["camera"], "camera")

        w.show_panel("intrinsics")
        self.check("intrinsics panel")
        self.shot(w.docks["intrinsics"], "intrinsics")

        cap = w.capture_panel
        w.show_panel("capture")
        cap.set_plan(Plan(**CAPTURE_PLAN))
        folder = work / "session"
        cap.folder.set_text(str(folder))
        self.check("capture panel")
        self.shot(w.docks["capture"], "capture")
        cap.planar_editor.enabled.setChecked(True)
        self.check("planar plan editor")
        self.shot(w.docks["capture"], "capture-planar")
        cap.planar_editor.enabled.setChecked(False)
        setup = cap.report_setup  # the signing fields (issue 37): specification, environment, identification
        setup.toggle.setChecked(True)
        self.show_widget(setup.fields)
        self.check("report set-up unfolded")
        self.shot(w.docks["capture"], "capture-report-setup")
        setup.toggle.setChecked(False)
        self.click(cap.start_btn)
        self.wait(lambda: (folder / "results.json").exists() and cap.start_btn.isEnabled(), "the capture", 120.0)
        self.wait(lambda: w.results_panel.session_dir == folder and not w.results_panel.drawing,
                  "the live capture's results on screen", 30.0)
        self.check("capture done")
        self.shot(w.docks["capture"], "capture-done")

        est = w.estimation_panel
        w.show_panel("estimation")
        self.click(est.run_btn)
        self.wait(lambda: est.job is None and est.message.text() == "done", "the estimate", 120.0)
        self.wait(lambda: not w.results_panel.drawing, "the results to be drawn", 30.0)
        if est.progress.value() != est.progress.maximum():
            self.problems.append(f"estimate done but its progress bar shows {est.progress.value()} of "
                                 f"{est.progress.maximum()}")
        self.check("estimated")
        self.shot(w.docks["estimation"], "estimation")

        rp = w.results_panel
        w.show_panel("results")
        bar = rp.tabs.tabBar()
        from PySide6.QtCore import Qt
        from PySide6.QtTest import QTest

        for i in range(rp.tabs.count()):
            title = rp.tabs.tabText(i)
            rp.tabs.setCurrentIndex(i)  # the bar may need scrolling to show the tab: select, then click it
            self.pause(0.05)
            QTest.mouseClick(bar, Qt.MouseButton.LeftButton, pos=bar.tabRect(i).center())
            if rp.tabs.currentIndex() != i:
                self.problems.append(f"clicking results tab {title!r} did not show it")
            self.check(f"results tab {title}")
            self.shot(w, f"results-{title.lower().replace(' ', '-').replace(',', '').replace('/', '-')}")
        rp.show_view(3)
        self.wait(lambda: "recomputed RMS" in rp.detail.title.text(), "the clicked view", 30.0)
        self.check("clicked view")

        for dock in ("camera", "log", "results"):
            w.docks[dock].toggleViewAction().trigger()
            self.check(f"{dock} dock hidden")
        w.default_layout()
        self.check("reset layout")
        self.click(sp.connect_btn)  # disconnect
        self.wait(lambda: not w.stage_ctl.connected, "the stage to disconnect")
        self.check("disconnected")
        self.shot(w, "window-end")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser()
    p.add_argument("--out", type=Path, help="screenshots into this folder")
    args = p.parse_args(argv)
    from PySide6.QtCore import QSettings

    from lps_gui.gui.app import make_app
    from lps_gui.gui.main_window import MainWindow

    app = make_app()
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="lps-real-window-") as tmp:
        settings = QSettings(str(Path(tmp) / "settings.ini"), QSettings.Format.IniFormat)
        settings.setValue("folders/last", tmp)
        window = MainWindow(settings)  # the simulated rig on real time, as lps-gui runs it
        window.show()
        driver = Driver(window, args.out)
        driver.wait(lambda: window.isVisible() and window.windowHandle().isExposed(), "the window to be exposed", 10.0)
        try:
            driver.run(Path(tmp))
        finally:
            window.close()
            app.processEvents()
            print(json.dumps({"problems": driver.problems, "shots": driver.shots}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
