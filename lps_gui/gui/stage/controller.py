"""The GUI's handle on a Stage: one command thread, status polling, events as signals.

Stage methods block until the controller acknowledges (a serial round trip),
so every call runs on one dedicated worker thread, in order; the GUI thread
only submits and receives signals. A status poll runs several times a second
while connected, on its own thread, so the readout keeps moving (and shows
Home) while a long call such as homing blocks the command thread. A HardwareError from any call (port vanished, alarm) is
reported once and, if the link is gone, turns the controller to
"Disconnected" without touching anything already captured.
"""
from __future__ import annotations

import logging
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, Callable

from PySide6.QtCore import QObject, QTimer, Signal

from lps_gui.errors import HardwareError
from lps_gui.gui.workers import expected, one_line
from lps_gui.hardware.stage import Stage, StageStatus

log = logging.getLogger(__name__)

POLL_INTERVAL_MS = 200  # 5 readout updates per second


class StageController(QObject):
    """Owns the connected stage (if any) and serializes every call to it."""

    status_changed = Signal(object)  # StageStatus
    event_received = Signal(object)  # StageEvent
    connection_changed = Signal(bool, str)  # connected, description
    command_failed = Signal(str, str)  # what, one-line cause
    settings_read = Signal(object)  # list[StageSetting]
    link_lost = Signal(str)  # the stage stopped answering; the GUI drops the connection
    opened = Signal(object, object, str)  # stage, extra (e.g. its simulated camera), description
    _opened_in_thread = Signal(object, object, str)
    _polled = Signal(object, object)  # stage, StageStatus: from the status thread to the GUI thread

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.stage: Stage | None = None
        self.description = ""
        self.last_status: StageStatus | None = None
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="stage")
        self._status_pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="stage-status")
        self._poll_pending = False
        self._unsubscribe: Callable[[], None] | None = None
        self._timer = QTimer(self)
        self._timer.setInterval(POLL_INTERVAL_MS)
        self._timer.timeout.connect(self.poll)
        self._opened_in_thread.connect(self._on_opened)
        self._polled.connect(self._show_polled)

    # ------------------------------------------------------------------ connection
    @property
    def connected(self) -> bool:
        return self.stage is not None

    def open(self, factory: Callable[[], tuple[Stage, Any]], description: str) -> Future:
        """Build and connect a stage on the stage thread, then start polling.

        ``factory`` returns ``(stage, extra)``; ``extra`` (e.g. the simulated
        camera that follows a simulated stage) is passed on by :attr:`opened`.
        Opening a port or building a simulated rig may take a moment, so the
        GUI thread never runs it.
        """
        if self.stage is not None:
            self.detach()

        def go() -> tuple[Stage, Any]:
            stage, extra = factory()
            stage.connect()
            return stage, extra

        fut = self._submit("connect", go)
        fut.add_done_callback(lambda f: None if f.exception() else self._opened_in_thread.emit(*f.result(), description))
        return fut

    def _on_opened(self, stage: Stage, extra: Any, description: str) -> None:  # GUI thread
        self.stage = stage
        self.description = description
        self._unsubscribe = stage.events.subscribe(self.event_received.emit)
        log.info("stage: connected to %s", description)
        self._timer.start()
        self.connection_changed.emit(True, description)
        self.opened.emit(stage, extra, description)
        self.poll()

    def detach(self, reason: str = "") -> None:
        """Disconnect (best effort) and forget the stage."""
        stage, self.stage = self.stage, None
        self._timer.stop()
        if self._unsubscribe:
            self._unsubscribe()
            self._unsubscribe = None
        if stage is not None:
            def go() -> None:
                try:
                    stage.disconnect()
                except Exception:  # already gone: nothing more to do
                    log.debug("disconnect failed", exc_info=True)

            self._pool.submit(go)
        self.last_status = None
        if stage is not None:
            log.info("stage: disconnected%s", f" ({reason})" if reason else "")
            self.connection_changed.emit(False, reason)

    def shutdown(self) -> None:
        self.detach("closed")
        self._pool.shutdown(wait=True, cancel_futures=True)
        self._status_pool.shutdown(wait=True, cancel_futures=True)

    # ------------------------------------------------------------------ commands
    def call(self, what: str, method: str, *args: Any) -> Future | None:
        """Run ``stage.method(*args)`` on the stage thread; failures become ``command_failed``."""
        if self.stage is None:
            self.command_failed.emit(what, "stage: not connected; connect the stage first")
            return None
        stage = self.stage
        if not callable(getattr(stage, method, None)):  # a menu entry for a capability this stage does not declare
            self.command_failed.emit(what, f"{what}: the connected stage ({type(stage).__name__}) cannot do this")
            return None
        log.info("stage: %s", what)
        fut = self._submit(what, lambda: getattr(stage, method)(*args))
        if method == "home":
            fut.add_done_callback(lambda f: self._log_home_end(stage, f))
        return fut

    def _log_home_end(self, stage: Stage, fut: Future) -> None:  # stage thread
        """Homing moves the carriage a long way without a word: say when and where it ended."""
        if fut.exception() is not None:
            return  # _check logs the failure
        try:
            st = stage.status()
            where = ", ".join(f"{ax} {v:.3f}" for ax, v in zip("XYZ", st.machine_mm))
            log.info("stage: homing finished (%s); machine position %s mm", st.state, where)
        except Exception:  # noqa: BLE001 - the end is still worth logging
            log.info("stage: homing finished")

    def call_now(self, what: str, method: str, *args: Any) -> Future | None:
        """Like :meth:`call` for real-time commands (jog cancel, feed hold): not queued behind other calls."""
        if self.stage is None:
            return None
        stage = self.stage
        log.info("stage: %s", what)
        fut = self._status_pool.submit(lambda: getattr(stage, method)(*args))
        fut.add_done_callback(lambda f: self._check(what, f))
        return fut

    def read_settings(self) -> None:
        if self.stage is None:
            return
        stage = self.stage
        fut = self._submit("read settings", stage.read_settings)
        fut.add_done_callback(lambda f: None if f.exception() else self.settings_read.emit(f.result()))

    def write_setting(self, number: int, value: float) -> Future | None:
        return self.call(f"write ${number}={value:g}", "write_setting", number, value)

    def poll(self) -> None:
        """Ask for a status report unless one is still on its way."""
        if self.stage is None or self._poll_pending:
            return
        self._poll_pending = True
        stage = self.stage

        def go() -> StageStatus:
            return stage.status()

        fut = self._status_pool.submit(go)
        fut.add_done_callback(lambda f: self._on_polled(stage, f))

    def _on_polled(self, stage: Stage, fut: Future) -> None:  # status thread
        self._poll_pending = False
        if self.stage is not stage:
            return  # disconnected meanwhile: a failed late poll is no lost link
        if fut.exception() is not None:
            self._check("status", fut)
        else:
            self._polled.emit(stage, fut.result())

    def _show_polled(self, stage: Stage, st: StageStatus) -> None:  # GUI thread
        """A status that arrives after a disconnect is dropped: no stale position or state under "not connected"."""
        if self.stage is stage:
            self.last_status = st
            self.status_changed.emit(st)

    # ------------------------------------------------------------------ plumbing
    def _submit(self, what: str, fn: Callable[[], Any]) -> Future:
        fut = self._pool.submit(fn)
        fut.add_done_callback(lambda f: self._check(what, f))
        return fut

    def _check(self, what: str, fut: Future) -> None:  # stage thread: only emit signals
        exc = fut.exception()
        if exc is None:
            return
        msg = one_line(exc)
        log.error("stage: %s failed: %s", what, msg, exc_info=None if expected(exc) else exc)
        self.command_failed.emit(what, msg)
        stage = self.stage
        gone = what in ("status", "connect") or stage is None or not _still_connected(stage)
        if gone and isinstance(exc, (HardwareError, OSError)):
            self.link_lost.emit(msg)


def _still_connected(stage: Stage) -> bool:
    try:
        return bool(stage.connected)
    except Exception:
        return False
