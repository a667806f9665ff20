"""Jobs run blocking work in a thread, report progress, cancel, and turn errors into one line."""
from __future__ import annotations

import gc
import threading
import weakref

import pytest

from lps_gui.errors import InputError
from lps_gui.gui.workers import Job, one_line

pytestmark = pytest.mark.gui


def counting(n, progress, cancel, gate=None):
    """Count to n, checking cancel at every step; waits on ``gate`` (an Event) first."""
    if gate is not None:
        gate.wait(5.0)
    for i in range(n):
        cancel.check("counting")
        progress(i + 1, n, f"step {i + 1}")
    return threading.current_thread().name


def test_job_runs_off_the_gui_thread_and_reports_progress(qtbot):
    job = Job("count", counting, 200)
    seen = []
    job.progress.connect(lambda d, t, m: seen.append((d, t, threading.current_thread() is threading.main_thread())))
    with qtbot.waitSignal(job.finished, timeout=5000):
        with qtbot.waitSignal(job.succeeded, timeout=5000) as got:
            job.start()
    assert got.args[0] != threading.main_thread().name  # the work ran in another thread
    assert seen and seen[-1][:2] == (200, 200)  # the last report always arrives
    assert all(on_main for *_, on_main in seen)  # ... delivered to the GUI thread
    assert len(seen) < 200  # throttled


def test_a_job_whose_work_returned_is_not_running_while_its_thread_ends(qtbot):
    """A window closed right after a capture's ``session_done`` asked "A capture is running. Quit?" (a modal nobody
    answered in CI: the whole run hung): the result was delivered while the thread took its last steps. Seen from a
    slot run inside the worker thread (so the thread is surely still running), the job has ended."""
    from PySide6.QtCore import Qt

    job = Job("count", counting, 3)
    seen = []
    job.succeeded.connect(lambda _r: seen.append((job._thread.isRunning(), job.running)), Qt.ConnectionType.DirectConnection)
    with qtbot.waitSignal(job.finished, timeout=5000):
        job.start()
    assert seen == [(True, False)]


def test_cancel_stops_the_work(qtbot):
    gate = threading.Event()
    job = Job("count", counting, 10**9, gate=gate)
    with qtbot.waitSignal(job.cancelled, timeout=5000) as got:
        job.start()
        job.cancel()
        gate.set()
    assert "cancelled" in got.args[0]
    assert job.result is None
    job.wait()


def test_failure_is_one_line(qtbot):
    def broken(progress, cancel):
        raise InputError("session.json: not an lps-session/1 session file")

    job = Job("broken", broken)
    with qtbot.waitSignal(job.failed, timeout=5000) as got:
        job.start()
    message, tb = got.args
    assert message == "session.json: not an lps-session/1 session file"
    assert "Traceback" in tb
    assert one_line(ValueError("bad\nsecond line")) == "ValueError: bad"
    job.wait()


def test_functions_without_cancel_get_only_what_they_accept(qtbot):
    def only_progress(x, progress):
        progress(1, 1)
        return x * 2

    job = Job("p", only_progress, 21)
    with qtbot.waitSignal(job.succeeded, timeout=5000) as got:
        job.start()
    assert got.args[0] == 42
    job.wait()


def test_a_finished_job_is_freed_with_its_thread_by_reference_counting(qtbot):
    """No job <-> thread cycle: the QThread is never left to the cyclic collector (any thread's, at any time)."""
    gc.disable()
    try:
        job = Job("nothing", lambda: None, pass_progress=False)
        with qtbot.waitSignal(job.finished, timeout=10000):
            job.start()
        assert job._thread.isFinished()  # waited for on the GUI thread before finished() was passed on
        thread = weakref.ref(job._thread)
        del job
        assert thread() is None
    finally:
        gc.enable()
