"""The serial link to a GRBL controller: a reader thread, answers matched to lines, character counting.

Transport apart from protocol (PyMeasure's ``adapters/serial.py`` habit): the
link opens a port name/URL with ``serial.serial_for_url`` or uses an
already-open pyserial-like object (an emulator's pty, a scripted fake).

GRBL answers every line with exactly one ``ok`` or ``error:N``, in order, so
the link keeps the unanswered lines in a FIFO: an answer completes the
oldest, push lines printed before it (``[VER:]``, ``$N=``, ``[MSG:]``...) are
collected for it. A line an alarm cut short still gets its answer from GRBL
(the abort returns through the main loop, which prints ``ok``, before the
reset banner): it stays in the FIFO as an *orphan* whose waiter was already
failed, so that ``ok`` is not credited to the next line. Lines go out only while the unanswered bytes (with their
``\\n``) fit in GRBL's RX buffer minus one (GRBL's ``stream.py`` rule), so a
stream keeps the planner full without overrunning the controller. Every wait
has a deadline; a read or write failure marks the link dead with a one-line
:class:`HardwareError` that every later call raises.
"""
from __future__ import annotations

import collections
import logging
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import serial

from lps_gui.errors import HardwareError, InputError
from lps_gui.hardware.grbl.codes import GrblError
from lps_gui.hardware.grbl.protocol import Message, classify, dwell_seconds

log = logging.getLogger(__name__)
MAX_LINE_BYTES = 80  # GRBL's LINE_BUFFER_SIZE


class ControllerReset(HardwareError):
    """GRBL printed its banner (it reset) while a line waited for its answer."""


@dataclass
class Pending:
    """A sent line waiting for its ``ok``/``error:N``; push lines in between are collected."""

    line: str
    nbytes: int
    done: threading.Event = field(default_factory=threading.Event)
    lines: list[str] = field(default_factory=list)
    error: Exception | None = None
    orphan: bool = False  # failed early (an alarm); its late answer is swallowed
    dwell_s: float = 0.0  # a G4's P: GRBL answers it that long after the planner empties


class GrblLink:
    """Lines to GRBL and answers back over one serial port.

    ``on_message(Message)`` receives everything that is not an answer (status
    reports, alarms, banners, messages) on the reader thread; it must not block.
    """

    def __init__(self, port: Any, baudrate: int, timeout_s: float, on_message: Callable[[Message], None]) -> None:
        self.port = port
        self.port_name = port if isinstance(port, str) else str(getattr(port, "port", None) or repr(port))
        self.baudrate = baudrate
        self.timeout_s = timeout_s
        self.rx_size = 128  # GRBL's RX buffer (bytes); updated from $I
        self.garbage_lines = 0
        self.cond = threading.Condition()  # guards the FIFO; also wakes waiters of on_message state
        self._on_message = on_message
        self._serial: Any = None
        self._reader: threading.Thread | None = None
        self._stop = threading.Event()
        self._write_lock = threading.Lock()
        self._pending: collections.deque[Pending] = collections.deque()
        self._rx_used = 0
        self.dead: HardwareError | None = None

    # ------------------------------------------------------------------ open / close
    def open(self) -> None:
        """Open the port (or take the given object) and start the reader thread."""
        try:
            if isinstance(self.port, str):
                self._serial = serial.serial_for_url(self.port, baudrate=self.baudrate, timeout=0.05, write_timeout=self.timeout_s)
            else:
                self._serial = self.port
                if not self._serial.is_open:
                    self._serial.open()
            self._serial.reset_input_buffer()
        except (serial.SerialException, OSError, ValueError) as exc:
            raise HardwareError(f"GRBL: cannot open port {self.port_name!r} ({exc}); check the cable and the port name") from None
        self.dead = None
        self._stop.clear()
        self.fail_pending(None)
        self._reader = threading.Thread(target=self._read_loop, name=f"grbl-reader {self.port_name}", daemon=True)
        self._reader.start()

    def close(self) -> None:
        """Stop the reader, close a port we opened, fail what is in flight."""
        self._stop.set()
        if self._reader is not None and self._reader is not threading.current_thread():
            self._reader.join(timeout=1.0)
        if self._serial is not None and isinstance(self.port, str):
            try:
                self._serial.close()
            except Exception:  # closing a vanished port may fail; it is gone either way
                pass
        self.fail_pending(HardwareError(f"GRBL on {self.port_name}: disconnected"))
        if self.dead is None:
            self.dead = HardwareError(f"GRBL on {self.port_name}: not connected; connect the stage first")

    @property
    def alive(self) -> bool:
        return self._reader is not None and self._reader.is_alive() and self.dead is None

    @property
    def in_flight(self) -> int:
        """Lines sent and not yet answered."""
        return len(self._pending)

    def dwell_in_flight_s(self) -> float:
        """Seconds of G4 dwell among the unanswered lines."""
        with self.cond:
            return sum(p.dwell_s for p in self._pending if not p.done.is_set())

    @property
    def rx_used(self) -> int:
        """Bytes of unanswered lines (what GRBL's RX buffer may still hold)."""
        return self._rx_used

    # ------------------------------------------------------------------ reading
    def _read_loop(self) -> None:
        buf = bytearray()
        ser = self._serial
        while not self._stop.is_set():
            try:
                data = ser.read(max(1, ser.in_waiting))
            except Exception as exc:  # SerialException, OSError (EIO), TypeError on a closed fd
                if not self._stop.is_set():
                    self.vanished(exc)
                return
            buf += data
            if len(buf) > 4 * MAX_LINE_BYTES and b"\n" not in buf and b"\r" not in buf:
                self.garbage_lines += 1  # no line end for a long while: noise or a wrong baud rate
                log.warning("GRBL: %d bytes without a line end dropped", len(buf))
                buf.clear()
            while True:
                ends = [k for k in (buf.find(b"\n"), buf.find(b"\r")) if k >= 0]
                if not ends:
                    break
                raw = bytes(buf[: min(ends)])
                del buf[: min(ends) + 1]
                line = raw.decode("ascii", errors="replace").strip()
                if line:
                    try:
                        self._dispatch(line)
                    except Exception:  # a handler bug must not kill the reader
                        log.exception("GRBL: failed to handle %r", line)

    def _dispatch(self, line: str) -> None:
        log.debug("GRBL << %r", line)
        msg = classify(line)
        if msg.kind in ("ok", "error"):
            with self.cond:
                if not self._pending:
                    log.warning("GRBL: %r with no command in flight; ignored", line)
                    return
                p = self._pending.popleft()
                self._rx_used -= p.nbytes
                if p.orphan:
                    log.info("GRBL: %r answers %r, which an alarm cut short; not credited to a later line", line, p.line)
                    self.cond.notify_all()
                    return
                if msg.kind == "error":
                    p.error = GrblError("error", int(msg.code), f"GRBL rejected {p.line!r}")
                p.done.set()
                self.cond.notify_all()
            if msg.kind == "error":
                self._on_message(msg._replace(text=str(p.error)))
            return
        if msg.kind in ("msg", "feedback", "setting", "startup"):
            with self.cond:
                if self._pending:
                    self._pending[0].lines.append(line)
        elif msg.kind == "unknown":
            self.garbage_lines += 1
            log.warning("GRBL: unrecognized line %r ignored", line)
            return
        self._on_message(msg)

    def vanished(self, exc: BaseException) -> None:
        """The port failed: every waiter and every later call gets one clear error."""
        self.dead = HardwareError(f"GRBL on {self.port_name}: the port vanished ({exc}); reconnect the stage and resume")
        self.fail_pending(self.dead)
        self._on_message(Message("disconnected", text=str(self.dead)))

    def fail_pending(self, err: Exception | None) -> None:
        """Complete every unanswered line with ``err`` (a reset, a lost port), forget them, free the RX budget."""
        with self.cond:
            while self._pending:
                p = self._pending.popleft()
                if not p.done.is_set():
                    p.error = err or HardwareError(f"GRBL on {self.port_name}: line {p.line!r} lost")
                    p.done.set()
            self._rx_used = 0
            self.cond.notify_all()

    def orphan_pending(self, err: Exception) -> None:
        """Fail every waiter with ``err`` (an alarm) but keep the lines: GRBL still answers them, or resets."""
        with self.cond:
            for p in self._pending:
                if not p.done.is_set():
                    p.error, p.orphan = err, True
                    p.done.set()
            self.cond.notify_all()

    # ------------------------------------------------------------------ writing
    def write(self, data: bytes) -> None:
        """Write raw bytes (a line, or a real-time byte that is never counted)."""
        if self.dead is not None:
            raise self.dead
        try:
            with self._write_lock:
                self._serial.write(data)
        except Exception as exc:
            self.vanished(exc)
            raise self.dead from None

    def wait_for(self, predicate: Callable[[], bool], timeout_s: float, what: str,
                 retry: Callable[[], None] | None = None, retry_every_s: float = 0.25) -> None:
        """Block until ``predicate()`` (checked under :attr:`cond`) or raise with ``what`` after ``timeout_s``.

        ``retry`` (called outside the lock every ``retry_every_s``) re-sends what a
        reset may have swallowed, e.g. a ``?``.
        """
        deadline = time.monotonic() + timeout_s
        next_retry = time.monotonic() + retry_every_s
        while True:
            with self.cond:
                while not predicate():
                    if self.dead is not None:
                        raise self.dead
                    now = time.monotonic()
                    if now >= deadline:
                        raise HardwareError(f"GRBL on {self.port_name}: {what}")
                    if retry is not None and now >= next_retry:
                        break
                    self.cond.wait(min(deadline - now, next_retry - now if retry else 0.1, 0.1))
                else:
                    return
            retry()
            next_retry = time.monotonic() + retry_every_s

    def send(self, line: str, timeout_s: float | None = None,
             keep_waiting: Callable[[], bool] | None = None) -> Pending:
        """Queue a line within the RX-buffer budget (character counting); return without its answer.

        While the buffer stays full past the deadline, ``keep_waiting()`` may
        extend it (GRBL reads no line while its planner is full, which is no fault).
        """
        data = (line.strip() + "\n").encode("ascii")
        if len(data) > min(self.rx_size - 1, MAX_LINE_BYTES):
            raise InputError(f"GRBL line too long ({len(data)} bytes > {MAX_LINE_BYTES}): {line!r}")
        timeout_s = self.timeout_s if timeout_s is None else timeout_s
        def fits() -> bool:
            return self._rx_used + len(data) <= self.rx_size - 1

        while True:
            try:
                self.wait_for(fits, timeout_s, f"RX buffer still full after {timeout_s:g} s; the controller stopped answering")
                break
            except HardwareError:
                if self.dead is not None:
                    raise
                if keep_waiting is None or not keep_waiting():
                    if fits():  # an answer came while keep_waiting() asked '?'
                        break
                    raise
        p = Pending(line.strip(), len(data), dwell_s=dwell_seconds(line))
        with self.cond:
            self._pending.append(p)
            self._rx_used += len(data)
        self.write(data)
        return p

    def wait_reply(self, p: Pending, timeout_s: float | None = None,
                   keep_waiting: Callable[[], bool] | None = None) -> list[str]:
        """Wait for the answer of a sent line; return its push lines or raise GrblError/HardwareError.

        When the deadline passes, ``keep_waiting()`` may extend it (a feed hold:
        GRBL answers no line until ``~``, which is no cable fault). The answer
        may arrive while ``keep_waiting()`` asks GRBL (its ``?`` is answered after
        the ``ok`` already on its way), so it is looked for once more before failing.
        """
        timeout_s = self.timeout_s if timeout_s is None else timeout_s
        while not p.done.wait(timeout_s):
            if self.dead is not None:
                raise self.dead
            if keep_waiting is not None and keep_waiting():
                continue
            if p.done.is_set():
                break
            raise HardwareError(
                f"GRBL on {self.port_name}: no reply to {p.line!r} within {timeout_s:g} s; check the cable or reset the controller"
            )
        if p.error is not None:
            raise p.error
        return p.lines
