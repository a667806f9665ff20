"""GrblStage against the races a real board's link produces (issue 39, driver defects 1-4).

The emulator is made to time its output as a real board's does: every line
arrives ``LATENCY_S`` after the one before it (a USB adapter's latency timer),
and with ``boot_race`` the board boots as the port opens, so the boot banner
comes first and the banner of the driver's reset after it. The emulator's clock
is stepped and its link delivers lines on that clock, so each test decides the
order: a reply stays on its way until the test has seen the driver write what
it writes next (``emu.bytes_in``), then time moves on. Wall-clock waits only
bound a hang or outlast the driver's own reply timeout.
"""
from __future__ import annotations

import contextlib
import time

import pytest

from lps_gui.errors import HardwareError
from lps_gui.hardware.grbl.driver import GrblStage
from lps_gui.hardware.grbl.emulator import GrblEmulator
from lps_gui.hardware.sim_stage import SimulatedStage

from tests.hardware.grbl_port import Background, drive

LATENCY_S = 0.016  # FTDI's default latency timer
LIMIT_S = 20.0  # wall seconds: only stops a hang


def _wait_bytes(emu: GrblEmulator, n: int) -> None:
    """Until the emulator has read ``n`` bytes since it started (the driver wrote them)."""
    deadline = time.monotonic() + LIMIT_S
    while emu.bytes_in < n:
        assert time.monotonic() < deadline, f"the driver wrote {emu.bytes_in} bytes, not {n}"
        time.sleep(0.002)


@contextlib.contextmanager
def _rig(timeout_s: float = 2.0, boot_race: bool = False, connect: bool = True):
    """A stepped emulator and a driver; the latency starts after ``connect`` (defects 2-4 are not about connecting)."""
    emu = GrblEmulator(SimulatedStage(travel_mm=(0.0, 100.0), start_mm=10.0), stepped=True,
                       line_latency_s=0.0 if connect else LATENCY_S, boot_race=boot_race)
    emu.start()
    stage = GrblStage(emu.path, timeout_s=timeout_s, poll_interval_s=0.01)
    try:
        if connect:
            drive(emu, stage.connect, sim_step_s=0.05)
            emu.line_latency_s = LATENCY_S
        yield emu, stage
    finally:
        stage.disconnect()
        emu.stop()


def test_connect_pairs_replies_after_a_boot_banner_and_the_reset_banner():
    """Defect 1: the boot banner, then the reset's banner; a line sent in between is still answered."""
    with _rig(boot_race=True, connect=False) as (emu, stage):
        connecting = Background(stage.connect)
        _wait_bytes(emu, 1)  # the driver's reset byte
        emu.settle()  # the board prints its boot banner, then acts on the reset: a second banner
        assert emu.undelivered == ["", "Grbl 1.1h ['$' for help]"] * 2
        emu.advance(2 * LATENCY_S + 0.005)  # the boot banner is in, the reset's is still on its way
        # the driver may already have answered the boot banner (a loaded machine runs its thread first): whatever
        # it asked is answered after the reset's banner, which must still be first in line
        assert emu.undelivered[:2] == ["", "Grbl 1.1h ['$' for help]"]
        _wait_bytes(emu, 2)  # what the driver sends next goes out before the second banner arrives
        connecting.finish(emu, sim_step_s=0.05, limit_s=LIMIT_S)
        assert stage.build_info is not None and stage.build_info.version.startswith("1.1h")
        assert stage.settings and stage.settings[130] == pytest.approx(100.0)
        assert any(ln.startswith("[GC:G0 G54") for ln in drive(emu, lambda: stage.command("$G")))


def test_a_report_asked_before_the_hold_does_not_end_it():
    """Defect 2: a report produced before GRBL acted on '!' arrives after it; the next line is refused."""
    with _rig() as (emu, stage):
        stage.realtime(b"?")  # another thread's poll: its Idle report is on its way when '!' goes out
        drive(emu, stage.feed_hold, sim_step_s=0.01, limit_s=LIMIT_S)
        emu.advance(0.1)  # everything in flight arrives
        assert emu.stage.status().state == "Hold"
        with pytest.raises(HardwareError, match="is in a feed hold"):
            drive(emu, lambda: stage.command("G4 P0"), limit_s=10.0)


def test_a_reply_that_arrives_while_asking_status_after_the_timeout_is_taken():
    """Defect 3: the ok is on its way when the reply deadline passes; the '?' asked then must not call GRBL dead."""
    with _rig(timeout_s=0.3) as (emu, stage):
        before = emu.bytes_in
        dwell = Background(lambda: stage.command("G4 P0"))
        _wait_bytes(emu, before + len(b"G4 P0\n"))
        emu.settle()
        assert emu.undelivered[0] == "ok"  # GRBL answered at once; the link holds it
        _wait_bytes(emu, before + len(b"G4 P0\n") + 1)  # the deadline passed: the driver asks '?'
        emu.settle()
        assert emu.undelivered[0] == "ok" and emu.undelivered[1].startswith("<Idle|")
        assert dwell.finish(emu, sim_step_s=0.05, limit_s=LIMIT_S) == []


def test_resume_waits_until_grbl_leaves_the_hold():
    """Defect 4: a report asked before '~' says Hold; a command right after resume() must not be refused."""
    with _rig() as (emu, stage):
        drive(emu, stage.feed_hold, sim_step_s=0.01, limit_s=LIMIT_S)
        emu.advance(0.1)
        before = emu.bytes_in
        stage.realtime(b"?")  # a poll whose Hold report is on its way when '~' goes out
        resuming = Background(stage.resume)
        _wait_bytes(emu, before + 2)  # '?' and '~' are in
        commanding = Background(lambda: (resuming.thread.join(LIMIT_S), stage.command("G4 P0"))[1])
        _wait_bytes(emu, before + 3)  # the next '?' (resume's, or the command's hold check) is in too
        resuming.finish(emu, sim_step_s=0.02, limit_s=LIMIT_S)
        assert commanding.finish(emu, sim_step_s=0.02, limit_s=LIMIT_S) == []
        assert emu.stage.status().state == "Idle"
