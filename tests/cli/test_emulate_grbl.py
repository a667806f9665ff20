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


def _parsed(*argv: str):
    import argparse

    from lps_gui.cli import emulate_grbl

    parser = argparse.ArgumentParser()
    emulate_grbl.add_arguments(parser)
    return parser.parse_args(list(argv))


def test_link_timing_switches_reach_the_grbl_emulator_and_no_other_kind():
    from lps_gui.cli.emulate_grbl import build_emulator

    emu = build_emulator(_parsed("--line-latency", "16", "--boot-race"), "grbl")
    assert emu.line_latency_s == pytest.approx(0.016) and emu.boot_race
    plain = build_emulator(_parsed(), "grbl")
    assert plain.line_latency_s == 0.0 and not plain.boot_race
    build_emulator(_parsed("--line-latency", "16", "--boot-race"), "marlin")  # Marlin takes whole lines: ignored


def test_line_latency_is_refused_outside_its_range():
    res = subprocess.run([*LPS, "emulate-grbl", "--line-latency", "-1"], capture_output=True, text=True, timeout=30)
    assert res.returncode == 2 and "--line-latency: must be at least 0" in res.stderr


def _read_until(fd: int, needle: bytes, count: int, timeout_s: float = 30.0) -> bytes:
    """Bytes from the pty until ``needle`` was seen ``count`` times (bounded: never a hang)."""
    import os
    import select
    import time

    got, end = b"", time.monotonic() + timeout_s
    while got.count(needle) < count and time.monotonic() < end:
        if select.select([fd], [], [], 0.1)[0]:
            got += os.read(fd, 4096)
    return got


def test_emulate_grbl_boot_race_banners_after_the_hosts_first_byte_and_the_driver_connects():
    import os
    import select
    import tty

    proc = _serve("--boot-race", "--line-latency", "16")
    try:
        path = proc.stdout.readline().strip()
        fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
        try:
            tty.setraw(fd)
            assert not select.select([fd], [], [], 0.3)[0]  # booting: a board that booted already would have spoken
            os.write(fd, b"\x18")  # the host's reset byte during the boot: the boot banner, then the reset's
            assert _read_until(fd, b"Grbl 1.1h", 2).count(b"Grbl 1.1h") == 2
        finally:
            os.close(fd)
        stage = GrblStage(path, timeout_s=5.0, poll_interval_s=0.01)
        stage.connect()
        assert stage.settings and stage.status().state in ("Idle", "Alarm")
        stage.disconnect()
    finally:
        out, err = _stop(proc, signal.SIGINT)
    assert proc.returncode == 0, err
