"""A raw serial client for a stepped GRBL emulator: write bytes, run the firmware, read whole lines.

With ``GrblEmulator(stepped=True)`` simulated time stands still until the test
advances it, and :meth:`SteppedPort.send` makes the emulator read and execute
what was written before it returns, so every answer is already on the pty:
no test waits on wall-clock time for anything but bytes already sent.
"""
from __future__ import annotations

import threading
import time
from typing import Callable, TypeVar

import serial

from lps_gui.hardware.grbl.driver import GrblStage
from lps_gui.hardware.grbl.emulator import GrblEmulator

T = TypeVar("T")
READ_LIMIT_S = 10.0  # a bound against a hang, never a timing window: the bytes are already written


class SteppedPort:
    """pyserial on the emulator's pty, in step with the emulator's clock."""

    def __init__(self, emu: GrblEmulator) -> None:
        self.emu = emu
        self.ser = serial.Serial(emu.path, 115200, timeout=0.01)
        self.buf = b""
        self.sent = emu.bytes_in  # what the emulator will have read once our writes are in

    def send(self, data: bytes) -> None:
        """Write, then let the emulator read and execute it (no simulated time passes)."""
        self.ser.write(data)
        self.ser.flush()
        self.sent += len(data)
        self.emu.settle(until_bytes=self.sent)

    def advance(self, seconds: float) -> None:
        self.emu.advance(seconds)

    def lines(self, n: int) -> list[str]:
        """The next ``n`` lines GRBL sent (CR LF stripped)."""
        out: list[str] = []
        deadline = time.monotonic() + READ_LIMIT_S
        while len(out) < n:
            while b"\r\n" in self.buf and len(out) < n:
                raw, self.buf = self.buf.split(b"\r\n", 1)
                out.append(raw.decode("latin-1"))
            if len(out) >= n:
                break
            if time.monotonic() > deadline:
                raise AssertionError(f"only {len(out)} of {n} lines: {out}")
            self.buf += self.ser.read(256)
        return out

    def pending(self) -> list[str]:
        """Every complete line already sent (the emulator flushed before :meth:`send` returned)."""
        self.emu.settle()
        self.buf += self.ser.read(4096)
        while self.ser.in_waiting:
            self.buf += self.ser.read(4096)
        out = []
        while b"\r\n" in self.buf:
            raw, self.buf = self.buf.split(b"\r\n", 1)
            out.append(raw.decode("latin-1"))
        return out

    def ask(self, data: bytes, n: int = 1) -> list[str]:
        self.send(data)
        return self.lines(n)

    def close(self) -> None:
        self.ser.close()


class Background:
    """A driver call left waiting in a thread while the test looks at it and moves time on."""

    def __init__(self, fn: Callable[[], object]) -> None:
        self.errors: list[BaseException] = []
        self.result: list = []
        self.thread = threading.Thread(target=self._run, args=(fn,), daemon=True)
        self.thread.start()

    def _run(self, fn: Callable[[], object]) -> None:
        try:
            self.result.append(fn())
        except BaseException as exc:  # noqa: BLE001 - re-raised by finish() or read by the test
            self.errors.append(exc)

    def waiting(self) -> bool:
        return self.thread.is_alive() and not self.errors

    def finish(self, emu: GrblEmulator, sim_step_s: float = 0.5, limit_s: float = 120.0):
        """Advance simulated time in ``sim_step_s`` steps until the call returns; return or raise what it did.

        ``limit_s`` (wall) only stops a hang.
        """
        deadline = time.monotonic() + limit_s
        while self.thread.is_alive():
            if time.monotonic() > deadline:
                raise AssertionError(f"still waiting after {limit_s:g} s of wall time")
            emu.advance(sim_step_s)
            self.thread.join(0.002)
        if self.errors:
            raise self.errors[0]
        return self.result[0]


def drive(emu: GrblEmulator, fn: Callable[[], T], sim_step_s: float = 0.5, limit_s: float = 120.0) -> T:
    """Run ``fn()`` (a driver call that waits on motion) while simulated time advances; its result or error."""
    return Background(fn).finish(emu, sim_step_s, limit_s)


class SteppedGrblStage(GrblStage):
    """A GrblStage on a stepped emulator whose waiting calls move simulated time on (via :func:`drive`).

    Between calls the emulator's clock stands still, so a move just acknowledged
    is still at its start when the next line, hold or cancel arrives.
    """

    emulator: GrblEmulator

    def wait_idle(self, timeout_s: float = 60.0):
        return drive(self.emulator, lambda: GrblStage.wait_idle(self, timeout_s=timeout_s))

    def home(self) -> None:
        drive(self.emulator, lambda: GrblStage.home(self), sim_step_s=0.1)

    def soft_reset(self) -> None:
        drive(self.emulator, lambda: GrblStage.soft_reset(self))


def stepped_stage(emu: GrblEmulator, **options) -> SteppedGrblStage:
    stage = SteppedGrblStage(emu.path, **options)
    stage.emulator = emu
    return stage
