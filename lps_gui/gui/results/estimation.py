"""Estimation panel: pick a session and intrinsics, a method and its options, run it off the GUI thread.

The work is :func:`lps_gui.pipeline.estimate.estimate_session`, the same
function ``lps estimate`` runs; it writes results.json and the CSVs into the
session (or the chosen output folder) and returns the results dict.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from PySide6.QtCore import QSettings, Signal
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QProgressBar,
    QPushButton,
    QWidget,
)

from lps_gui.core.estimator import methods
from lps_gui.gui.fit import compact_buttons
from lps_gui.gui.widgets import PathPicker, ValueTable, add_rows, double_spin, fmt, stack
from lps_gui.gui.workers import Job
from lps_gui.io.results.model import Results, as_results

METHODS = tuple((m.label, m.name) for m in methods.REGISTRY if m.in_gui)


def parameter_rows(results: Results | dict[str, Any]) -> list[tuple[str, str, str, str]]:
    """(name, value, sigma, unit) rows summarizing the results."""
    results = as_results(results)
    p = results.parameters.raw  # the line's vectors (l0, n, rvec) by name
    rows: list[tuple[str, str, str, str]] = [("method", str(results.method or ""), "", "")]
    for name, key, sig, unit in (
        ("noise sigma (a posteriori)", "sigma_px", None, "px"),
        ("RMS reprojection", "rms_px", None, "px"),
        ("views used / total", None, None, ""),
        ("observations", "n_observations", None, ""),
        ("iterations", "iterations", None, ""),
    ):
        if key is None:
            rows.append((name, f"{p.get('n_used', '—')} / {p.get('n_views', '—')}", "", unit))
        else:
            rows.append((name, fmt(p.get(key)), fmt(p.get(sig)) if sig else "", unit))
    for i, ax in enumerate("xyz"):
        l0 = p.get("l0_cam_mm") or [None] * 3
        l0s = p.get("l0_sigma_mm") or [None] * 3
        rows.append((f"l0 {ax}", fmt(l0[i], 7), fmt(l0s[i], 2), "mm"))
    for i, ax in enumerate("xyz"):
        n = p.get("n_cam") or [None] * 3
        rows.append((f"n {ax}", fmt(n[i], 7), "", ""))
    rv = p.get("rvec_rad") or [None] * 3
    rvs = p.get("rvec_sigma_rad") or [None] * 3
    for i, ax in enumerate("xyz"):
        rows.append((f"rotation {ax}", fmt(rv[i], 7), fmt(rvs[i], 2), "rad"))
    single = results.figures.single_run
    for name, key, unit in (("mean step", "mean_step_mm", "mm"), ("step std", "step_std_um", "µm"),
                            ("max |deviation|", "max_abs_deviation_um", "µm"), ("scale error", "scale_ppm", "ppm")):
        if single and key in single.raw:
            rows.append((name, fmt(getattr(single, key)), "", unit))
    truth = results.truth_comparison
    if truth and "position_rms_error_um" in truth.raw:
        rows.append(("position error vs truth (RMS)", fmt(truth.position_rms_error_um), "", "µm"))
    return rows


PARALLEL_DETECTION_MIN_VIEWS = 60  # below this, starting detection processes costs more than it saves


def corners_needed(session_dir: Path) -> bool:
    """Whether the session has images to take corners from; detection itself keeps what is current.

    A file time does not say whether corners.vnl is complete: a cancelled
    detection writes the views it finished, newer than captures.jsonl, and the
    session then looked detected for good. :func:`detect_session` judges by
    content (the hash of captures.jsonl, each image's stats or hash) and
    detects only what is missing, returning at once when nothing is.
    """
    from lps_gui.io.session import Session

    session = Session.open(session_dir)
    records = session.records()
    return bool(records) and any((session.folder / r.file).exists() for r in records)


def detect_missing(session_dir: Path, progress: Any, cancel: Any) -> Any:
    """Detect the views corners.vnl lacks (all of them the first time); what the Detect button runs."""
    from lps_gui.io.session import Session
    from lps_gui.pipeline.detect import detect_session

    n = len(Session.open(session_dir).records())
    return detect_session(session_dir, progress=progress, cancel=cancel,
                          workers=None if n >= PARALLEL_DETECTION_MIN_VIEWS else 1)


def detect_and_estimate(session_dir: Path, method: str, options: dict[str, Any], intrinsics_path: Path | None,
                        progress: Any, cancel: Any) -> Results:
    """What the Estimate button runs: detect corners where images lack them, then estimate (results read here,
    on the worker thread: the GUI thread only shows them).

    Detection is incremental (views already in corners.vnl are kept), so a
    resumed capture only detects its new frames.
    """
    if corners_needed(session_dir):
        detect_missing(session_dir, progress, cancel)
    from lps_gui.pipeline.estimate import estimate_session

    return as_results(estimate_session(session_dir, method=method, options=options, intrinsics_path=intrinsics_path,
                                       progress=progress, cancel=cancel), str(Path(session_dir) / "results.json"))


class EstimationPanel(QWidget):
    """Run the estimator on a session; results go to the Results panel."""

    run_requested = Signal(object)  # Job, started by the main window
    results_ready = Signal(object, object)  # results dict, session folder Path

    def __init__(self, start_dir=None, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.session = PathPicker("session folder (holds session.json)", folder=True, start_dir=start_dir)
        self.intrinsics = PathPicker("empty: use the session's intrinsics", folder=False,
                                     filter="Intrinsics (*.json *.yaml *.yml *.xml)", start_dir=start_dir)
        self.method = QComboBox()
        for label, key in METHODS:
            self.method.addItem(label, key)
        self.robust = QCheckBox("robust loss (Huber) on corner residuals")
        self.detect_outliers = QCheckBox("flag outlier views and re-solve without them")
        self.detect_outliers.setChecked(True)
        self.self_calibrate = QCheckBox("refine intrinsics (prior: their covariance)")
        self.self_calibrate.setToolTip("Unchecked, the session decides: a row of targets refines its intrinsics "
                                       "unless its stage's angles leave the row model (then each stop's own pose "
                                       "is used with the calibrated intrinsics).")
        self.outlier_k = double_spin(2.0, 20.0, 5.0, 1, " σ")
        self.grid_window = double_spin(0.001, 50.0, 0.5, 3, " mm")
        self.grid_resolution = double_spin(0.00001, 1.0, 0.0001, 5, " mm")
        self.threshold_px = double_spin(0.0, 100.0, 0.0, 2, " px")
        self.threshold_px.setSpecialValueText("until no improvement")

        inputs = QGroupBox("Inputs")
        add_rows(QFormLayout(inputs), [("Session", self.session), ("Intrinsics", self.intrinsics)])
        opts = QGroupBox("Method")
        add_rows(QFormLayout(opts), [
            ("Method", self.method), ("", self.robust), ("", self.detect_outliers), ("", self.self_calibrate),
            ("Outlier threshold k", self.outlier_k), ("Grid half-width (hybrid)", self.grid_window),
            ("Grid resolution (hybrid)", self.grid_resolution), ("Stop at RMS (hybrid)", self.threshold_px)])

        self.run_btn = QPushButton("Estimate")
        self.detect_btn = QPushButton("Detect")
        self.detect_btn.setToolTip("Detect the corners the session's images still lack (corners.vnl), without "
                                   "estimating; Estimate does this first by itself")
        self.cancel_btn = QPushButton("Cancel")
        self.cancel_btn.setEnabled(False)
        self.progress = QProgressBar()
        self.progress.setFormat("%p%")
        self.message = QLabel("idle")
        self.message.setWordWrap(True)  # a long error wraps; it does not widen the dock
        compact_buttons(self.run_btn, self.detect_btn, self.cancel_btn)  # with the bar: within a 1000 px screen's dock
        row = QHBoxLayout()
        row.addWidget(self.run_btn)
        row.addWidget(self.detect_btn)
        row.addWidget(self.cancel_btn)
        row.addWidget(self.progress, 1)

        self.table = ValueTable(["Parameter", "Value", "σ", "Unit"], stretch=0)
        stack(self, [inputs, opts, row, self.message, (self.table, 1)])

        self.job: Job | None = None
        self.last_results: Results | None = None
        self.method.currentIndexChanged.connect(self._method_changed)
        self.run_btn.clicked.connect(self.start)
        self.detect_btn.clicked.connect(self.start_detection)
        self.cancel_btn.clicked.connect(self.cancel)
        self._method_changed()

    def set_session(self, folder: Path | str) -> None:
        """The session the next estimation runs on."""
        self.session.set_text(str(folder))

    def set_intrinsics_file(self, path: Path | str) -> None:
        self.intrinsics.set_text(str(path))

    def save(self, s: QSettings) -> None:
        s.setValue("estimation/method", self.method.currentData())

    def restore(self, s: QSettings) -> None:
        method = s.value("estimation/method")
        i = self.method.findData(str(method)) if method else -1
        if i >= 0:
            self.method.setCurrentIndex(i)

    def _method_changed(self) -> None:
        hybrid = self.method.currentData() == "hybrid"
        for w in (self.grid_window, self.grid_resolution, self.threshold_px):
            w.setEnabled(hybrid)

    def options(self) -> dict[str, Any]:
        """The options dict of :func:`estimate_session` (hybrid keys only for the hybrid method)."""
        opts: dict[str, Any] = {"robust": self.robust.isChecked(), "outlier_k": self.outlier_k.value(),
                                "detect_outliers": self.detect_outliers.isChecked(),
                                "self_calibrate": True if self.self_calibrate.isChecked() else None}  # None: a row does
        if self.method.currentData() == "hybrid":
            opts.update(grid_window_mm=self.grid_window.value(), grid_resolution_mm=self.grid_resolution.value(),
                        threshold_px=self.threshold_px.value() or None)
        return opts

    def make_job(self) -> Job:
        """The estimation of the chosen session as a Job (not started)."""
        session = self.session.path()
        if session is None:
            from lps_gui.errors import InputError

            raise InputError("estimation: choose a session folder first")
        return Job(f"estimate {session.name}", detect_and_estimate, session, str(self.method.currentData()),
                   self.options(), self.intrinsics.path())

    def start(self) -> None:
        """Ask the main window to run the estimation (it owns job bookkeeping and error boxes)."""
        session = self.session.path()
        self._launch(self.make_job, lambda res: self._on_done(res, session))

    def start_detection(self) -> None:
        """Detect only: after a cancelled estimate, or to look at the corners before estimating."""
        def make() -> Job:
            session = self.session.path()
            if session is None:
                from lps_gui.errors import InputError

                raise InputError("detection: choose a session folder first")
            return Job(f"detect {session.name}", detect_missing, session)

        self._launch(make, self._on_detected)

    def _launch(self, make: Any, on_success: Any) -> None:
        try:
            job = make()
        except Exception as exc:
            from lps_gui.gui.workers import one_line

            self.message.setText(one_line(exc))
            self.run_requested.emit(exc)
            return
        self.job = job
        job.progress.connect(self._on_progress)
        job.succeeded.connect(on_success)
        job.failed.connect(lambda msg, _tb: self.message.setText(f"failed: {msg}"))
        job.cancelled.connect(lambda msg: self.message.setText(msg))
        job.finished.connect(self._on_finished)
        self.run_btn.setEnabled(False)
        self.detect_btn.setEnabled(False)
        self.cancel_btn.setEnabled(True)
        self.progress.setValue(0)
        self.message.setText("running…")
        self.run_requested.emit(job)

    def _on_detected(self, table: Any) -> None:
        self.progress.setValue(self.progress.maximum())
        found = sum(1 for n in table.names if n not in table.failed)
        self.message.setText(f"corners: {found} of {len(table.names)} views detected; estimate next")

    def cancel(self) -> None:
        if self.job is not None:
            self.job.cancel()

    def _on_progress(self, done: int, total: int, message: str) -> None:
        self.progress.setMaximum(max(total, 1))
        self.progress.setValue(done)
        if message:
            self.message.setText(message)

    def _on_done(self, results: Results, session: Path | None) -> None:
        self.progress.setMaximum(max(self.progress.maximum(), 1))
        self.progress.setValue(self.progress.maximum())  # done is 100 %, whatever the last report said
        self.show_results(results)
        self.message.setText("done")
        self.results_ready.emit(results, session)

    def show_results(self, results: Results | dict[str, Any]) -> None:
        results = as_results(results)
        self.last_results = results
        self.table.set_rows(parameter_rows(results))

    def _on_finished(self) -> None:
        if self.job is not None and self.job.error is not None:
            self.progress.reset()
        self.run_btn.setEnabled(True)
        self.detect_btn.setEnabled(True)
        self.cancel_btn.setEnabled(False)
        self.job = None

