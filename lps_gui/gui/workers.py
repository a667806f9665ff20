"""Run blocking long work off the GUI thread.

A :class:`Job` wraps any function written for the CLI, i.e. one taking
``progress(done, total, message)`` and ``cancel`` (a :class:`CancelToken`),
in a QThread. The worker only emits signals; the slots that receive them run
in the GUI thread and are the only code touching widgets. Progress is
throttled so a fast loop cannot flood the event queue.
"""
from __future__ import annotations

import inspect
import logging
import os
import sys
import threading
import time
import traceback
import weakref
from typing import Any, Callable

from PySide6.QtCore import QObject, QThread, Signal

from lps_gui.core.progress import CancelToken
from lps_gui.errors import Cancelled, LpsError
from lps_gui.gui.wording import for_gui

log = logging.getLogger(__name__)

PROGRESS_INTERVAL_S = 0.05  # at most ~20 progress signals per second


def one_line(exc: BaseException) -> str:
    """The message a user sees: the first line of an LpsError or OSError worded for the GUI, or the type and text
    of a bug."""
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    if expected(exc):
        return for_gui(text) if text else "stopped without a reason given"
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def expected(exc: BaseException) -> bool:
    """A failure the user can act on (bad input, hardware, disk), not a bug: its traceback is not news."""
    return isinstance(exc, (LpsError, OSError))


UI_SWITCH_INTERVAL_S = 0.001  # GIL slice while jobs run: the GUI thread waits at most ~1 ms for it
_active_jobs = 0
_saved_switch_interval = sys.getswitchinterval()


def _job_started() -> None:
    """Shorten the GIL slice while any job runs (the GUI thread gets the GIL back sooner)."""
    global _active_jobs, _saved_switch_interval
    if _active_jobs == 0:
        _saved_switch_interval = sys.getswitchinterval()
        sys.setswitchinterval(min(_saved_switch_interval, UI_SWITCH_INTERVAL_S))
    _active_jobs += 1


def _job_ended() -> None:
    global _active_jobs
    _active_jobs = max(0, _active_jobs - 1)
    if _active_jobs == 0:
        sys.setswitchinterval(_saved_switch_interval)


WORKER_NICE = 5  # workers yield the CPU to the GUI thread when both want it


def lower_thread_priority(nice: int = WORKER_NICE) -> None:
    """Make the calling thread nicer than the GUI thread (Linux: per-thread nice; elsewhere a no-op)."""
    if not hasattr(os, "setpriority") or not sys.platform.startswith("linux"):
        return
    try:
        tid = threading.get_native_id()
        os.setpriority(os.PRIO_PROCESS, tid, min(19, os.getpriority(os.PRIO_PROCESS, tid) + nice))
    except OSError:  # not permitted: run at normal priority
        pass


def _parameters(fn: Callable[..., Any]) -> set[str] | None:
    """Names ``fn`` accepts, or None when it takes ``**kwargs`` (or cannot be inspected)."""
    try:
        params = inspect.signature(fn).parameters
    except (TypeError, ValueError):
        return None
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()):
        return None
    return set(params)


_RUNNING: set["Job"] = set()  # strong references: a running job is never garbage-collected with its thread
_UNENDED: list[QThread] = []  # threads that did not end after finished(): never destroyed while running
THREAD_END_WAIT_MS = 10000


def running_jobs() -> list["Job"]:
    """Jobs started and not yet reported finished (GUI thread bookkeeping)."""
    return list(_RUNNING)


def stop_all_jobs(timeout_ms: int = 10000) -> bool:
    """Cancel every running job and wait for its thread; True if all ended (used at shutdown)."""
    jobs = running_jobs()
    for job in jobs:
        job.cancel()
    return all(job.wait(timeout_ms) for job in jobs)


class _Thread(QThread):
    """The thread body; all results leave through the owning Job's signals.

    It drops its reference to the work when the work starts: no Job <-> thread
    reference cycle, so the thread object is freed by reference counting on
    the GUI thread, never by the cyclic collector on whatever thread happens
    to trigger a collection (where ``~QThread`` of a thread still finishing
    waits for it while holding the GIL).
    """

    def __init__(self, body: Callable[[], None]) -> None:
        super().__init__()
        self._body: Callable[[], None] | None = body

    def run(self) -> None:  # runs in the worker thread
        body, self._body = self._body, None
        if body is not None:
            body()


class Job(QObject):
    """A blocking ``fn(*args, progress=..., cancel=..., **kwargs)`` in a worker thread.

    Signals
    -------
    progress(done, total, message)
        Throttled progress; the last report always gets through.
    succeeded(result)
        The function returned.
    failed(message, traceback)
        It raised; ``message`` is one line for a message box.
    cancelled(message)
        It raised :class:`Cancelled` after :meth:`cancel`.
    finished()
        Always, last.
    """

    progress = Signal(int, int, str)
    succeeded = Signal(object)
    failed = Signal(str, str)
    cancelled = Signal(str)
    finished = Signal()

    def __init__(
        self,
        name: str,
        fn: Callable[..., Any],
        *args: Any,
        pass_progress: bool = True,
        parent: QObject | None = None,
        **kwargs: Any,
    ) -> None:
        super().__init__(parent)
        self.name = name
        self.token = CancelToken()
        self._fn = fn
        self._args = args
        self._kwargs = kwargs
        self._pass_progress = pass_progress
        self._last_emit = 0.0
        self._thread = _Thread(self._run_in_thread)
        self._thread.finished.connect(self._on_thread_finished)
        self.result: Any = None
        self.error: str | None = None
        self.expected_error = True  # False: the failure was a bug, its traceback belongs in the log
        self.started_at = 0.0
        self._work_ended = False  # set in the worker before its result is emitted

    # ------------------------------------------------------------------ control (GUI thread)
    def start(self) -> "Job":
        self.started_at = time.monotonic()
        log.info("%s: started", self.name)
        _job_started()
        _RUNNING.add(self)
        self._thread.start()
        return self

    def cancel(self) -> None:
        """Ask the work to stop at its next check; results so far are kept by the work itself."""
        if not self.token.cancelled:
            log.info("%s: cancel requested", self.name)
        self.token.cancel()

    @property
    def running(self) -> bool:
        """Its work is still running: False once the work returned or raised (before its result is delivered, while
        the thread takes its last steps), so a slot of ``succeeded`` already sees the job as ended (a window closed
        right after a capture's ``session_done`` must not ask whether to stop a capture that is over)."""
        return self._thread.isRunning() and not self._work_ended

    def wait(self, timeout_ms: int = 30000) -> bool:
        return self._thread.wait(timeout_ms)

    # ------------------------------------------------------------------ worker thread
    def _progress(self, done: int, total: int, message: str = "") -> None:
        now = time.monotonic()
        if now - self._last_emit >= PROGRESS_INTERVAL_S or (total and done >= total):
            self._last_emit = now
            self.progress.emit(int(done), int(total), str(message))

    def _run_in_thread(self) -> None:
        lower_thread_priority()
        try:
            kwargs = dict(self._kwargs)
            if self._pass_progress:
                accepted = _parameters(self._fn)
                if accepted is None or "progress" in accepted:
                    kwargs["progress"] = self._progress
                if accepted is None or "cancel" in accepted:
                    kwargs["cancel"] = self.token
            result = self._fn(*self._args, **kwargs)
        except Cancelled as exc:
            self._work_ended = True
            self.error = one_line(exc)
            self.cancelled.emit(self.error)
        except Exception as exc:  # every failure reaches the user as one line, the log gets the rest
            self._work_ended = True
            self.error = one_line(exc)
            self.expected_error = expected(exc)
            tb = traceback.format_exc()
            self.failed.emit(self.error, tb)
        else:
            self._work_ended = True
            self.result = result
            self.succeeded.emit(result)

    def _on_thread_finished(self) -> None:  # GUI thread
        # finished() comes from the thread's last steps: let them end (the GIL is released meanwhile) before the
        # job, and with it the QThread, can be dropped; a thread that does not end is kept, never destroyed running
        if not self._thread.wait(THREAD_END_WAIT_MS):
            log.warning("%s: its thread did not end after finished(); kept", self.name)
            _UNENDED.append(self._thread)
        _job_ended()
        _RUNNING.discard(self)
        if self.error is None:  # a failure or a cancel is reported by whoever shows it, without a duration
            log.info("%s: finished in %.2f s", self.name, time.monotonic() - self.started_at)
        self.finished.emit()


def owned_by(job: Job, owner: QObject) -> Job:
    """Tie ``job`` to ``owner`` (a panel): when the owner goes, the job is cancelled and its signals stop.

    A panel's own worker (formatting a table, reading corners) can finish after
    the panel was deleted; its slots would then touch deleted widgets
    ("TextTable already deleted"). Blocked, its results go nowhere; the job's
    bookkeeping (``_RUNNING``, the thread's end) still happens.
    """
    ref = weakref.ref(job)

    def gone(_obj: object = None) -> None:
        j = ref()
        if j is not None:
            j.cancel()
            j.blockSignals(True)

    owner.destroyed.connect(gone)
    return job
