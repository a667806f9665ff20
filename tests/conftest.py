"""Test-wide settings: Qt offscreen, one QApplication for the whole session.

The report paints with a QGuiApplication when none exists; widgets need a
QApplication. Creating the QApplication first, once, lets PDF tests and GUI
tests share one process in any order.
"""
import gc
import os
import shutil
import tempfile

import pytest

pytest_plugins = ["tests.watchdog"]  # a hung test fails with every thread's stack; a deadlock ends the run

RAM_DISK = "/dev/shm"
RAM_DISK_FREE_BYTES = 2 << 30  # a whole run writes ~0.2 GB (pytest keeps its last 3 runs)


def _temp_in_ram() -> None:
    """Test folders on the RAM disk when the machine has one and TMPDIR is not chosen.

    Why: every write of the product is fsynced (io/atomic.py), a few thousand per
    run; on a disk each waits for the device (~4-10 ms here), on tmpfs it returns
    at once. The product code runs unchanged and every test sees the same files;
    only the waits go. Subprocesses the tests start inherit TMPDIR.
    """
    if "TMPDIR" in os.environ or not os.access(RAM_DISK, os.W_OK):
        return
    if shutil.disk_usage(RAM_DISK).free < RAM_DISK_FREE_BYTES:
        return
    os.environ["TMPDIR"] = RAM_DISK
    tempfile.tempdir = None  # tempfile caches its choice: the next call reads TMPDIR


_RUNTIME_DIR = ""


def _own_runtime_dir() -> None:
    """Emulator announcements (hardware/announce.py) in a folder of this test process alone.

    Why: the GUI's stage list shows every pty announced under $XDG_RUNTIME_DIR; an `lps emulate-grbl` that a test
    starts in the other pytest-xdist worker (or one the developer runs) would appear in this worker's windows
    mid-test. Each worker imports this file itself and so gets its own folder; the processes a test starts inherit it.
    """
    global _RUNTIME_DIR
    _RUNTIME_DIR = os.environ["XDG_RUNTIME_DIR"] = tempfile.mkdtemp(prefix="lps-tests-runtime-")  # 0700, as XDG asks


_temp_in_ram()
_own_runtime_dir()
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
os.environ.setdefault("PYLON_CAMEMU", "2")  # pylon offers two emulated cameras (read when pylon first loads)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # what the entry points do (lps_gui/blas_threads.py), before numpy loads


def pytest_unconfigure(config):
    shutil.rmtree(_RUNTIME_DIR, ignore_errors=True)  # _own_runtime_dir's, in each process (master and workers)


def pytest_configure(config):
    from lps_gui.allocator import tune_allocator

    tune_allocator()  # what the entry points do (lps, lps-gui): the estimator's temporaries stay in the heap
    try:
        from PySide6.QtWidgets import QApplication
    except ImportError:  # a Qt-less environment still runs the non-GUI tests
        return
    if QApplication.instance() is None:
        config._lps_qapp = QApplication(["lps-tests"])


@pytest.fixture(autouse=True)
def _collector_as_usual(request):
    """`lps`'s main() freezes what is alive for its exit (lps_gui/gc_tuning.py); the next test collects as usual.

    A Qt test's windows and widgets go now, on the GUI thread: pytest-qt only
    closes them and calls deleteLater, which no event loop runs before the next
    test, and a Python-owned widget left in a reference cycle is otherwise
    destroyed by the cyclic collector on whatever thread triggers a collection
    (an estimator's block thread, a camera preview), off the GUI thread.
    """
    yield
    gc.unfreeze()
    if "qtbot" in request.fixturenames:
        from PySide6.QtCore import QCoreApplication, QEvent

        QCoreApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete)
        gc.collect()


@pytest.fixture(scope="session")
def lightfield_demo(tmp_path_factory):
    """`lps demo --lightfield --quick` once per test run (about 9 s): its pipeline tests and the GUI's tab share it."""
    from lps_gui.pipeline.demos.lightfield import run_lightfield_demo

    return run_lightfield_demo(tmp_path_factory.mktemp("lf") / "out", quick=True)


@pytest.fixture(scope="session")
def small_planar_estimated(tmp_path_factory):
    """A simulated small-planar point session (both directions, 2 runs, seed 3) estimated by `lps estimate`.

    Read only (several modules share it, one estimate): a test that writes into it (a report) copies it first.
    """
    from lps_gui.cli import main as lps_main

    folder = tmp_path_factory.mktemp("small-planar") / "s"
    assert lps_main(["simulate", "--planar", "--points", str(folder), "--preset", "small-planar", "--directions",
                     "both", "--runs", "2", "--seed", "3"]) == 0
    assert lps_main(["estimate", str(folder)]) == 0
    return folder


def _asme_demo(tmp_path_factory, test: str):
    from lps_gui.pipeline.demos.asme import run_asme_demo

    return run_asme_demo(tmp_path_factory.mktemp("asme") / test, test)


@pytest.fixture(scope="session")
def min_step_demo(tmp_path_factory):
    """`lps demo --test min-step` (run_asme_demo, seed 0) once per test run: the report's and the GUI's tests read it."""
    return _asme_demo(tmp_path_factory, "min-step")


@pytest.fixture(scope="session")
def settling_demo(tmp_path_factory):
    """`lps demo --test settling` (run_asme_demo, seed 0) once per test run: the report's front-page and every-figure
    tests read it (a test that writes into its session folder, a report, copies it first)."""
    return _asme_demo(tmp_path_factory, "settling")


@pytest.fixture(scope="session")
def quick_planar_demo(tmp_path_factory):
    """`lps demo --planar --quick` once per test run (its out folder; the session in out/session), about 10 s.

    Read only: tests/pipeline/test_demo_planar.py reads it; a test that estimates or reports into it copies it first.
    """
    from lps_gui.cli import main as lps_main

    out = tmp_path_factory.mktemp("demo-planar") / "out"
    assert lps_main(["demo", "--planar", "--quick", "--out", str(out)]) == 0
    return out
