"""Job bookkeeping for the main window: status-bar progress, Cancel, error boxes.

Panels hand their :class:`Job` here; it shows progress in the status bar,
offers Cancel, and turns a failure into a non-blocking message box with the
one-line cause while the traceback goes to the log.
"""
from __future__ import annotations

import logging
from typing import Any, Callable

from PySide6.QtCore import QObject, Qt
from PySide6.QtWidgets import QLabel, QMessageBox, QProgressBar, QPushButton, QStatusBar, QWidget

from lps_gui.gui.workers import Job

log = logging.getLogger("lps_gui.gui")


class JobRunner(QObject):
    """Runs jobs for a window and reports them in its status bar."""

    def __init__(self, window: QWidget, status_bar: QStatusBar) -> None:
        super().__init__(window)
        self.window = window
        self.jobs: list[Job] = []
        self.last_error: tuple[str, str] | None = None
        self._error_box: QMessageBox | None = None
        self.label = QLabel("idle")
        self.progress = QProgressBar()
        self.progress.setMaximumWidth(220)
        self.progress.setVisible(False)
        self.cancel_btn = QPushButton("Cancel")
        self.cancel_btn.setVisible(False)
        self.cancel_btn.clicked.connect(self.cancel_all)
        for w in (self.label, self.progress, self.cancel_btn):
            status_bar.addPermanentWidget(w)

    def run(self, job: Job, on_success: Callable[[Any], None] | None = None) -> Job:
        """Start ``job`` in its thread with status-bar progress, cancel and error reporting."""
        self.jobs.append(job)
        job.progress.connect(self._on_progress)
        job.failed.connect(lambda msg, tb, j=job: self._on_failed(j.name, msg, tb, j.expected_error))
        job.cancelled.connect(lambda msg, name=job.name: log.info("%s: %s", name, msg))
        if on_success is not None:
            job.succeeded.connect(on_success)
        job.finished.connect(lambda j=job: self._on_finished(j))
        self.label.setText(job.name)
        self.progress.setRange(0, 0)
        self.progress.setVisible(True)
        self.cancel_btn.setVisible(True)
        job.start()
        return job

    def _on_progress(self, done: int, total: int, message: str) -> None:
        self.progress.setRange(0, max(total, 1))
        self.progress.setValue(done)
        if message:
            self.label.setText(message[:60])

    def _on_failed(self, name: str, message: str, tb: str, expected: bool = True) -> None:
        """The box shows the cause; the log gets it too, with the traceback only for a bug."""
        if expected:
            log.debug("%s failed:\n%s", name, tb.rstrip())
        else:
            log.error("%s failed with a program error (please report it):\n%s", name, tb.rstrip())
        self.progress.reset()
        self.show_error(f"{name.split(' ')[0].capitalize()} failed", message)

    def _on_finished(self, job: Job) -> None:
        if job in self.jobs:
            self.jobs.remove(job)
        if not self.jobs:
            self.label.setText("cancelled" if job.token.cancelled else ("failed" if job.error else "done"))
            self.progress.setVisible(False)
            self.cancel_btn.setVisible(False)
        job.deleteLater()

    def cancel_all(self) -> None:
        for job in list(self.jobs):
            job.cancel()

    def wait_all(self, timeout_ms: int = 10000) -> None:
        for job in list(self.jobs):
            job.wait(timeout_ms)

    def show_error(self, title: str, message: str) -> None:
        """A non-blocking message box with the one-line cause; data stay as they are."""
        self.last_error = (title, message)
        log.error("%s: %s", title, message)
        if self._error_box is not None:
            self._error_box.close()
        box = QMessageBox(QMessageBox.Icon.Warning, title, message, QMessageBox.StandardButton.Ok, self.window)
        box.setWindowModality(Qt.WindowModality.WindowModal)
        box.open()
        self._error_box = box
