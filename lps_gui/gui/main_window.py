"""The main window: dockable panels, menus, status bar, jobs and remembered settings.

Panels never run long work themselves: they hand a :class:`Job` to
:meth:`MainWindow.run_job`, which shows its progress in the status bar,
offers Cancel, and turns a failure into a message box with the one-line
cause (the traceback goes to the log panel). Layout, last folders, port and
options are kept in QSettings.
"""
from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Callable

from PySide6.QtCore import QSettings, Qt, QTimer
from PySide6.QtGui import QAction, QCloseEvent, QKeySequence
from PySide6.QtWidgets import (
    QDockWidget,
    QFileDialog,
    QLabel,
    QMainWindow,
    QMessageBox,
    QWidget,
)

from lps_gui import __version__
from lps_gui.core.clock import Clock
from lps_gui.errors import LpsError
from lps_gui.gui.camera.intrinsics import IntrinsicsPanel
from lps_gui.gui.camera.panel import CameraPanel
from lps_gui.gui.capture.panel import CapturePanel
from lps_gui.gui.fit import clamp_to_screen, guard_wheel, scrolled
from lps_gui.gui.job_runner import JobRunner
from lps_gui.gui.log_panel import LogPanel
from lps_gui.gui.results.estimation import EstimationPanel
from lps_gui.gui.results.panel import ResultsPanel
from lps_gui.gui.services import preload_backends
from lps_gui.gui.stage.controller import StageController
from lps_gui.gui.stage.panel import StagePanel
from lps_gui.gui.stage.sources import RIG_SOURCES
from lps_gui.gui.workers import Job, one_line, stop_all_jobs
from lps_gui.hardware.stage import StageStatus
from lps_gui.io.results.model import Results

log = logging.getLogger("lps_gui.gui")

ORGANIZATION = "lps-calib"
APPLICATION = "lps-gui"
LAYOUT_VERSION = 1
DOCK_SHARES = (0.38, 0.38, 0.24)  # of the window's width: panels on the left, results, camera and log
DOCK_CAPS = (470, 320)  # px: on a wide screen the left panels and the camera stop there, the results get the rest
SCROLLED = ("stage", "camera", "intrinsics", "capture", "estimation")  # they grow; the window must not


class MainWindow(QMainWindow):
    """The operator's window over stage, camera, intrinsics, capture, estimation and results."""

    def __init__(self, settings: QSettings | None = None, sim_clock: Clock | None = None,
                 parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.settings = settings or QSettings(ORGANIZATION, APPLICATION)
        self.setWindowTitle(f"lps-calib {__version__} — linear positioning system calibration")
        self.setDockNestingEnabled(True)

        # --- panels
        self.log_panel = LogPanel()
        self.log_panel.attach()
        logging.getLogger("lps_gui").setLevel(logging.INFO)
        self.stage_ctl = StageController(self)
        self.stage_panel = StagePanel(self.stage_ctl, clock=sim_clock)
        self.intrinsics_panel = IntrinsicsPanel(start_dir=self.last_folder)
        self.camera_panel = CameraPanel(board=self.intrinsics_panel.board)
        self.capture_panel = CapturePanel(self.stage_ctl, self.camera_panel, board=self.intrinsics_panel.board,
                                          start_dir=self.last_folder,
                                          intrinsics=lambda: self.intrinsics_panel.intrinsics)
        self.estimation_panel = EstimationPanel(start_dir=self.last_folder)
        self.results_panel = ResultsPanel()

        self.docks: dict[str, QDockWidget] = {}
        for name, title, widget in (
            ("stage", "Stage", self.stage_panel), ("camera", "Camera", self.camera_panel),
            ("intrinsics", "Intrinsics", self.intrinsics_panel), ("capture", "Capture", self.capture_panel),
            ("estimation", "Estimation", self.estimation_panel), ("results", "Results", self.results_panel),
            ("log", "Log", self.log_panel),
        ):
            dock = QDockWidget(title, self)
            dock.setObjectName(f"dock_{name}")
            dock.setWidget(scrolled(widget) if name in SCROLLED else widget)
            self.docks[name] = dock
            dock.toggleViewAction().toggled.connect(self._dock_toggled)
        self.default_layout()

        # --- status bar
        sb = self.statusBar()
        self.status_conn = QLabel("Stage: not connected")
        self.status_state = QLabel("—")
        self.status_pos = QLabel("X — mm")
        for w in (self.status_conn, self.status_state, self.status_pos):
            sb.addWidget(w)
        self.runner = JobRunner(self, sb)

        self._build_menus()
        self._wire()
        self.restore_settings()
        guard_wheel(self)
        preload_backends()
        log.info("lps-gui %s ready", __version__)

    # ------------------------------------------------------------------ layout
    def default_layout(self) -> None:
        """View > Reset layout: the docks as at first start, the window within the screen."""
        clamp_to_screen(self)
        self.arrange_docks()

    def arrange_docks(self) -> None:
        """Left: stage / capture / estimation / intrinsics tabs; right: results beside camera and log."""
        d = self.docks
        for dock in d.values():
            dock.setFloating(False)
            dock.show()
        self.addDockWidget(Qt.DockWidgetArea.LeftDockWidgetArea, d["stage"])
        for name in ("capture", "estimation", "intrinsics"):
            self.tabifyDockWidget(d["stage"], d[name])
        self.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, d["results"])
        self.splitDockWidget(d["results"], d["camera"], Qt.Orientation.Horizontal)
        self.splitDockWidget(d["camera"], d["log"], Qt.Orientation.Vertical)
        d["stage"].raise_()
        w, h = max(self.width(), 800), max(self.height(), 500)  # shares of the window: a laptop screen too
        left, camera = (int(min(w * share, cap)) for share, cap in zip(DOCK_SHARES[::2], DOCK_CAPS))
        self.resizeDocks([d["stage"], d["results"], d["camera"]], [left, w - left - camera, camera],
                         Qt.Orientation.Horizontal)
        self.resizeDocks([d["camera"], d["log"]], [int(h * 0.7), int(h * 0.3)], Qt.Orientation.Vertical)

    def _dock_toggled(self, shown: bool) -> None:
        """A dock closed (not merely tabbed away) gives its width back: the window shrinks into the screen."""
        if not shown:
            QTimer.singleShot(0, self, lambda: clamp_to_screen(self))

    def show_panel(self, name: str) -> None:
        dock = self.docks[name]
        dock.show()
        dock.raise_()

    def _build_menus(self) -> None:
        mb = self.menuBar()
        m = mb.addMenu("&File")
        self.open_session_action = self._action(m, "Open session…", self.open_session_dialog, QKeySequence.StandardKey.Open)
        self._action(m, "Import images…", self.import_dialog)
        self._action(m, "Open light field…", self.open_lightfield_dialog)
        m.addSeparator()
        self._action(m, "Export PDF report…", lambda: self.export("pdf"))
        self._action(m, "Export CSV…", lambda: self.export("csv"))
        self._action(m, "Save screenshot…", self.screenshot_dialog)
        m.addSeparator()
        self._action(m, "Quit", self.close, QKeySequence.StandardKey.Quit)

        m = mb.addMenu("&Stage")
        self._action(m, "Connect / disconnect", self.stage_panel.toggle_connection)
        self._action(m, "Home", lambda: self.stage_ctl.call("home", "home"))
        self._action(m, "Unlock", lambda: self.stage_ctl.call("unlock", "unlock"))
        self._action(m, "Feed hold", lambda: self.stage_ctl.call("feed hold", "feed_hold"))
        self._action(m, "Resume", lambda: self.stage_ctl.call("resume", "resume"))
        self._action(m, "Stop jog", self.stage_panel.stop)

        m = mb.addMenu("&Run")
        self._action(m, "Calibrate intrinsics", self.intrinsics_panel.start)
        self._action(m, "Start capture", self.capture_panel.start)
        self._action(m, "Estimate", self.estimation_panel.start, QKeySequence("Ctrl+R"))
        self._action(m, "Cancel running work", self.cancel_jobs, QKeySequence("Ctrl+."))

        m = mb.addMenu("&View")
        for dock in self.docks.values():
            m.addAction(dock.toggleViewAction())
        m.addSeparator()
        self._action(m, "Reset layout", self.default_layout)

        m = mb.addMenu("&Help")
        self._action(m, "About lps-calib", self.about)

    def _action(self, menu: Any, text: str, slot: Callable[[], Any], shortcut: Any = None) -> QAction:
        a = QAction(text, self)
        if shortcut is not None:
            a.setShortcut(shortcut)
        a.triggered.connect(lambda _=False: slot())
        menu.addAction(a)
        return a

    def _wire(self) -> None:
        ctl = self.stage_ctl
        ctl.status_changed.connect(self._on_status)
        ctl.connection_changed.connect(self._on_connection)
        ctl.link_lost.connect(self._on_link_lost)
        ctl.command_failed.connect(self._on_command_failed)
        ctl.event_received.connect(self._on_stage_event)
        self.stage_panel.camera_offered.connect(self.camera_panel.set_sim_camera)
        self.camera_panel.failed.connect(self.show_error)
        self.camera_panel.view_grabbed.connect(lambda path: self.intrinsics_panel.add_images([path]))
        for panel in (self.estimation_panel, self.capture_panel, self.intrinsics_panel):
            panel.run_requested.connect(self._panel_job)
        self.estimation_panel.results_ready.connect(self._on_results)
        self.intrinsics_panel.saved.connect(self.estimation_panel.set_intrinsics_file)
        self.stage_panel.source_changed.connect(lambda src: self.camera_panel.expect_sim_camera(src in RIG_SOURCES))
        self.capture_panel.session_done.connect(self._on_capture_done)
        self.capture_panel.failed.connect(self.show_error)
        self.capture_panel.board_changed.connect(self.intrinsics_panel.set_board)
        self.results_panel.export_requested.connect(self.export)
        self.results_panel.failed.connect(self.show_error)

    # ------------------------------------------------------------------ stage status
    def _on_status(self, st: StageStatus) -> None:
        self.status_state.setText(f"State: {st.state}")
        x, y, z = st.work_mm
        self.status_pos.setText(f"X {x:.3f}  Y {y:.3f}  Z {z:.3f} mm")

    def _on_connection(self, connected: bool, description: str) -> None:
        if connected:
            self.status_conn.setText(f"Stage: {description}")
            self.stage_panel.remember(self.settings)
        else:
            self.status_conn.setText("Stage: not connected")
            self.status_state.setText("—")
            self.status_pos.setText("X — mm")
            self.camera_panel.set_sim_camera(None)

    def _on_link_lost(self, message: str) -> None:
        was = self.stage_ctl.connected
        self.stage_ctl.detach(message)
        self.stage_panel.connect_failed()
        self.capture_panel.stage_lost(message)
        if was:
            self.show_error("Stage connection lost", message)

    def _on_command_failed(self, what: str, message: str) -> None:
        if what == "status":
            return  # reported through link_lost
        if what == "connect":
            self.show_error("Stage not connected", message)
        else:
            self.statusBar().showMessage(f"stage {what}: {message}", 8000)

    def _on_stage_event(self, event: Any) -> None:
        text = f"stage {event.kind}" + (f" {event.code}" if event.code is not None else "") + (f": {event.text}" if event.text else "")
        level = logging.WARNING if event.kind in ("alarm", "error") else (
            logging.DEBUG if event.kind == "state" else logging.INFO)
        log.log(level, text)
        if event.kind == "alarm":
            self.statusBar().showMessage(text, 10000)

    # ------------------------------------------------------------------ jobs
    def _panel_job(self, job: Any) -> None:
        if isinstance(job, Job):
            self.run_job(job)
        elif isinstance(job, BaseException):  # the panel could not even prepare its work
            self.show_error("Cannot start", one_line(job))

    def run_job(self, job: Job, on_success: Callable[[Any], None] | None = None) -> Job:
        return self.runner.run(job, on_success)

    @property
    def jobs(self) -> list[Job]:
        return self.runner.jobs

    @property
    def last_error(self) -> tuple[str, str] | None:
        return self.runner.last_error

    def cancel_jobs(self) -> None:
        self.runner.cancel_all()

    def show_error(self, title: str, message: str) -> None:
        self.runner.show_error(title, message)

    # ------------------------------------------------------------------ results and sessions
    def _on_results(self, results: Results, session_dir: Path | None) -> None:
        out = session_dir
        self.results_panel.set_results(results, session_dir, out)
        self.show_panel("results")
        if session_dir:
            self.remember_folder(session_dir)

    def _on_capture_done(self, session_dir: Path) -> None:
        """A complete capture: the next estimate is of it; a live capture's results (and report) come on screen."""
        self.estimation_panel.set_session(session_dir)
        self.remember_folder(session_dir)
        if (Path(session_dir) / "results.json").is_file():
            self.open_session(Path(session_dir))

    def open_session_dialog(self) -> None:
        folder = QFileDialog.getExistingDirectory(self, "Open a session folder", self.last_folder())
        if folder:
            self.open_session(Path(folder))

    def open_lightfield_dialog(self) -> None:
        folder = QFileDialog.getExistingDirectory(self, "Open a light field folder", self.last_folder())
        if folder:
            self.open_lightfield(Path(folder))

    def open_lightfield(self, folder: Path) -> bool:
        """File > Open light field: the results dock's "Light field" tab shows the folder's EPIs and numbers."""
        try:
            self.results_panel.show_lightfield(folder)
        except LpsError as exc:
            self.show_error("Not a light field", str(exc))
            return False
        self.show_panel("results")
        return True

    def import_dialog(self) -> Any:
        """File > Import images: the dialog, then the import as a job; the new session is opened for estimation."""
        from lps_gui.gui.import_dialog import ImportDialog

        dialog = ImportDialog(self.last_folder, self)
        dialog.accepted.connect(lambda: self._run_import(dialog.request))
        dialog.open()
        return dialog

    def _run_import(self, request: dict[str, Any]) -> Job:
        from lps_gui.capture.import_images import import_images

        return self.run_job(Job("import images", import_images, **request), lambda folder: self.open_session(Path(folder)))

    def open_session(self, folder: Path) -> bool:
        """Select ``folder`` for estimation and show its results.json if it has one."""
        folder = Path(folder)
        if not (folder / "session.json").is_file():
            self.show_error("Not a session", f"{folder}: no session.json here; choose a folder made by a capture "
                                             "(or by `lps simulate`)")
            return False
        self.estimation_panel.set_session(folder)
        self.remember_folder(folder)
        results_path = folder / "results.json"
        if not results_path.exists():
            self.show_panel("estimation")
            return False
        try:
            from lps_gui.io.results.model import read_results

            results = read_results(results_path)
        except Exception as exc:
            self.show_error("Results not loaded", one_line(exc))
            return False
        self.estimation_panel.show_results(results)
        self.results_panel.set_results(results, folder, folder)
        self.show_panel("results")
        return True

    def export(self, kind: str) -> None:
        if self.results_panel.results is None:
            self.show_error("Nothing to export", "export: no results yet; run an estimation or open a session first")
            return
        start = str(self.results_panel.session_dir or self.last_folder())
        if kind == "pdf":
            path, _ = QFileDialog.getSaveFileName(self, "Export PDF report", str(Path(start) / "report.pdf"), "PDF (*.pdf)")
            if path:
                self.export_pdf(Path(path))
        else:
            folder = QFileDialog.getExistingDirectory(self, "Export CSV into folder", start)
            if folder:
                self.export_csv(Path(folder))

    def export_pdf(self, path: Path) -> Job | None:
        """Write the PDF report in a worker thread."""
        from lps_gui.report.pdf.document import write_report

        panel = self.results_panel
        job = Job(f"report {path.name}", write_report, panel.session_dir or path.parent, panel.results, path)
        return self.run_job(job, lambda p: (log.info("report written to %s", p), panel.set_report(Path(p))))

    def export_csv(self, folder: Path) -> list[Path]:
        try:
            files = self.results_panel.export_csv(folder)
        except Exception as exc:
            self.show_error("CSV export failed", one_line(exc))
            return []
        log.info("CSV written: %s", ", ".join(str(f) for f in files))
        return files

    def screenshot_dialog(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Save screenshot", str(Path(self.last_folder()) / "lps-gui.png"), "PNG (*.png)")
        if path:
            self.grab().save(path)

    def about(self) -> None:
        QMessageBox.about(self, "About lps-calib",
                          f"lps-calib {__version__}\nMeasures how accurately a linear positioning system moves a "
                          "camera, from the camera's own images of a fixed chessboard.")

    # ------------------------------------------------------------------ settings
    def last_folder(self) -> str:
        return str(self.settings.value("folders/last", str(Path.home())))

    def remember_folder(self, folder: Path) -> None:
        self.settings.setValue("folders/last", str(Path(folder)))

    def restore_settings(self) -> None:
        s = self.settings
        geometry = s.value("window/geometry")
        if geometry is not None:
            self.restoreGeometry(geometry)
        else:
            self.resize(1600, 1000)
        clamp_to_screen(self)  # a geometry saved on a bigger screen, or the default on a small one
        state = s.value("window/state")
        if state is not None:
            self.restoreState(state, LAYOUT_VERSION)
        else:
            self.arrange_docks()  # the first start: the docks' shares of the window as it now is
        self.stage_panel.restore(s)
        self.camera_panel.expect_sim_camera(self.stage_panel.current_source() in RIG_SOURCES)
        self.capture_panel.restore(s)
        self.estimation_panel.restore(s)

    def save_settings(self) -> None:
        s = self.settings
        s.setValue("window/geometry", self.saveGeometry())
        s.setValue("window/state", self.saveState(LAYOUT_VERSION))
        self.estimation_panel.save(s)
        self.capture_panel.save(s)
        s.sync()

    def shutdown(self) -> None:
        """Stop previews, jobs and the stage thread (used by close and by tests)."""
        self.camera_panel.stop()
        self.cancel_jobs()
        self.runner.wait_all()
        stop_all_jobs()  # panel-internal jobs too (thumbnails, corner reading): none outlives the window
        self.stage_ctl.shutdown()
        self.log_panel.detach()

    def confirm_quit(self) -> bool:
        """Quitting during a capture stops it: ask first (the frames taken stay; it can be resumed)."""
        job = self.capture_panel.job
        if job is None or not job.running:
            return True
        answer = QMessageBox.question(
            self, "Capture running", "A capture is running. Quit and stop it? The frames taken so far are kept and "
            "the session can be resumed.", QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.No,
            QMessageBox.StandardButton.No)
        return answer == QMessageBox.StandardButton.Yes

    def closeEvent(self, event: QCloseEvent) -> None:
        if not self.confirm_quit():
            event.ignore()
            return
        self.save_settings()
        self.shutdown()
        super().closeEvent(event)

