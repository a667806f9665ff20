"""A line-based controller's firmware served on a pseudo-terminal, whatever its protocol.

The pty is raw and non-blocking; a thread reads bytes into the firmware (a
:class:`LineFirmware`: GRBL's, Marlin's...), advances the simulated stage's
clock ``time_scale`` times faster than real time and writes what the firmware
says, line by line. With ``stepped=True`` simulated time moves only when the
caller says so (:meth:`LineEmulator.advance`): a test then decides when a move
ends or a reply arrives, and no outcome depends on how fast the machine runs
the test. :class:`LinkFaults` switches inject what goes wrong with any serial
link, in no protocol's terms: a port that vanishes after N received lines,
slow replies and lines of garbage bytes; a firmware adds its own (GRBL's
alarms, Marlin's spoiled checksums) in its own files. Tests flip them while
the emulator runs.

``line_latency_s`` delivers every line that long after the one before it (or
after it was printed), like a USB adapter's latency timer (16 ms on FTDI
chips): a report asked for before a real-time byte can then arrive after it.
Bytes are read at wire speed: each byte goes to the firmware as it arrives.
"""
from __future__ import annotations

import logging
import os
import select
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from lps_gui.core.clock import SimClock
from lps_gui.hardware.pty_device import PtyEndpoint
from lps_gui.hardware.sim_stage import SimulatedStage

log = logging.getLogger(__name__)

GARBAGE = b"\x00\xff\xfe#%\x07garbage\x1b[0m"  # what a noisy line or a board's reset prints


@dataclass
class LinkFaults:
    """Fault switches of any serial link (read on every step; flip them any time).

    drop_after_lines : close the port when this many lines were received (None: never): a vanished USB cable.
    reply_delay_s : delay everything the controller sends by this many real seconds.
    garbage_every : send a line of garbage bytes before every Nth message.
    """

    drop_after_lines: int | None = None
    reply_delay_s: float = 0.0
    garbage_every: int = 0

    def drops_at(self, lines_received: int) -> bool:
        """The cable goes with this received line."""
        return self.drop_after_lines is not None and lines_received >= self.drop_after_lines


class LineFirmware(Protocol):
    """A controller's firmware as the serving loop drives it: bytes in, lines out through its ``send``."""

    lines_received: int

    @property
    def busy(self) -> bool:
        """Something runs that needs the loop to turn fast (a move, a waiting line, a delay)."""

    def power_up(self) -> None:
        """What the controller prints when it boots."""

    def receive(self, b: int) -> None:
        """One byte from the host (its serial interrupt)."""

    def drain(self) -> None:
        """Take what the main loop takes between two bytes."""

    def poll(self) -> None:
        """The clock moved: run what executes, print what is due."""


class LinkedFirmware:
    """What every line firmware keeps of its link: the fault switches, where its lines go, and the cable.

    ``send(line)`` queues a line for the host; ``on_drop()`` closes the port (the drop fault); ``halted``
    is a firmware that answers nothing more (a dropped link, Marlin's kill()).
    """

    def __init__(self, faults: LinkFaults, send: Callable[[str], None], on_drop: Callable[[], None]) -> None:
        self.faults = faults
        self._send = send
        self._on_drop = on_drop
        self.halted = False

    def _cable_goes(self, lines_received: int) -> bool:
        """The link's drop fault: with this received line the port vanishes and the firmware stops (True)."""
        if not self.faults.drops_at(lines_received):
            return False
        log.info("emulator: dropping the connection (fault injection)")
        self.halted = True
        self._on_drop()
        return True


class LineEmulator(PtyEndpoint):
    """A :class:`LineFirmware` on a pty. ``start()`` returns the device path a serial client opens.

    A subclass builds ``self.firmware`` after this constructor, handing it
    ``send=self._send`` and ``on_drop=self._drop_now``.
    """

    firmware: LineFirmware

    def __init__(self, stage: SimulatedStage | None, faults: LinkFaults, time_scale: float = 1.0,
                 stepped: bool = False, line_latency_s: float = 0.0, name: str = "emulator") -> None:
        super().__init__(stage if stage is not None else SimulatedStage(), time_scale, name)
        self.faults = faults
        self.stepped = stepped
        self.line_latency_s = float(line_latency_s)
        if stepped and not isinstance(self.stage.clock, SimClock):
            raise ValueError(f"a stepped {name} needs a stage on a SimClock")
        self._lock = threading.RLock()  # the firmware is driven by the serving thread and by advance()
        self.bytes_in = 0  # bytes read from the port (a stepped test waits until its writes are in)
        self._out: list[tuple[float, float, bytes]] = []  # (wall due, due on _now(), bytes), in the order printed
        self._n_out = 0

    @property
    def lines_received(self) -> int:
        return self.firmware.lines_received

    # ------------------------------------------------------------------ lifecycle (PtyEndpoint)
    def _opened(self) -> None:
        """Power-up: what the firmware prints when it boots."""
        self.firmware.power_up()
        self._flush_out()

    @property
    def undelivered(self) -> list[str]:
        """Lines the firmware printed that the link has not delivered yet (latency, slow replies)."""
        with self._lock:
            return [data.decode("latin-1").rstrip("\r\n") for _, _, data in self._out]

    # ------------------------------------------------------------------ output
    def _now(self) -> float:
        """The link's clock: simulated time when stepped (a test decides when a line arrives), else wall time."""
        return self.stage.clock.now() if self.stepped else time.monotonic()

    def _send(self, text: str) -> None:
        """Queue a message (CR LF added) line by line: slow-reply delay (wall seconds), latency and garbage applied."""
        f = self.faults
        self._n_out += 1
        data = b""
        if f.garbage_every and self._n_out % f.garbage_every == 0:
            data += GARBAGE + b"\r\n"
        data += (text if text.endswith("\r\n") else text + "\r\n").encode("ascii")
        wall, now = time.monotonic(), self._now()
        for line in data.splitlines(keepends=True):
            wall_due, link_due = wall + f.reply_delay_s, now
            if self._out:
                wall_due, link_due = max(wall_due, self._out[-1][0]), max(link_due, self._out[-1][1])
            if self.line_latency_s > 0:
                link_due += self.line_latency_s
            self._out.append((wall_due, link_due, line))

    def _flush_out(self) -> None:
        wall, now = time.monotonic(), self._now()
        while self._out and self._out[0][0] <= wall and self._out[0][1] <= now and self._master >= 0:
            _, _, data = self._out.pop(0)
            try:
                os.write(self._master, data)
            except BlockingIOError:  # nobody reads the port: bytes are lost like on a wire
                log.debug("%s: output dropped (host not reading)", self.name)
            except OSError:
                return

    # ------------------------------------------------------------------ serving loop (PtyEndpoint._serve)
    def _step(self) -> None:
        busy = self.firmware.busy or bool(self._out)
        r, _, _ = select.select([self._master], [], [], 0.002 if busy else 0.02)
        with self._lock:
            if r:
                self._read_input()
            if not self.stepped:
                self._tick_clock()
            if self._running:
                self.firmware.poll()
            self._flush_out()

    def _read_input(self) -> None:
        """Feed every byte waiting on the pty to the firmware's serial interrupt."""
        while self._master >= 0:
            try:
                data = os.read(self._master, 4096)
            except OSError:  # EAGAIN (nothing left), EINTR, or the pty closing under us
                return
            if not data or self._unplugged_by(data):
                return
            self.bytes_in += len(data)
            for b in data:  # wire speed: the main loop keeps up with every byte unless a line executes
                self.firmware.receive(b)
                self.firmware.drain()

    def advance(self, seconds: float, step_s: float = 0.01) -> None:
        """Stepped clock: let ``seconds`` of simulated time pass, in steps of ``step_s``.

        Bytes already written to the port are read first; after every step the
        firmware runs (lines waiting for planner space, dwells, alarm delays) and
        its output is written, as the controller's main loop would between those instants.
        """
        if not self.stepped:
            raise RuntimeError(f"advance() needs {type(self).__name__}(stepped=True)")
        clock = self.stage.clock
        end = clock.now() + max(float(seconds), 0.0)
        with self._lock:
            while True:
                self._read_input()
                if self._running:
                    self.firmware.poll()
                self._flush_out()
                left = end - clock.now()
                if left <= 1e-12 or not self._running:
                    break
                clock.advance(min(step_s, left))

    def settle(self, until_bytes: int | None = None, limit_s: float = 10.0) -> None:
        """Stepped clock: read what was written and run the firmware once, without time passing.

        ``until_bytes``: first wait (``limit_s`` at most) until that many bytes came
        in since start: a pty may hand a write to the other side a moment later.
        """
        deadline = time.monotonic() + limit_s
        while until_bytes is not None and self.bytes_in < until_bytes and time.monotonic() < deadline:
            with self._lock:
                self._read_input()
            if self.bytes_in < until_bytes:
                time.sleep(0.001)
        self.advance(0.0)
