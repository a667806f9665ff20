"""Capture panel: plan editor with estimated duration, session folder, start/pause/resume/abort, resume a session.

The work is :class:`lps_gui.capture.engine.CaptureEngine` (what ``lps
capture`` runs) in a worker thread. Every image is on disk and listed in
captures.jsonl before the next move, so abort or a lost stage never loses
what was captured, and "Resume session…" continues at the first missing stop.
"""
from __future__ import annotations

import logging
import time
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable

from PySide6.QtCore import QSettings, Signal
from PySide6.QtWidgets import (
    QComboBox,
    QFileDialog,
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QProgressBar,
    QPushButton,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

from lps_gui.capture.plans import plan_duration_s
from lps_gui.core.geometry.board import Board
from lps_gui.core.planning.plan import Plan
from lps_gui.errors import InputError
from lps_gui.gui.capture.planar_plan_editor import (
    PlanarPlanEditor,
    apply_shared_to_panel,
    planar_duration_s,
    planar_engine,
    shared_from_panel,
)
from lps_gui.gui.capture.stitch_plan import StitchRow
from lps_gui.gui.capture.targets_editor import TargetsEditor
from lps_gui.gui.widgets import PathPicker, add_rows, double_spin, stack
from lps_gui.gui.workers import Job, one_line

log = logging.getLogger(__name__)

DEFAULT_FRAME_S = 0.25  # grab + encode + durable write of one frame, until a capture has measured it
START_S = 1.5  # session folder, engine and camera start, first move: once per capture
PLAN_FIELDS = ("start_mm", "stop_mm", "step_mm", "directions", "runs", "overshoot_mm", "settle_s",
               "frames_per_stop", "feed_mm_min")


def is_simulated_rig(stage: Any, camera: Any) -> bool:
    """Whether ``camera`` renders what ``stage`` (a simulated rig) really does: truth can be recorded."""
    return camera.pose_source is not None and camera.pose_source == stage.true_pose


def sim_spec() -> Any:
    from lps_gui.core.truth.simulate import preset
    from lps_gui.gui.stage.sources import SIM_PRESET

    return preset(SIM_PRESET)


def _describe(stage: Any) -> dict[str, Any]:
    try:
        return dict(stage.describe() or {})
    except Exception:  # a stage that cannot describe itself now still gets an estimate
        return {}


def asme_test_tip() -> str:
    """The test combo's tooltip, from the presets' own numbers (the same words as lps capture --help)."""
    from lps_gui.core.planning.presets import (
        MIN_STEP_COUNT,
        MIN_STEP_FRAMES,
        MIN_STEP_LOCATIONS,
        MIN_STEP_UM,
        SETTLING_FRAMES,
    )

    return (f"ASME B5.64 test: min-step takes {MIN_STEP_COUNT} steps of {MIN_STEP_UM:g} \u00b5m forward and back at "
            f"{MIN_STEP_LOCATIONS} places, {MIN_STEP_FRAMES} frames per stop averaged; settling takes "
            f"{SETTLING_FRAMES} frames back to back after each move. The plan covers start..stop; the test goes "
            "into session.json asme_test for the estimate")


def fmt_duration(seconds: float) -> str:
    s = int(round(seconds))
    return f"{s // 3600} h {s % 3600 // 60:02d} min" if s >= 3600 else (f"{s // 60} min {s % 60:02d} s" if s >= 60 else f"{s} s")


class CapturePanel(QWidget):
    """Edit a plan and run it on the connected stage and camera."""

    run_requested = Signal(object)  # Job (or the exception that prevented it) for the main window
    session_done = Signal(object)  # Path of a session folder captured completely
    failed = Signal(str, str)  # title, one-line cause (the capture stopped; frames are kept)
    board_changed = Signal(object)  # Board
    board_move = Signal(str)  # a stitched plan's pause: where to move the board (from the capture thread)

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
        for label, key in (("both (ISO 230-2)", "both"), ("forward ↑", "+"), ("backward ↓", "-")):
            self.directions.addItem(label, key)
        self.runs = QSpinBox()
        self.runs.setRange(1, 100)
        self.overshoot_mm = double_spin(0.0, 100.0, 1.0, 3, " mm")
        self.settle_s = double_spin(0.0, 60.0, 0.2, 2, " s")
        self.frames_per_stop = QSpinBox()
        self.frames_per_stop.setRange(1, 100)
        self.feed_mm_min = double_spin(1.0, 20000.0, 600.0, 0, " mm/min")
        self.stitch = StitchRow()  # one board moved between overlapping segments (SPEC 13)
        plan_box = QGroupBox("Plan")
        self.summary = QLabel()
        self.summary.setWordWrap(True)
        self.iso_btn = QPushButton("ISO 230-2 plan")
        self.iso_btn.setToolTip("5 runs in both directions over targets spaced non-uniformly between start and stop, "
                                "spread over the lead-screw pitch so the targets do not alias it")
        self.pitch_mm = double_spin(0.0, 100.0, 0.0, 3, " mm")
        self.pitch_mm.setSpecialValueText("pitch unknown")
        self.pitch_mm.setMinimumWidth(self.pitch_mm.sizeHint().width())  # squeezed, the text was cut on the left
        self.pitch_mm.setToolTip("lead-screw pitch for the ISO 230-2 plan (0: unknown)")
        iso_row = QHBoxLayout()
        iso_row.addWidget(self.iso_btn)
        iso_row.addWidget(self.pitch_mm)
        self._iso_targets: tuple[float, ...] | None = None
        self.asme_test = QComboBox()  # an ASME B5.64 test's plan preset (docs/asme-b5.64.md), as lps capture --test
        for label, key in (("none", None), ("min-step (incremental steps)", "min-step"), ("settling", "settling")):
            self.asme_test.addItem(label, key)
        self.asme_test.setToolTip(asme_test_tip())
        self.frame_s = DEFAULT_FRAME_S
        self._frames_at_start = 0
        form = QFormLayout(plan_box)
        form.addRow("Preset", iso_row)  # first: the plan a standard calibration needs
        form.addRow("ASME B5.64 test", self.asme_test)
        add_rows(form, [
            ("Start", self.start_mm), ("Stop", self.stop_mm), ("Step", self.step_mm),
            ("Directions", self.directions), ("Runs", self.runs), ("Overshoot", self.overshoot_mm),
            ("Settle", self.settle_s), ("Frames per stop", self.frames_per_stop), ("Feed", self.feed_mm_min),
            ("Move board every", self.stitch)])
        form.addRow("", self.summary)
        from lps_gui.gui.capture.report_setup import ReportSetupBox

        self.report_setup = ReportSetupBox()
        self.planar_editor = PlanarPlanEditor(lambda: shared_from_panel(self), self.board, self.intrinsics,
                                              lambda fields: apply_shared_to_panel(self, fields))
        self.planar_editor.changed.connect(self.update_summary)
        self.planar_editor.enabled.toggled.connect(
            lambda on: [w.setEnabled(not on) for w in (self.start_mm, self.stop_mm, self.step_mm, self.iso_btn,
                                                       self.asme_test)])

        self.targets_editor = TargetsEditor(self.start_dir)  # a row of targets instead of the board (SPEC 13)

        self.folder = PathPicker("empty: a new dated folder beside the last one", folder=True, start_dir=self.start_dir)
        sess = QGroupBox("Session")
        sl = QVBoxLayout(sess)
        sl.addWidget(self.folder)
        self.compensation = PathPicker("optional: compensation table (CSV, LinuxCNC)", folder=False,
                                       filter="Compensation tables (*.csv *.comp *.txt);;All files (*)", start_dir=self.start_dir)
        self.compensation.setToolTip("Command each target through this table's inverse so the true position lands on the nominal")
        sl.addWidget(self.compensation)
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
        self.eta.setWordWrap(True)  # a long error wraps; it does not widen the dock
        self.eta.setMinimumHeight(2 * self.eta.fontMetrics().lineSpacing() + 2)  # "complete: ... folder" takes two lines

        from lps_gui.gui.capture.live import LivePanel

        self.live_panel = LivePanel()  # the deviation plot growing stop by stop, the live flags, the report
        self.planar_editor.enabled.toggled.connect(self.live_panel.set_planar)
        self.live_panel.flagged.connect(lambda _flag: self.pause() if self.live_panel.pause_on_flag.isChecked() else None)
        stack(self, [plan_box, (self.planar_editor, 1), self.targets_editor, self.report_setup, sess, row, self.progress, self.eta,
                     self.live_panel]).addStretch(1)

        for w in (self.start_mm, self.stop_mm, self.step_mm):
            w.valueChanged.connect(self._targets_edited)
        self.iso_btn.clicked.connect(self.apply_iso_plan)
        self.asme_test.currentIndexChanged.connect(self.apply_asme_test)
        for w in (self.start_mm, self.stop_mm, self.step_mm, self.overshoot_mm, self.settle_s, self.feed_mm_min):
            w.valueChanged.connect(self.update_summary)
        for w in (self.runs, self.frames_per_stop):
            w.valueChanged.connect(self.update_summary)
        self.directions.currentIndexChanged.connect(self.update_summary)
        self.stitch.changed.connect(self.update_summary)
        self.board_move.connect(self._on_board_move)
        self.start_btn.clicked.connect(self.start)
        self.pause_btn.clicked.connect(self.pause)
        self.resume_btn.clicked.connect(self.resume)
        self.abort_btn.clicked.connect(self.abort)
        self.resume_session_btn.clicked.connect(self.resume_session_dialog)
        self._set_running(False)
        self.apply_iso_plan()  # the default plan: ISO 230-2's 5 bidirectional runs (a saved plan replaces it)
        self.update_summary()

    # ------------------------------------------------------------------ plan
    def plan(self) -> Plan:
        if self.planar_editor.active():
            return self.planar_editor.plan()
        return self.stitch.apply(Plan(
            start_mm=self.start_mm.value(), stop_mm=self.stop_mm.value(), step_mm=self.step_mm.value(),
            targets_mm=self._iso_targets, directions=str(self.directions.currentData()), runs=self.runs.value(),
            overshoot_mm=self.overshoot_mm.value(), settle_s=self.settle_s.value(),
            frames_per_stop=self.frames_per_stop.value(), feed_mm_min=self.feed_mm_min.value()))

    def set_plan(self, plan: Plan) -> None:
        self.start_mm.setValue(plan.start_mm)
        self.stop_mm.setValue(plan.stop_mm)
        self.step_mm.setValue(plan.step_mm)
        self._iso_targets = tuple(plan.targets_mm) if plan.targets_mm is not None else None
        self.directions.setCurrentIndex(max(0, self.directions.findData(plan.directions)))
        self.runs.setValue(plan.runs)
        self.overshoot_mm.setValue(plan.overshoot_mm)
        self.settle_s.setValue(plan.settle_s)
        self.frames_per_stop.setValue(plan.frames_per_stop)
        self.feed_mm_min.setValue(plan.feed_mm_min)
        self.stitch.show_plan(plan)
        self._set_test(None)  # a plan set from outside is no ASME test

    def update_summary(self) -> None:
        try:
            plan = self.plan()
        except InputError as exc:
            self.summary.setText(f"<span style='color:#b00020'>{one_line(exc)}</span>")
            self.start_btn.setEnabled(False)
            return
        self.summary.setText(f"{len(plan.targets())} targets, {plan.n_frames()} frames, "
                             f"about {fmt_duration(self.estimate_s(plan))}"
                             + (f" (ASME B5.64 {self.test_name()} test)" if self.test_name() else
                                " (ISO 230-2 targets, non-uniform)" if self._iso_targets else ""))
        self.start_btn.setEnabled(self.job is None)

    def estimate_s(self, plan: Plan) -> float:
        """Expected capture time: the stage's moves and settles plus the measured time per frame."""
        accel = float((getattr(self.stage_ctl, "stage", None) and _describe(self.stage_ctl.stage).get("accel_mm_s2"))
                      or 200.0)
        duration = planar_duration_s if self.planar_editor.active() else plan_duration_s
        return START_S + duration(plan, accel_mm_s2=accel, grab_s=self.frame_s)

    def apply_iso_plan(self) -> None:
        """The ISO 230-2 preset: 5 runs both ways, non-uniform targets over [start, stop] (step as spacing)."""
        from lps_gui.core.planning.presets import iso230_plan_fields

        start, stop = self.start_mm.value(), self.stop_mm.value()
        n = max(5, int(round((stop - start) / max(self.step_mm.value(), 1e-9))) + 1)
        try:
            fields = iso230_plan_fields(start, stop, n, self.pitch_mm.value() or None)
        except InputError as exc:
            self.summary.setText(f"<span style='color:#b00020'>{one_line(exc)}</span>")
            return
        self._set_test(None)
        self._apply_fields(fields)

    def _apply_fields(self, fields: dict[str, Any]) -> None:
        """A preset's plan fields (:mod:`lps_gui.core.planning.presets`) into the plan's widgets."""
        self.directions.setCurrentIndex(self.directions.findData(fields["directions"]))
        self.runs.setValue(fields["runs"])
        if "frames_per_stop" in fields:
            self.frames_per_stop.setValue(fields["frames_per_stop"])
        if "settle_s" in fields:
            self.settle_s.setValue(fields["settle_s"])
        self._iso_targets = fields["targets_mm"]
        self.update_summary()

    def test_name(self) -> str | None:
        """The ASME B5.64 test the plan is ("min-step", "settling") or None."""
        return self.asme_test.currentData()

    def _set_test(self, test: str | None) -> None:
        self.asme_test.blockSignals(True)
        self.asme_test.setCurrentIndex(max(0, self.asme_test.findData(test)))
        self.asme_test.blockSignals(False)

    def apply_asme_test(self) -> None:
        """The chosen ASME B5.64 test's plan over [start, stop] (the presets of lps capture --test)."""
        from lps_gui.capture.setup import asme_plan_fields

        test = self.test_name()
        if test is None:
            self.apply_iso_plan()  # back to the standard plan
            return
        try:
            fields = asme_plan_fields(test, self.start_mm.value(), self.stop_mm.value())
        except InputError as exc:
            self._set_test(None)
            self.summary.setText(f"<span style='color:#b00020'>{one_line(exc)}</span>")
            return
        self._apply_fields(fields)

    def asme_test_meta(self) -> dict[str, Any]:
        """session.json ``asme_test`` of the chosen test (what lps estimate computes for it); {} for none."""
        record = self.session_setup().test_record()
        return {"asme_test": record} if record else {}

    def session_setup(self) -> Any:
        """The operator's set-up (``lps_gui.capture.setup.SessionSetup``): the report box and the chosen test."""
        return self.report_setup.setup(test=self.test_name())

    def _targets_edited(self) -> None:
        if self._iso_targets is not None and not self.signalsBlocked():
            plan_targets = self._iso_targets
            if (self.start_mm.value(), self.stop_mm.value()) != (plan_targets[0], plan_targets[-1]):
                self._iso_targets = None  # the range changed by hand: uniform targets again
                self._set_test(None)  # and no longer the test's plan

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
            extra = self.session_setup().meta()  # spec, environment, test, identification: checked once
            targets = self.targets_editor.targets()
            if targets and (gantry or is_simulated_rig(stage, camera)):
                raise InputError("targets: the simulated rig renders one board; uncheck Targets, or simulate a row "
                                 "with lps simulate")
        except Exception as exc:
            self.run_requested.emit(exc)
            return
        if gantry:  # the simulated XY gantry built for this plan, its truth recorded
            from lps_gui.sim.session import start_rig_session

            self.set_board(gantry[0].rig.board)
            self._run(folder, lambda: start_rig_session(folder, gantry[0], stage, camera, extra=extra), stage, camera)
            return
        simulated = is_simulated_rig(stage, camera)
        if simulated:
            self.set_board(sim_spec().rig.board)
        board = targets or self.board()
        intrinsics = self.intrinsics()

        def create() -> Any:
            from lps_gui.io.session import Session

            if simulated:
                from lps_gui.sim.session import start_rig_session

                from lps_gui.capture.setup import apply_setup

                session = start_rig_session(folder, replace(sim_spec(), plan=plan), stage, camera)
                apply_setup(session, extra)  # specification, environment, test, identification for the report
                return session
            from lps_gui.capture.setup import device_records

            stage_record, camera_record = device_records(stage, camera)  # as lps capture records them (SPEC 16)
            return Session.create(folder, board, plan, intrinsics=intrinsics, camera=camera_record,
                                  stage=stage_record, extra=extra)

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
        table_path = self.compensation.path()  # read on the GUI thread
        live_on = self.live_panel.enabled.isChecked()
        self.live_panel.clear()

        def work(progress: Any, cancel: Any) -> Any:
            session = make_session()
            from lps_gui.capture.engine import CaptureEngine
            from lps_gui.sim.session import simulated_engine

            engine = planar_engine(session, stage, camera)  # the simulated gantry records its truth
            if engine is None and is_simulated_rig(stage, camera) and (session.truth or {}).get("simulated"):
                engine = simulated_engine(session, stage, camera)
            elif engine is None:
                engine = CaptureEngine(stage, camera, session)
            from lps_gui.capture.compensated import apply_compensation

            apply_compensation(engine, session, table_path)  # a table, or the session's own on resume
            self.engine = engine  # pause/abort from the GUI thread are thread-safe engine calls
            engine.subscribe(lambda e: self.board_move.emit(e.message) if e.kind == "move board" else None)
            if self._abort_early:
                engine.abort()
            live = self.live_panel.attach(engine, live_on)
            try:
                summary = engine.run(progress, cancel)
            except BaseException:
                self.live_panel.finish(live, None)  # its thread ends, corners.vnl stays as far as detected
                raise
            self.live_panel.finish(live, summary)
            return summary

        self._abort_early = False
        self._eta_base: tuple[int, float] | None = None  # (frames done, time) at this run's first report
        job = Job(f"capture {self.session_dir.name}", work)
        job.progress.connect(self._on_progress)
        job.succeeded.connect(self._on_summary)
        job.cancelled.connect(lambda msg: self.eta.setText(msg))
        job.failed.connect(lambda msg, _tb: self.eta.setText(f"stopped: {msg}" + self._kept()))
        job.finished.connect(self._on_finished)
        self.job = job
        self._t0 = time.monotonic()
        self._set_running(True)
        self.eta.setText("starting…")
        self.run_requested.emit(job)

    def _on_summary(self, summary: Any) -> None:
        """The engine returned: complete, aborted, or stopped by an error (frames kept in every case)."""
        state = getattr(summary, "state", "done")
        self._learn_frame_time(summary)
        if state == "done":
            self.progress.setValue(self.progress.maximum())
            self.eta.setText(f"complete: {summary.listed} frames in {self.session_dir}")
            self.session_done.emit(self.session_dir)
        elif state == "aborted":
            self.eta.setText(f"aborted: {summary.listed} of {summary.total} frames kept; resume later")
        else:
            message = summary.error or "capture stopped"
            self.eta.setText(f"stopped: {message}")
            self.failed.emit("Capture stopped", message)

    def _learn_frame_time(self, summary: Any) -> None:
        """Per-frame time of this rig from a capture that ran from start to end (for the next estimate)."""
        captured = int(getattr(summary, "captured", 0) or 0)
        if getattr(summary, "state", "") != "done" or captured < 3 or captured != int(getattr(summary, "total", -1)):
            return
        elapsed = time.monotonic() - self._t0
        plan = self.plan()
        duration = planar_duration_s if self.planar_editor.active() else plan_duration_s
        motion = duration(plan, grab_s=0.0) * captured / max(plan.n_frames(), 1)
        self.frame_s = min(10.0, max(0.01, (elapsed - START_S - motion) / captured))
        log.info("capture: %.3f s per frame measured; used for the next estimate", self.frame_s)
        self.update_summary()

    def set_folder(self, folder: Path) -> None:
        """The folder the next capture writes (empty: a new dated folder)."""
        self.folder.set_text(str(folder))

    def set_board(self, board: Board) -> None:
        """Hook for the main window: the board the simulated rig really has."""
        self.board_changed.emit(board)

    def pause(self) -> None:
        if self.engine is not None:
            self.engine.pause()
            self.eta.setText("paused")
            self.pause_btn.setEnabled(False)
            self.resume_btn.setEnabled(True)

    def _on_board_move(self, message: str) -> None:
        """A stitched plan paused for the board to be moved: say where; Resume continues."""
        self.eta.setText(f"<b>{message}</b>")
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
            self.eta.setText(f"stage lost: {message}" + (self._kept() + ", resume later" if self.progress.value() > 0 else ""))

    def _kept(self) -> str:
        """What a stopped capture leaves: said only when frames were captured."""
        return "; the captured frames are kept" if self.progress.value() > 0 else "; no frame was captured"

    def _on_progress(self, done: int, total: int, message: str) -> None:
        self.progress.setMaximum(max(total, 1))
        self.progress.setValue(done)
        eta = self.remaining_s(done, total)
        self.eta.setText(f"{done}/{total} frames" + (f", {fmt_duration(eta)} left" if eta is not None else "")
                         + (f" — {message}" if message else ""))

    def remaining_s(self, done: int, total: int) -> float | None:
        """Time left from this run's own pace: a resumed session's earlier frames took no time of this run
        (counting them halved the estimate). None until two reports of this run came."""
        now = time.monotonic()
        if getattr(self, "_eta_base", None) is None:
            self._eta_base = (done, now)
            return None
        done0, t0 = self._eta_base
        if done <= done0:
            return None
        return (now - t0) / (done - done0) * (total - done)

    def _on_finished(self) -> None:
        if self.job is not None and self.job.error is not None:
            self.progress.reset()  # a failed or aborted run leaves no half-full bar behind
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
        s.setValue("capture/frame_s", self.frame_s)
        self.report_setup.save(s)
        self.targets_editor.save(s)

    def restore(self, s: QSettings) -> None:
        self.report_setup.restore(s)
        self.targets_editor.restore(s)
        try:
            self.frame_s = float(s.value("capture/frame_s") or DEFAULT_FRAME_S)
        except (TypeError, ValueError):
            self.frame_s = DEFAULT_FRAME_S
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

