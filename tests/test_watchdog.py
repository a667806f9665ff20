"""The per-test watchdog (tests/watchdog.py): a hung test fails with every thread's stack, a deadlock ends the run.

Each case runs a small test file in its own pytest process with a one-second
timeout; the process is itself bounded, so these tests cannot hang.
"""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

HUNG_TESTS = '''
import threading

def _deadlocked_pair():
    """Two threads that each hold one lock and wait for the other's."""
    a, b, both = threading.Lock(), threading.Lock(), threading.Barrier(2)

    def take(first, second):
        with first:
            both.wait()
            with second:
                pass

    threads = [threading.Thread(target=take, args=pair, name=f"holder-{i}", daemon=True)
               for i, pair in enumerate([(a, b), (b, a)])]
    for t in threads:
        t.start()
    return threads

def test_waits_for_deadlocked_threads():
    _deadlocked_pair()[0].join()

def test_qt_event_loop_waits_for_a_deadlocked_thread():
    from PySide6.QtCore import QCoreApplication, QEventLoop

    app = QCoreApplication.instance() or QCoreApplication(["watchdog-test"])
    _deadlocked_pair()
    QEventLoop().exec()  # nothing will ever quit it

def test_the_run_goes_on():
    pass
'''

GIL_HELD = '''
import ctypes

def test_deadlock_holding_the_gil():
    libc = ctypes.PyDLL(None)  # PyDLL: the call keeps the GIL, as a C extension stuck on a futex does
    mutex = ctypes.create_string_buffer(64)  # zeros: PTHREAD_MUTEX_INITIALIZER
    libc.pthread_mutex_lock(mutex)
    libc.pthread_mutex_lock(mutex)  # a normal mutex locked twice by one thread: a futex wait no signal ends

def test_never_reached():
    pass
'''


def run_inner(tmp_path: Path, source: str, *options: str, **more: str) -> subprocess.CompletedProcess:
    """``source`` as test_inner.py (and each of ``more`` as test_NAME.py) run by pytest with a 1 s timeout."""
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    (tmp_path / "test_inner.py").write_text(textwrap.dedent(source))
    for name, text in more.items():
        (tmp_path / f"test_{name}.py").write_text(textwrap.dedent(text))
    env = dict(os.environ, PYTHONPATH=str(ROOT), QT_QPA_PLATFORM="offscreen")
    cmd = [sys.executable, "-m", "pytest", "-p", "tests.watchdog", "-p", "no:cacheprovider", "-q",
           "-o", "timeout=1", "-o", "watchdog_grace_s=4", *options, str(tmp_path)]
    return subprocess.run(cmd, check=False, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=180)


def test_hung_tests_fail_with_every_threads_stack_and_the_run_goes_on(tmp_path):
    out = run_inner(tmp_path, HUNG_TESTS)
    text = out.stdout + out.stderr
    assert out.returncode == 1, text
    assert "2 failed, 1 passed" in text, text
    for name in ("test_waits_for_deadlocked_threads", "test_qt_event_loop_waits_for_a_deadlocked_thread"):
        assert f"watchdog: test_inner.py::{name} still running after 1 s" in text, text
    assert "--- thread holder-0" in text and "--- thread holder-1" in text, text  # the deadlocked threads' stacks
    assert "in take" in text and "with second:" in text, text
    assert "Timeout (" not in text, text  # no hard stop: every test ended


def test_a_deadlock_that_holds_the_gil_ends_the_run_with_every_threads_stack(tmp_path):
    out = run_inner(tmp_path, GIL_HELD)
    text = out.stdout + out.stderr
    assert out.returncode == 1, text
    assert "Timeout (" in text and "test_deadlock_holding_the_gil" in text, text  # faulthandler's dump
    assert "passed" not in text, text  # the run ended there


def test_under_xdist_a_hung_test_fails_with_the_stacks_and_a_deadlock_ends_only_its_worker(tmp_path):
    """`make test` runs on two pytest-xdist workers: each runs its tests on its main thread, so the watchdog works
    there as in one process; the hard step ends the stuck worker, xdist fails that test as crashed and the other
    worker (or a new one) runs the rest. Every dump reaches the terminal (stderr)."""
    out = run_inner(tmp_path, HUNG_TESTS, "-n", "2", gil=GIL_HELD)
    text = out.stdout + out.stderr
    assert out.returncode == 1, text
    assert "3 failed, 2 passed" in text, text
    for name in ("test_waits_for_deadlocked_threads", "test_qt_event_loop_waits_for_a_deadlocked_thread"):
        assert f"watchdog: test_inner.py::{name} still running after 1 s" in text, text
    assert "--- thread holder-0" in text and "with second:" in text, text
    assert "crashed while running 'test_gil.py::test_deadlock_holding_the_gil'" in text, text
    assert "Timeout (" in text and "in test_deadlock_holding_the_gil" in out.stderr, text  # faulthandler's dump
