"""Per-test watchdog: a test past its timeout fails with every thread's stack; a deadlock ends the run.

pytest-timeout's own methods each miss one kind of hang: its SIGALRM handler
never runs while the main thread is stuck in C (a Qt event loop, a lock that
does not return on a signal), and its timer thread never runs while a
deadlocked thread holds the GIL. This plugin keeps pytest-timeout's settings
(``timeout`` in pyproject.toml, ``@pytest.mark.timeout(n)``) and its hooks,
and does three things when a test runs past its timeout:

1. a Python thread writes every thread's stack to the terminal, quits the Qt
   event loops Python code started and sends the main thread SIGALRM, whose
   handler fails the test; the run goes on with the next test;
2. if the main thread cannot take that signal, the test is failed with the
   stacks as soon as it returns;
3. ``watchdog_grace_s`` later, if the test has still not ended (the GIL or the
   main thread is held in C), faulthandler's C thread, which needs no GIL,
   dumps every thread's stack and ends the run with exit status 1.

Under pytest-xdist (``make test``) each worker runs its tests on its main
thread, so all of this holds per worker; step 3 ends only the stuck worker's
process: xdist fails that test as crashed and the run goes on without it.
"""
from __future__ import annotations

import faulthandler
import gc
import os
import signal
import sys
import threading
import traceback

import pytest

DEFAULT_GRACE_S = 30.0
_stderr_fd: int | None = None  # the terminal's stderr, kept before pytest captures fd 2 during tests


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addini("watchdog_grace_s", "seconds after a test's timeout before a stuck run is dumped and ended",
                  default=str(DEFAULT_GRACE_S))


def pytest_configure(config: pytest.Config) -> None:
    global _stderr_fd
    _stderr_fd = os.dup(sys.__stderr__.fileno())  # global capture is suspended here: fd 2 is the terminal


def pytest_unconfigure(config: pytest.Config) -> None:
    global _stderr_fd
    if _stderr_fd is not None:
        faulthandler.cancel_dump_traceback_later()
        os.close(_stderr_fd)
        _stderr_fd = None


def _write(text: str) -> None:
    if _stderr_fd is not None:
        os.write(_stderr_fd, text.encode("utf-8", "replace"))


def thread_stacks() -> str:
    """Every thread's stack but the caller's, most recent call last, headed by the thread's name."""
    names = {t.ident: t.name for t in threading.enumerate()}
    me = threading.get_ident()
    return "".join(f"\n--- thread {names.get(ident, '(not started by threading)')} ({ident:#x}):\n"
                   + "".join(traceback.format_stack(frame))
                   for ident, frame in sys._current_frames().items() if ident != me)


def _quit_qt_event_loops() -> None:
    """Ask every running QEventLoop that Python holds (pytest-qt's waits) to quit, from its own thread."""
    qtcore = sys.modules.get("PySide6.QtCore")
    if qtcore is None:
        return
    for obj in gc.get_objects():
        try:
            if isinstance(obj, qtcore.QEventLoop) and obj.isRunning():
                qtcore.QMetaObject.invokeMethod(obj, "quit", qtcore.Qt.ConnectionType.QueuedConnection)
        except RuntimeError:  # its C++ object is gone
            pass


class Watch:
    """The watchdog of one test: a Python timer for the soft step, faulthandler for the hard one."""

    def __init__(self, item: pytest.Item, timeout_s: float, grace_s: float) -> None:
        self.item = item
        self.timeout_s = timeout_s
        self.stacks: str | None = None  # set when the soft step fired
        self.ended = False  # the test's protocol is over: a late alarm is ignored
        self.main = threading.main_thread().ident
        self.timer = threading.Timer(timeout_s, self._fire)
        self.timer.name = f"watchdog {item.nodeid}"
        self.timer.daemon = True
        self.previous = signal.signal(signal.SIGALRM, self._on_alarm)
        if _stderr_fd is not None:
            faulthandler.dump_traceback_later(timeout_s + grace_s, exit=True, file=_stderr_fd)
        self.timer.start()

    def message(self) -> str:
        return f"watchdog: {self.item.nodeid} still running after {self.timeout_s:g} s; every thread's stack:{self.stacks}"

    def _fire(self) -> None:  # watchdog thread
        self.stacks = thread_stacks()
        _write(f"\n{'+' * 30} {self.message()}\n{'+' * 30}\n")
        signal.pthread_kill(self.main, signal.SIGALRM)  # handled as soon as the main thread runs Python again
        _quit_qt_event_loops()

    def _on_alarm(self, signum: int, frame: object) -> None:  # main thread
        __tracebackhide__ = True
        if not self.ended:
            pytest.fail(self.message())

    def cancel(self) -> None:
        self.ended = True
        faulthandler.cancel_dump_traceback_later()
        self.timer.cancel()
        self.timer.join()
        signal.signal(signal.SIGALRM, self.previous)


_WATCH = pytest.StashKey["Watch"]()


@pytest.hookimpl(tryfirst=True, optionalhook=True)  # pytest-timeout's hooks (the test extra has it)
def pytest_timeout_set_timer(item: pytest.Item, settings) -> bool:
    if threading.current_thread() is threading.main_thread():
        item.stash[_WATCH] = Watch(item, settings.timeout, float(item.config.getini("watchdog_grace_s")))
    return True


@pytest.hookimpl(tryfirst=True, optionalhook=True)
def pytest_timeout_cancel_timer(item: pytest.Item) -> bool:
    watch = item.stash.get(_WATCH, None)
    if watch is not None:
        watch.cancel()
    return True


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):
    """A test the watchdog fired on fails, even when the alarm could not interrupt it."""
    outcome = yield
    report = outcome.get_result()
    watch = item.stash.get(_WATCH, None)
    if watch is not None and watch.stacks is not None and report.when == "call" and report.passed:
        report.outcome = "failed"
        report.longrepr = watch.message()
