"""GUI test fixtures: a main window with throw-away settings, and an event-loop gap meter."""
from __future__ import annotations

import time

import pytest
from PySide6.QtCore import QSettings, QTimer

from lps_gui.core.clock import RealClock


@pytest.fixture(autouse=True)
def no_modal_question(monkeypatch):
    """A modal question nobody answers waits forever (offscreen, no one clicks): fail instead of hanging. A test that
    expects a question answers it with its own monkeypatch (tests/gui/test_operator_laptop.py)."""
    from PySide6.QtWidgets import QMessageBox

    def unanswered(_parent, title, text, *_args, **_kwargs):
        raise AssertionError(f"a modal question no test answers: {title!r}: {text!r}")

    monkeypatch.setattr(QMessageBox, "question", staticmethod(unanswered))


@pytest.fixture
def settings(tmp_path):
    """QSettings in a temporary INI file: tests never touch the user's settings."""
    s = QSettings(str(tmp_path / "lps-gui-test.ini"), QSettings.Format.IniFormat)
    yield s
    s.sync()


@pytest.fixture
def make_window(qtbot, settings):
    """Factory for main windows (the simulated rig on real time unless a clock is given)."""
    from lps_gui.gui.main_window import MainWindow

    made = []

    def make(sim_clock=None, settings_=None):
        w = MainWindow(settings_ or settings, sim_clock=sim_clock or RealClock())
        qtbot.addWidget(w)
        w.resize(1400, 900)
        w.show()
        made.append(w)
        return w

    yield make
    for w in made:
        w.shutdown()


@pytest.fixture
def window(make_window):
    return make_window()


class GapMeter:
    """Ticks of a 5 ms QTimer: how long the event loop was blocked, and by whom.

    ``max_busy_cpu_s`` is the most GUI-thread CPU time spent between two ticks:
    work our code did on the GUI thread, which a loaded machine does not
    inflate (a thread that is merely descheduled spends no CPU). Tests assert
    on it; the wall-clock ``max_gap_s`` depends on the machine's load and is
    measured by ``benchmarks/bench_gui.py`` instead.
    """

    def __init__(self) -> None:
        self.timer = QTimer()
        self.timer.setInterval(5)
        self.timer.timeout.connect(self._tick)
        self.last = 0.0
        self.last_cpu = 0.0
        self.max_gap_s = 0.0
        self.max_gap_cpu_s = 0.0
        self.max_busy_cpu_s = 0.0
        self.ticks = 0

    def _tick(self) -> None:
        now = time.perf_counter()
        cpu = time.thread_time()
        if self.ticks and now - self.last > self.max_gap_s:
            self.max_gap_s = now - self.last
            self.max_gap_cpu_s = cpu - self.last_cpu  # GUI-thread CPU spent inside the longest gap
        if self.ticks:
            self.max_busy_cpu_s = max(self.max_busy_cpu_s, cpu - self.last_cpu)
        self.last = now
        self.last_cpu = cpu
        self.ticks += 1

    def __enter__(self) -> "GapMeter":
        self.last = time.perf_counter()
        self.last_cpu = time.thread_time()
        self.timer.start()
        return self

    def __exit__(self, *exc) -> None:
        self.timer.stop()


@pytest.fixture
def gap_meter():
    return GapMeter


def connect_sim(qtbot, window) -> None:
    """Connect the default source (the simulated rig) and wait for the first status report."""
    assert window.stage_panel.source.currentData() == "sim"
    window.stage_panel.connect_btn.click()
    qtbot.waitUntil(lambda: window.stage_ctl.connected and window.stage_ctl.last_status is not None, timeout=10000)
