"""Scripted serial port for protocol tests (PyMeasure's ``expected_protocol`` pattern).

A test lists (sent, reply) byte pairs; the fake port checks every write against
the next expected one, answers with its reply, and at the end every pair must
have been used and nothing unexpected written.
"""
from __future__ import annotations

import threading
from contextlib import contextmanager
from typing import Iterator

import serial

from lps_gui.hardware.grbl.driver import GrblStage

BANNER = b"\r\nGrbl 1.1h ['$' for help]\r\n"
VERSION = b"[VER:1.1h.20190830:]\r\n[OPT:V,15,128]\r\nok\r\n"
SETTINGS = (
    b"$0=10\r\n$1=25\r\n$10=1\r\n$13=0\r\n$20=1\r\n$22=1\r\n$110=3000.000\r\n$120=200.000\r\n$130=505.000\r\nok\r\n"
)
IDLE = b"<Idle|MPos:-500.000,0.000,0.000|FS:0,0|WCO:-500.000,0.000,0.000>\r\n"
CONNECT = [(b"\x18", BANNER), (b"?", IDLE), (b"$I\n", VERSION), (b"$$\n", SETTINGS), (b"?", IDLE)]


class ScriptedSerial:
    """A pyserial stand-in replaying (sent, reply) pairs in order."""

    def __init__(self, pairs: list[tuple[bytes, bytes]]) -> None:
        self.pairs = list(pairs)
        self.errors: list[str] = []
        self.written: list[bytes] = []
        self.port = "scripted"
        self.is_open = True
        self._rx = bytearray()
        self._cond = threading.Condition()
        self.broken = False

    def open(self) -> None:
        self.is_open = True

    def close(self) -> None:
        self.is_open = False

    def reset_input_buffer(self) -> None:
        with self._cond:
            self._rx.clear()

    @property
    def in_waiting(self) -> int:
        return len(self._rx)

    def push(self, data: bytes) -> None:
        """Bytes the controller sends on its own (push messages)."""
        with self._cond:
            self._rx += data
            self._cond.notify_all()

    def write(self, data: bytes) -> int:
        if self.broken:
            raise serial.SerialException("write failed: [Errno 5] Input/output error")
        with self._cond:
            self.written.append(data)
            if not self.pairs:
                self.errors.append(f"unexpected write {data!r} after the script ended")
                return len(data)
            sent, reply = self.pairs[0]
            if data != sent:
                self.errors.append(f"expected {sent!r}, got {data!r}")
                return len(data)
            self.pairs.pop(0)
            self._rx += reply
            self._cond.notify_all()
        return len(data)

    def fail(self) -> None:
        """Make the port vanish: reads and writes raise like an unplugged USB adapter."""
        self.broken = True

    def read(self, n: int = 1) -> bytes:
        if self.broken:
            raise serial.SerialException("device reports readiness to read but returned no data")
        with self._cond:
            if not self._rx:
                self._cond.wait(0.02)
            out = bytes(self._rx[:n])
            del self._rx[:n]
            return out


@contextmanager
def expected_protocol(pairs: list[tuple[bytes, bytes]], connect: bool = True, **kw) -> Iterator[tuple[GrblStage, ScriptedSerial]]:
    """A connected GrblStage on a scripted port; asserts afterwards that the script was followed exactly."""
    fake = ScriptedSerial((CONNECT if connect else []) + list(pairs))
    stage = GrblStage(fake, timeout_s=kw.pop("timeout_s", 1.0), poll_interval_s=kw.pop("poll_interval_s", 0.001), **kw)
    if connect:
        stage.connect()
    try:
        yield stage, fake
    finally:
        stage.link.close()
    assert not fake.errors, fake.errors
    assert not fake.pairs, f"unused script pairs: {fake.pairs}"
