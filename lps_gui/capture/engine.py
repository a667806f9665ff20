"""The capture engine: run a session's plan against a Stage and a Camera, losing nothing.

For every planned frame not yet listed in captures.jsonl (in
:meth:`Plan.stops` order) the engine moves, waits until the stage is idle,
settles, grabs, writes the image atomically and only then appends its line
(SPEC 7), so a crash, a kill or a vanished port never leaves a listed frame
missing on disk, and a later :meth:`CaptureEngine.run` continues at the
first frame not listed.

ISO 230-2: each target is approached from its run's own direction. Within a
run the targets come in that direction anyway; at the start of a run, and
whenever the engine does not know where the stage came from (first stop of a
call, after a pause or an error), it first goes to the overshoot position
beyond the target so the last move is in the run's direction.

A simulated rig comes with one explicit hook, ``simulator`` (a
:class:`SimulatorHook`): the engine tells it when to record the truth of a
frame and when to seed its draws (before the move onto a stop, before each
grab), so a simulated session resumed after a kill draws the same
repeatability and image noise as an uninterrupted one. Everything else the
engine needs from a device is declared on :class:`Stage` and :class:`Camera`.
"""
from __future__ import annotations

import threading
import time
from typing import Any, Callable, Protocol

import numpy as np

from lps_gui.camera.base import Camera
from lps_gui.capture import events as ev
from lps_gui.capture.camera_lock import (
    check_frame,
    check_frame_size,
    expected_frame_size,
    lock_camera,
    record_bayer_gains,
)
from lps_gui.capture.events import CaptureEvent, CaptureListener, CaptureProgress, CaptureSummary
from lps_gui.capture.moves import approach_point_mm, check_plan_in_travel, format_target, go_to_planar
from lps_gui.capture.settle import SettleOptions, Settler
from lps_gui.core.clock import Clock, RealClock
from lps_gui.core.planning.plan import PlannedStop
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.errors import HardwareError, InputError
from lps_gui.hardware.stage import EventSource, Stage
from lps_gui.io.atomic import check_writable
from lps_gui.io.session import IMAGES_DIR, CaptureRecord, Session
from lps_gui.io.session_lock import SessionLock


class SimulatorHook(Protocol):
    """What a simulated rig does beside the frames (``lps_gui.sim.session.SimulatedRigHook``)."""

    def prune(self, session: Session) -> None: ...  # before a (re)start: keep the truth of listed frames only
    def record(self, session: Session, index: int) -> None: ...  # durably, before the frame's capture line
    def finalize(self, session: Session) -> None: ...  # the plan is complete
    def seed_stop(self, stop: PlannedStop) -> None: ...  # before the move onto ``stop``: the stage's draws
    def seed_frame(self, index: int) -> None: ...  # before the grab of frame ``index``: the camera's noise


class _Stop(Exception):
    """Internal: abort or cancel requested."""


def encode_image(image: np.ndarray, ext: str) -> bytes:
    """Encode an 8-bit frame losslessly as ``ext`` (".png", ".tif", ".bmp"...)."""
    import cv2

    params = [cv2.IMWRITE_PNG_COMPRESSION, 1] if ext.lower() == ".png" else []
    ok, buf = cv2.imencode(ext, image, params)
    if not ok:
        raise InputError(f"capture: cannot encode images as {ext!r}; use .png")
    return buf.tobytes()


def image_name(index: int, ext: str) -> str:
    """File name of capture ``index`` inside images/ (sorts in capture order)."""
    return f"{index:06d}{ext}"


LOSSLESS = (".png", ".tif", ".tiff", ".bmp", ".pgm", ".ppm")
POSITION_TOLERANCE_MM = 0.01  # a controller reports its step count: any real miss is a lost move, not noise


def check_reached(target_mm: float, reported_mm: float, tolerance_mm: float = POSITION_TOLERANCE_MM) -> None:
    """HardwareError when the stage reports a position off the target by more than ``tolerance_mm``."""
    if not abs(reported_mm - target_mm) <= tolerance_mm:  # also catches NaN
        raise HardwareError(
            f"stage: reports {reported_mm:.4f} mm after the move to {target_mm:.4f} mm ({1e3 * (reported_mm - target_mm):+.1f} um, "
            f"tolerance {1e3 * tolerance_mm:.0f} um); check for a limit, a stall or lost steps, then resume"
        )


def bytes_per_frame(camera: Camera) -> int:
    """Upper bound of one stored frame: the raw size (PNG only shrinks it); 8 MB when unknown."""
    props = camera.properties()
    w, h = props.get("width"), props.get("height")
    if w and h:
        return int(w) * int(h) * int(props.get("channels", 1)) + 4096
    return 8 << 20


class CaptureEngine:
    """Runs the plan of ``session`` against ``stage`` and ``camera``.

    Parameters
    ----------
    stage : a connected :class:`Stage`.
    camera : a :class:`Camera` (opened by :meth:`run` when needed).
    session : the session folder; its plan says what to capture.
    clock : settle time and ETA; the stage's clock when it has one, else real time.
    encode : image file extension, lossless (".png" default).
    simulator : for a simulated rig, records the true pose at each grab and
        seeds its draws (see :mod:`lps_gui.sim.session`); the engine only says when.
    move_timeout_s : minimum time a move may take before it is an error.
    command_of : ``(nominal_mm, direction) -> commanded_mm``, a compensation
        table's inverse (``CompensationTable.command_mm``): the stage is sent
        there so the true position lands on the nominal; captures.jsonl then
        records ``commanded_mm``. None: command the targets as planned.
    position_tolerance_mm : the stage's reported position after a move must
        be this close to the position commanded, or the capture pauses with an
        error (a stage that stopped short must not be listed as the target).
    settle : settle detection before each stop's first frame and frame
        averaging (:mod:`lps_gui.capture.settle`); recorded in session.json
        ``acquisition``, the settle time of each stop in captures.jsonl.

    The camera's controls are locked for the whole capture and every frame's
    exposure and gain checked against them (:mod:`lps_gui.capture.camera_lock`).

    :meth:`pause`, :meth:`resume`, :meth:`abort` and :meth:`progress` are
    safe to call from any thread while :meth:`run` blocks in another.
    """

    def __init__(
        self,
        stage: Stage,
        camera: Camera,
        session: Session,
        clock: Clock | None = None,
        encode: str = ".png",
        *,
        simulator: SimulatorHook | None = None,
        move_timeout_s: float = 60.0,
        command_of: Callable[[float, int], float] | None = None,
        position_tolerance_mm: float = POSITION_TOLERANCE_MM,
        settle: SettleOptions | None = None,
    ) -> None:
        self.stage = stage
        self.camera = camera
        self.session = session
        self.clock: Clock = clock or stage.clock or RealClock()
        self.encode = encode if encode.startswith(".") else "." + encode
        if self.encode.lower() not in LOSSLESS:
            raise InputError(f"--encode {encode}: not a lossless format; use one of {', '.join(LOSSLESS)} "
                             "(lossy compression moves corners)")
        self.simulator = simulator
        self.move_timeout_s = float(move_timeout_s)
        self.command_of = command_of
        self._commanded_mm: float | None = None
        self.position_tolerance_mm = float(position_tolerance_mm)
        self._plan = session.plan()
        self._total = self._plan.n_frames()
        self._lock = threading.Lock()
        self._wake = threading.Condition(self._lock)
        self._pause_req = False
        self._pause_note: str | None = None  # why the capture pauses itself (a stitched plan's next segment)
        self._abort_req = False
        self._state = ev.IDLE
        self._error: str | None = None
        self._done = len({r.index for r in session.records()})
        self._current: PlannedStop | None = None
        self._message = ""
        self._eta_s: float | None = None
        self._events = EventSource()
        self._last_move: tuple[int, str, float, int] | None = None  # (run, direction, target, stop's first index)
        self._reported_mm: float | tuple[float, float] | None = None
        self._axis_sides: list[int | None] = [None, None]  # planar: side of each axis' last approach
        self._idle_s: float | None = None  # clock time the stage reported the last move onto a stop done
        self._active = False
        self.configure_settle(settle)
        self._locked: dict[str, Any] = {}
        self._frame_size: tuple[int, int] | None = None  # the intrinsics' image size every frame must have

    def configure_settle(self, settle: SettleOptions | None) -> None:
        """Settle detection and averaging for the next :meth:`run` (None or inactive options: neither)."""
        self.settle = settle if settle is not None and settle.active else None
        self._settler = None if self.settle is None else Settler(self.session.board(), self.settle, self.clock)

    # ------------------------------------------------------------------ control (any thread)
    def pause(self) -> None:
        """Stop after the frame being taken; :meth:`resume` continues (the next stop is re-approached)."""
        with self._lock:
            self._pause_req = True
            self._wake.notify_all()

    def resume(self) -> None:
        """Continue a user pause. After an error pause :meth:`run` has returned: call it again."""
        with self._lock:
            self._pause_req = False
            self._wake.notify_all()

    def abort(self) -> None:
        """Stop after the frame being taken; everything listed stays on disk."""
        with self._lock:
            self._abort_req = True
            self._wake.notify_all()

    @property
    def state(self) -> str:
        with self._lock:
            return self._state

    @property
    def error(self) -> str | None:
        with self._lock:
            return self._error

    def progress(self) -> CaptureProgress:
        """A consistent snapshot for a GUI timer or a status line."""
        with self._lock:
            cur = self._current
            return CaptureProgress(
                state=self._state,
                done=self._done,
                total=self._total,
                eta_s=self._eta_s,
                index=None if cur is None else cur.index,
                target_mm=None if cur is None else cur.target_mm,
                message=self._message,
                error=self._error,
            )

    def subscribe(self, listener: CaptureListener) -> Callable[[], None]:
        """Call ``listener(event)`` on the engine's thread for every :class:`CaptureEvent`; returns an unsubscribe."""
        return self._events.subscribe(listener)  # type: ignore[arg-type]  # a fan-out of any event type

    # ------------------------------------------------------------------ run
    def run(self, progress: ProgressFn = no_progress, cancel: CancelToken | None = None) -> CaptureSummary:
        """Capture every planned frame not yet listed; block until done, aborted or paused by an error.

        Raises InputError before any move when the session folder cannot
        take the images (unwritable, not enough free space). A HardwareError
        (port vanished, alarm, timeout) or a write failure mid-run returns a
        summary in state "paused" with the error; reconnect and call
        :meth:`run` again to continue.
        """
        with self._lock:
            if self._active:
                raise InputError("capture: already running; pause, resume or abort it instead")
            self._active = True
            self._state, self._error, self._abort_req, self._pause_req = ev.RUNNING, None, False, False
            self._last_move = None
            self._axis_sides = [None, None]
        t0 = self.clock.now()
        captured = 0
        lock = SessionLock(self.session.folder)
        try:
            lock.__enter__()  # one writer per session: a second capture or resume is told who holds it
            remaining = self.session.remaining_stops()
            self._set(done=self._total - len(remaining))
            if remaining:
                if not self.camera.is_open:  # first: its frame size bounds the disk space needed
                    self.camera.open()
                check_writable(self.session.folder / IMAGES_DIR, len(remaining) * bytes_per_frame(self.camera))
                self._locked = lock_camera(self.camera, self.session)
                self._frame_size = expected_frame_size(self.session)
                if self.settle is not None and self.session.meta.get("acquisition") != self.settle.to_dict():
                    self.session.meta["acquisition"] = self.settle.to_dict()
                    self.session.save_meta()
                check_plan_in_travel(self._plan, self.stage)
            if self.simulator is not None:
                self.simulator.prune(self.session)
            self._emit(CaptureEvent("started", f"{len(remaining)} of {self._total} frames to capture"))
            progress(self._total - len(remaining), self._total, "starting")
            listed = self.session.records()
            segment = listed[-1].segment if listed else None
            for stop in remaining:
                if stop.segment != segment and stop.segment:  # a stitched plan: the operator moves the board first
                    self._ask_to_move_board(stop)
                segment = stop.segment
                self._checkpoint(cancel)
                self._set(current=stop)
                if self._last_move is None or self._last_move[3] != stop.index - stop.frame:
                    self._go_to(stop)  # a new stop (its frames share one move)
                self._take(stop)
                captured += 1
                eta = (self.clock.now() - t0) / captured * (self._total - self._done - 1)
                self._set(done=self._done + 1, eta=eta, message=f"frame {stop.index} at {format_target(stop.target_mm)}")
                progress(self._done, self._total, self._message)
        except _Stop as exc:
            self._finish(ev.ABORTED, str(exc))
        except HardwareError as exc:
            self._fail(str(exc))
        except OSError as exc:  # disk full or folder gone mid-run: nothing listed is lost
            self._fail(f"{self.session.folder}: cannot write ({exc.strerror or exc}); free space or fix the folder, then resume")
        except InputError as exc:  # unwritable folder, full disk, bad encoding: before any harm
            with self._lock:
                self._state, self._error = (ev.IDLE if captured == 0 else ev.PAUSED), str(exc)
            raise
        except BaseException:  # KeyboardInterrupt or a bug: listed frames are safe on disk
            with self._lock:
                self._state = ev.PAUSED
            raise
        else:
            if self.simulator is not None:
                self.simulator.finalize(self.session)
            self._finish(ev.DONE, f"capture complete: {self._total} frames")
        finally:
            lock.__exit__(None, None, None)
            with self._lock:
                self._active = False
        return CaptureSummary(
            state=self.state,
            captured=captured,
            listed=len({r.index for r in self.session.records()}),
            total=self._total,
            elapsed_s=self.clock.now() - t0,
            folder=str(self.session.folder),
            error=self.error,
        )

    # ------------------------------------------------------------------ steps
    def _go_to(self, stop: PlannedStop) -> None:
        """Move onto ``stop``'s target from its own direction, wait, settle, read the position."""
        if self._plan.planar:
            self._last_move = None
            if self.simulator is not None:
                self.simulator.seed_stop(stop)
            self._emit(CaptureEvent("move", f"move to {format_target(stop.target_mm)}", stop.index))
            self._reported_mm = go_to_planar(self.stage, stop, self._plan, self._axis_sides, self._move)
            self.clock.sleep(self._plan.settle_s)
            self._reported_mm = (float(self.stage.position_mm("X")), float(self.stage.position_mm("Y")))
            for want, got in zip(stop.target_mm, self._reported_mm):
                check_reached(float(want), got, self.position_tolerance_mm)
            self._last_move = (stop.run, stop.direction, stop.target_mm, stop.index - stop.frame)
            return
        plan, feed = self._plan, self._plan.feed_mm_min
        sign = 1.0 if stop.direction == "+" else -1.0
        start = approach_point_mm(plan, stop, self._last_move)
        self._last_move = None
        if start is not None:
            self._emit(CaptureEvent("approach", f"approach from {start:g} mm", stop.index))
            self._move(start, feed)
        if self.simulator is not None:
            self.simulator.seed_stop(stop)
        self._emit(CaptureEvent("move", f"move to {stop.target_mm:g} mm", stop.index))
        self._commanded_mm = None if self.command_of is None else float(self.command_of(stop.target_mm, int(sign)))
        self._move(stop.target_mm if self._commanded_mm is None else self._commanded_mm, feed)
        self._idle_s = self.clock.now()  # the move is done: frame times count from here (ASME B5.64 settling)
        self.clock.sleep(plan.settle_s)
        self._reported_mm = float(self.stage.position_mm())
        commanded = stop.target_mm if self._commanded_mm is None else self._commanded_mm
        check_reached(commanded, self._reported_mm, self.position_tolerance_mm)
        self._last_move = (stop.run, stop.direction, stop.target_mm, stop.index - stop.frame)

    def _move(self, target_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        here = self.stage.position_mm(axis)
        self.stage.move_to(target_mm, feed_mm_min, axis)
        at_feed_s = abs(target_mm - here) / max(feed_mm_min / 60.0, 1e-9)
        self.stage.wait_idle(timeout_s=max(self.move_timeout_s, 3.0 * at_feed_s + 10.0))

    def _take(self, stop: PlannedStop) -> None:
        """Grab, write the image atomically, then list it (truth line first, capture line last)."""
        if self.simulator is not None:
            self.simulator.seed_frame(stop.index)
        settle_s = None
        if self._settler is None:
            frame = self.camera.grab()
            since_move_s = self._since_move_s()
            check_frame(self._locked, frame, stop.index)
        else:
            got = self._settler.grab(self.camera, settle=stop.frame == 0)
            for f in got.grabbed:
                check_frame(self._locked, f, stop.index)
            frame, settle_s, since_move_s = got.frame, got.settle_s, self._since_move_s()
            if not got.settled:
                self._emit(CaptureEvent("warning", f"frame {stop.index}: the picture did not settle within "
                                        f"{self.settle.timeout_s:g} s (last shift {got.shift_px} px); taken anyway", stop.index))
        check_frame_size(self._frame_size, frame, stop.index)
        record_bayer_gains(self.camera, self.session)
        data = encode_image(frame.image, self.encode)
        rel, sha = self.session.write_image(image_name(stop.index, self.encode), data)
        if self.simulator is not None:
            self.simulator.record(self.session, stop.index)
        record = CaptureRecord(
            index=stop.index,
            run=stop.run,
            direction=stop.direction,
            target_mm=stop.target_mm,
            reported_mm=self._reported_mm,
            file=rel,
            sha256=sha,
            time=time.time(),
            frame=stop.frame,
            commanded_mm=self._commanded_mm,
            settle_s=None if settle_s is None else round(float(settle_s), 6),
            since_move_s=since_move_s,
            segment=stop.segment,
        )
        self.session.append(record)
        self._emit(CaptureEvent("frame", rel, stop.index, record.__dict__.copy()))

    def _since_move_s(self) -> float | None:
        """Now, after the grab, on the engine's clock since the stage reported the stop's move done."""
        return None if self._idle_s is None else round(self.clock.now() - self._idle_s, 6)

    def _ask_to_move_board(self, stop: PlannedStop) -> None:
        """Pause before a stitched plan's next segment, saying where the board goes (resume when it is fixed)."""
        from lps_gui.core.planning.segments import board_move_mm

        segs = self._plan.segments
        k = int(stop.segment)
        message = (f"segment {k + 1} of {len(segs)}: move the board {board_move_mm(segs, k):g} mm along +X (in view "
                   f"from {segs[k][0]:g} to {segs[k][1]:g} mm; the first stops repeat segment {k}'s last), fix it, "
                   "then resume")
        with self._lock:
            self._pause_req, self._pause_note = True, message
        self._emit(CaptureEvent("move board", message, stop.index))

    def _checkpoint(self, cancel: CancelToken | None) -> None:
        """Between frames: honour abort, cancel and pause (waiting here until resumed)."""
        with self._lock:
            paused = False
            while True:
                if self._abort_req or (cancel is not None and cancel.cancelled):
                    raise _Stop("capture aborted; every listed frame is kept, resume to continue")
                if not self._pause_req:
                    break
                if not paused:
                    paused, self._state, self._message = True, ev.PAUSED, self._pause_note or "paused"
                    self._last_move = None  # the operator may jog: re-approach afterwards
                    self._axis_sides = [None, None]
                    self._lock.release()
                    try:
                        self._emit(CaptureEvent("paused", self._pause_note or "capture paused"))
                    finally:
                        self._lock.acquire()
                    continue
                self._wake.wait(timeout=0.2)  # real time: waits for a person (or a cancel token)
            if paused:
                self._state, self._message, self._pause_note = ev.RUNNING, "resumed", None
        if paused:
            self._emit(CaptureEvent("resumed", "capture resumed"))

    # ------------------------------------------------------------------ bookkeeping
    def _set(self, done: int | None = None, eta: float | None = None, current: PlannedStop | None = None, message: str | None = None) -> None:
        with self._lock:
            if done is not None:
                self._done = done
            if eta is not None:
                self._eta_s = eta
            if current is not None:
                self._current = current
            if message is not None:
                self._message = message

    def _fail(self, message: str) -> None:
        with self._lock:
            self._state, self._error, self._message = ev.PAUSED, message, message
            self._last_move = None
        self._emit(CaptureEvent("error", message))

    def _finish(self, state: str, message: str) -> None:
        with self._lock:
            self._state, self._message = state, message
            if state == ev.DONE:
                self._eta_s = 0.0
        self._emit(CaptureEvent(state, message))

    def _emit(self, event: CaptureEvent) -> None:
        self._events.emit(event)  # type: ignore[arg-type]  # a failing listener is logged, never stops the capture
