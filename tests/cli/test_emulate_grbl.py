"""``lps emulate-grbl``: prints a pty path a GrblStage can drive, stops cleanly on Ctrl-C."""
from __future__ import annotations

import signal
import subprocess
import sys

import pytest

from lps_gui.errors import HardwareError
from lps_gui.hardware.grbl.driver import GrblStage


LPS = [sys.executable, "-c", "import sys; from lps_gui.cli import main; sys.exit(main(sys.argv[1:]))"]


def _default_sigint() -> None:
    """Ctrl-C as a terminal delivers it: a test run started in the background (``cmd &``) ignores SIGINT, and
    its children inherit that, so the emulator would never see the Ctrl-C these tests send."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _serve(*extra: str) -> subprocess.Popen:
    return subprocess.Popen(
        [*LPS, "emulate-grbl", "--time-scale", "50", "--travel", "0", "100", *extra],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=_default_sigint,
    )


def _stop(proc: subprocess.Popen, sig: int) -> tuple[str, str]:
    """Send ``sig`` and collect the output; an emulator that does not stop is killed, never left running."""
    proc.send_signal(sig)
    try:
        return proc.communicate(timeout=60)  # bounded; a loaded machine may take seconds to exit
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


def test_emulate_grbl_serves_a_pty_until_ctrl_c():
    proc = _serve("--homing-required")
    try:
        path = proc.stdout.readline().strip()
        assert path.startswith("/dev/")
        stage = GrblStage(path, timeout_s=5.0, poll_interval_s=0.01)
        stage.connect()
        assert stage.status().state == "Alarm"
        stage.home()
        stage.move_to(25.0, 3000.0)
        assert stage.wait_idle(timeout_s=30.0).work_mm[0] == pytest.approx(25.0)
        stage.disconnect()
    finally:
        out, err = _stop(proc, signal.SIGINT)
    assert proc.returncode == 0, err
    assert "emulator: stopped" in err


def test_emulate_grbl_fault_switch_drops_the_connection():
    proc = _serve("--drop-after-lines", "3")
    try:
        path = proc.stdout.readline().strip()
        stage = GrblStage(path, timeout_s=5.0)
        stage.connect()
        with pytest.raises(HardwareError, match="port vanished"):
            stage.move_to(5.0, 600.0)
        out, err = proc.communicate(timeout=60)  # bounded; a loaded machine may take seconds to exit
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0 and "connection dropped" in err


def test_emulate_grbl_stops_cleanly_on_sigterm():
    proc = _serve()
    try:
        assert proc.stdout.readline().startswith("/dev/")
    finally:
        out, err = _stop(proc, signal.SIGTERM)
    assert proc.returncode == 0 and "emulator: stopped" in err


def test_emulate_grbl_rejects_bad_travel():
    res = subprocess.run([*LPS, "emulate-grbl", "--travel", "5", "1"],
                         capture_output=True, text=True, timeout=30)
    assert res.returncode == 2 and "MIN_MM must be below MAX_MM" in res.stderr
