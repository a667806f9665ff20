"""Capture panel: plan editor with estimated duration, session folder, start/pause/resume/abort, resume a session.

The work is :class:`lps_gui.capture.engine.CaptureEngine` (what ``lps
capture`` runs) in a worker thread. Every image is on disk and listed in
captures.jsonl before the next move, so abort or a lost stage never loses
what was captured, and "Resume session…" continues at the first missing stop.
"""
from __future__ import annotations

import logging
from dataclasses import replace
import time
from pathlib import Path
from typing import Any, Callable

from PySide6.QtCore import QSettings, Signal
from PySide6.QtWidgets import (
    QComboBox, QFileDialog, QFormLayout, QGroupBox, QHBoxLayout, QLabel, QProgressBar, QPushButton,
    QSpinBox, QVBoxLayout, QWidget,
)

from lps_gui.core.board import Board
from lps_gui.capture.plans import plan_duration_s
from lps_gui.core.plan import Plan
from lps_gui.errors import InputError
from lps_gui.gui.planar_plan_editor import (
    PlanarPlanEditor, apply_shared_to_panel, planar_duration_s, planar_engine, shared_from_panel,
)
from lps_gui.gui.widgets import PathPicker, add_rows, double_spin, stack
from lps_gui.gui.workers import Job, one_line

log = logging.getLogger(__name__)

PLAN_FIELDS = ("start_mm", "stop_mm", "step_mm", "directions", "runs", "overshoot_mm", "settle_s",
               "frames_per_stop", "feed_mm_min")


def is_simulated_rig(stage: Any, camera: Any) -> bool:
    """Whether ``camera`` renders what ``stage`` (a simulated rig) really does: truth can be recorded."""
    return getattr(camera, "pose_source", None) == getattr(stage, "true_pose", object()) and hasattr(stage, "seed_capture")


def sim_spec() -> Any:
    from lps_gui.core.simulate import preset
    from lps_gui.gui.sources import SIM_PRESET

    return preset(SIM_PRESET)


def fmt_duration(seconds: float) -> str:
    s = int(round(seconds))
    return f"{s // 3600} h {s % 3600 // 60:02d} min" if s >= 3600 else (f"{s // 60} min {s % 60:02d} s" if s >= 60 else f"{s} s")


class CapturePanel(QWidget):
    """Edit a plan and run it on the connected stage and camera."""

    run_requested = Signal(object)  # Job (or the exception that prevented it) for the main window
    session_done = Signal(object)  # Path of a session folder captured completely
    failed = Signal(str, str)  # title, one-line cause (the capture stopped; frames are kept)
    board_changed = Signal(object)  # Board

    def __init__(self, stage_ctl: Any, camera_panel: Any, board: Callable[[], Board],
                 start_dir: Callable[[], str] | None = None, intrinsics: Callable[[], Any] | None = None,
                 parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.intrinsics = intrinsics or (lambda: None)  # the Intrinsics panel's calibration, embedded in new sessions
        self.stage_ctl = stage_ctl
        self.camera_panel = camera_panel
        self.board = board
        self.start_dir = start_dir or (lambda: "")
        self.engine: Any = None
        self.job: Job | None = None
        self.session_dir: Path | None = None
        self._t0 = 0.0
        self._abort_early = False

        self.start_mm = double_spin(-10000, 10000, 0.0, 3, " mm")
        self.stop_mm = double_spin(-10000, 10000, 58.0, 3, " mm")
        self.step_mm = double_spin(0.001, 10000, 2.0, 3, " mm")
        self.directions = QComboBox()
        for label, key in (("forward ↑", "+"), ("backward ↓", "-"), ("both (ISO 230-2)", "both")):
            self.directions.addItem(label, key)
        self.runs = QSpinBox()
        self.runs.setRange(1, 100)
        self.overshoot_mm = double_spin(0.0, 100.0, 1.0, 3, " mm")
        self.settle_s = double_spin(0.0, 60.0, 0.2, 2, " s")
        self.frames_per_stop = QSpinBox()
        self.frames_per_stop.setRange(1, 100)
        self.feed_mm_min = double_spin(1.0, 20000.0, 600.0, 0, " mm/min")
        plan_box = QGroupBox("Plan")
        self.summary = QLabel()
        add_rows(QFormLayout(plan_box), [
            ("Start", self.start_mm), ("Stop", self.stop_mm), ("Step", self.step_mm),
            ("Directions", self.directions), ("Runs", self.runs), ("Overshoot", self.overshoot_mm),
            ("Settle", self.settle_s), ("Frames per stop", self.frames_per_stop), ("Feed", self.feed_mm_min),
            ("", self.summary)])
        self.planar_editor = PlanarPlanEditor(lambda: shared_from_panel(self), self.board, self.intrinsics,
                                              lambda fields: apply_shared_to_panel(self, fields))
        self.planar_editor.changed.connect(self.update_summary)
        self.planar_editor.enabled.toggled.connect(
            lambda on: [w.setEnabled(not on) for w in (self.start_mm, self.stop_mm, self.step_mm)])

        self.folder = PathPicker("empty: a new dated folder beside the last one", folder=True, start_dir=self.start_dir)
        sess = QGroupBox("Session")
        sl = QVBoxLayout(sess)
        sl.addWidget(self.folder)
        self.resume_session_btn = QPushButton("Resume session…")
        self.resume_session_btn.setToolTip("Continue an interrupted session at the first stop not captured")
        sl.addWidget(self.resume_session_btn)

        self.start_btn = QPushButton("Start")
        self.pause_btn = QPushButton("Pause")
        self.resume_btn = QPushButton("Resume")
        self.abort_btn = QPushButton("Abort")
        row = QHBoxLayout()
        for b in (self.start_btn, self.pause_btn, self.resume_btn, self.abort_btn):
            row.addWidget(b)
        self.progress = QProgressBar()
        self.eta = QLabel("idle")

        stack(self, [plan_box, (self.planar_editor, 1), sess, row, self.progress, self.eta]).addStretch(1)

        for w in (self.start_mm, self.stop_mm, self.step_mm, self.overshoot_mm, self.settle_s, self.feed_mm_min):
            w.valueChanged.connect(self.update_summary)
        for w in (self.runs, self.frames_per_stop):
            w.valueChanged.connect(self.update_summary)
        self.directions.currentIndexChanged.connect(self.update_summary)
        self.start_btn.clicked.connect(self.start)
        self.pause_btn.clicked.connect(self.pause)
        self.resume_btn.clicked.connect(self.resume)
        self.abort_btn.clicked.connect(self.abort)
        self.resume_session_btn.clicked.connect(self.resume_session_dialog)
        self._set_running(False)
        self.update_summary()

    # ------------------------------------------------------------------ plan
    def plan(self) -> Plan:
        if self.planar_editor.active():
            return self.planar_editor.plan()
        return Plan(start_mm=self.start_mm.value(), stop_mm=self.stop_mm.value(), step_mm=self.step_mm.value(),
                    directions=str(self.directions.currentData()), runs=self.runs.value(),
                    overshoot_mm=self.overshoot_mm.value(), settle_s=self.settle_s.value(),
                    frames_per_stop=self.frames_per_stop.value(), feed_mm_min=self.feed_mm_min.value())

    def set_plan(self, plan: Plan) -> None:
        self.start_mm.setValue(plan.start_mm)
        self.stop_mm.setValue(plan.stop_mm)
        self.step_mm.setValue(plan.step_mm)
        self.directions.setCurrentIndex(max(0, self.directions.findData(plan.directions)))
        self.runs.setValue(plan.runs)
        self.overshoot_mm.setValue(plan.overshoot_mm)
        self.settle_s.setValue(plan.settle_s)
        self.frames_per_stop.setValue(plan.frames_per_stop)
        self.feed_mm_min.setValue(plan.feed_mm_min)

    def update_summary(self) -> None:
        try:
            plan = self.plan()
        except InputError as exc:
            self.summary.setText(f"<span style='color:#b00020'>{one_line(exc)}</span>")
            self.start_btn.setEnabled(False)
            return
        self.summary.setText(f"{len(plan.targets())} targets, {plan.n_frames()} frames, "
                             f"about {fmt_duration(planar_duration_s(plan) if self.planar_editor.active() else plan_duration_s(plan))}")
        self.start_btn.setEnabled(self.job is None)

    # ------------------------------------------------------------------ running
    def start(self) -> None:
        """Create the session in the chosen folder and capture the plan (both off the GUI thread)."""
        try:
            folder = self.folder.path()
            if folder is None:  # a fresh, dated folder beside the last one used
                base = Path(self.start_dir() or Path.home())
                if (base / "session.json").exists():
                    base = base.parent
                folder = base / time.strftime("session-%Y%m%d-%H%M%S")
                self.folder.set_text(str(folder))
            plan = self.plan()
            gantry = self.planar_editor.build_gantry(plan) if self.planar_editor.active() else None
            stage, camera = gantry[1:] if gantry else self._rig()
            if self.planar_editor.active() and not gantry:
                self.planar_editor.check_connected_rig(is_simulated_rig(stage, camera))
        except Exception as exc:
            self.run_requested.emit(exc)
            return
        if gantry:  # the simulated XY gantry built for this plan, its truth recorded
            from lps_gui.sim.planar_rig import start_gantry_session

            self.set_board(gantry[0].rig.board)
            self._run(folder, lambda: start_gantry_session(folder, gantry[0], stage, camera), stage, camera)
            return
        simulated = is_simulated_rig(stage, camera)
        if simulated:
            self.set_board(sim_spec().rig.board)
        board = self.board()
        intrinsics = self.intrinsics()

        def create() -> Any:
            from lps_gui.io.session import Session

            if simulated:
                from lps_gui.sim.session import start_rig_session

                return start_rig_session(folder, replace(sim_spec(), plan=plan), stage, camera)
            return Session.create(folder, board, plan, intrinsics=intrinsics, camera=camera.properties(),
                                  stage=stage.describe())

        self._run(folder, create, stage, camera)

    def resume_session_dialog(self) -> None:
        folder = QFileDialog.getExistingDirectory(self, "Resume an interrupted session", self.start_dir())
        if folder:
            self.resume_session(Path(folder))

    def resume_session(self, folder: Path) -> None:
        """Continue ``folder`` at the first planned stop not listed in captures.jsonl."""
        try:
            from lps_gui.io.session import Session

            session = Session.open(folder)
            remaining = session.remaining_stops()
            if not remaining:
                raise InputError(f"{folder}: every planned stop is captured already; estimate it instead")
            gantry = self.planar_editor.resume_rig(session)  # a planar session: its editor, its simulated gantry
            if not session.planar:
                self.set_plan(session.plan())
            self.folder.set_text(str(folder))
            stage, camera = gantry or self._rig()
        except Exception as exc:
            self.run_requested.emit(exc)
            return
        log.info("capture: resuming %s, %d frames to go", folder, len(remaining))
        self._run(Path(folder), lambda: session, stage, camera)

    def _rig(self) -> tuple[Any, Any]:
        from lps_gui.errors import HardwareError

        stage = self.stage_ctl.stage
        if stage is None:
            raise HardwareError("capture: no stage connected; connect one in the Stage panel")
        camera = self.camera_panel.camera or self.camera_panel.sim_camera
        if camera is None:
            raise HardwareError("capture: no camera; start the preview of a camera in the Camera panel")
        return stage, camera  # the engine opens it on its thread when needed

    def _run(self, folder: Path, make_session: Callable[[], Any], stage: Any, camera: Any) -> None:
        """Run the capture in a worker: make the session (file writes), build the engine, run it."""
        self.session_dir = Path(folder)
        self.camera_panel.pause(True)

        def work(progress: Any, cancel: Any) -> Any:
            session = make_session()
            from lps_gui.capture.engine import CaptureEngine
            from lps_gui.sim.session import simulated_engine

            engine = planar_engine(session, stage, camera)  # the simulated gantry records its truth
            if engine is None and is_simulated_rig(stage, camera) and (session.truth or {}).get("simulated"):
                engine = simulated_engine(session, stage, camera)
            elif engine is None:
                engine = CaptureEngine(stage, camera, session)
            self.engine = engine  # pause/abort from the GUI thread are thread-safe engine calls
            if self._abort_early:
                engine.abort()
            return engine.run(progress, cancel)

        self._abort_early = False
        job = Job(f"capture {self.session_dir.name}", work)
        job.progress.connect(self._on_progress)
        job.succeeded.connect(self._on_summary)
        job.cancelled.connect(lambda msg: self.eta.setText(msg))
        job.failed.connect(lambda msg, _tb: self.eta.setText(f"stopped: {msg}; captured frames are kept"))
        job.finished.connect(self._on_finished)
        self.job = job
        self._t0 = time.monotonic()
        self._set_running(True)
        self.eta.setText("starting…")
        self.run_requested.emit(job)

    def _on_summary(self, summary: Any) -> None:
        """The engine returned: complete, aborted, or stopped by an error (frames kept in every case)."""
        state = getattr(summary, "state", "done")
        if state == "done":
            self.eta.setText(f"complete: {summary.listed} frames in {self.session_dir}")
            self.session_done.emit(self.session_dir)
        elif state == "aborted":
            self.eta.setText(f"aborted: {summary.listed} of {summary.total} frames kept; resume later")
        else:
            message = summary.error or "capture stopped"
            self.eta.setText(f"stopped: {message}")
            self.failed.emit("Capture stopped", message)

    def set_board(self, board: Board) -> None:
        """Hook for the main window: the board the simulated rig really has."""
        self.board_changed.emit(board)

    def pause(self) -> None:
        if self.engine is not None:
            self.engine.pause()
            self.eta.setText("paused")
            self.pause_btn.setEnabled(False)
            self.resume_btn.setEnabled(True)

    def resume(self) -> None:
        if self.engine is not None:
            self.engine.resume()
            self.pause_btn.setEnabled(True)
            self.resume_btn.setEnabled(False)

    def abort(self) -> None:
        self._abort_early = True
        if self.engine is not None:
            self.engine.abort()
        if self.job is not None:
            self.job.cancel()

    def stage_lost(self, message: str) -> None:
        """The stage vanished: stop the capture; what is on disk stays."""
        if self.job is not None:
            self.abort()
            self.eta.setText(f"stage lost: {message}; captured frames are kept, resume later")

    def _on_progress(self, done: int, total: int, message: str) -> None:
        self.progress.setMaximum(max(total, 1))
        self.progress.setValue(done)
        elapsed = time.monotonic() - self._t0
        eta = elapsed / done * (total - done) if done else float("nan")
        self.eta.setText(f"{done}/{total} frames" + (f", {fmt_duration(eta)} left" if done else "")
                         + (f" — {message}" if message else ""))

    def _on_finished(self) -> None:
        self.job = None
        self.engine = None
        self.camera_panel.pause(False)
        self._set_running(False)

    def _set_running(self, on: bool) -> None:
        self.start_btn.setEnabled(not on)
        self.resume_session_btn.setEnabled(not on)
        self.pause_btn.setEnabled(on)
        self.resume_btn.setEnabled(False)
        self.abort_btn.setEnabled(on)

    # ------------------------------------------------------------------ settings
    def save(self, s: QSettings) -> None:
        for k, v in self.plan().to_dict().items():
            if k in PLAN_FIELDS and not isinstance(v, list):  # a planar plan's [x, y] stay out of the line plan
                s.setValue(f"plan/{k}", v)

    def restore(self, s: QSettings) -> None:
        d = {k: s.value(f"plan/{k}") for k in PLAN_FIELDS if s.value(f"plan/{k}") is not None}
        if not d:
            return
        try:
            cur = self.plan().to_dict()
            for k, v in d.items():
                cur[k] = type(cur[k])(v) if not isinstance(cur[k], str) else str(v)
            self.set_plan(Plan.from_dict(cur))
        except (InputError, ValueError, TypeError):
            log.info("capture: stored plan ignored (invalid)")

