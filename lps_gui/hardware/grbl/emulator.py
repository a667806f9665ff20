"""A GRBL 1.1 controller on a pseudo-terminal: :class:`GrblFirmware` served over a pty.

The pty is raw and non-blocking; a thread reads bytes into the firmware,
advances the simulated stage's clock ``time_scale`` times faster than real
time (``lps emulate-grbl`` defaults to 1x, GRBL's own timing) and writes what
the firmware says. With ``stepped=True`` simulated time moves only when the
caller says so (:meth:`GrblEmulator.advance`): a test then decides when a move
ends, an alarm's 500 ms pass or a hold completes, and no outcome depends on
how fast the machine runs the test. :class:`Faults` switches inject what goes
wrong with real hardware: a dropped connection, an alarm in the middle of a
move, error replies, slow replies and garbage bytes; tests flip them while
the emulator runs.

Two transport switches reproduce what a real board's link does to timing:
``line_latency_s`` delivers every line that long after the one before it (or
after it was printed), like a USB adapter's latency timer (16 ms on FTDI
chips): a report asked for before a real-time byte can then arrive after it.
``boot_race=True`` is a board that boots as the port opens (an Arduino's DTR
reset): the host's first reset byte arrives during GRBL's init, so the boot
banner comes first and the reset's banner after it (main.c enables the serial
interrupt before ``report_init_message()``). Bytes are read at wire speed:
GRBL's main loop takes each byte out of the 128-byte RX buffer as it arrives,
so only bytes that come while a line executes fill it.
"""
from __future__ import annotations

import logging
import os
import select
import threading
import time

from lps_gui.core.clock import SimClock
from lps_gui.hardware.grbl.firmware import BANNER, Faults, GrblFirmware
from lps_gui.hardware.pty_device import PtyEndpoint, emulated_stage
from lps_gui.hardware.sim_stage import SimulatedStage

log = logging.getLogger(__name__)

GARBAGE = b"\x00\xff\xfe#%\x07garbage\x1b[0m"
__all__ = ["BANNER", "Faults", "GrblEmulator", "emulated_grbl_stage"]


class GrblEmulator(PtyEndpoint):
    """GRBL 1.1 on a pty. ``start()`` returns the device path a serial client opens.

    Use as a context manager in tests: ``with GrblEmulator(...) as emu: GrblStage(emu.path)``.
    ``firmware`` holds GRBL's state; ``stage`` is the simulated stage that moves.
    ``homing_init_lock=True`` is stock GRBL 1.1h (config.h HOMING_INIT_LOCK): with
    ``$22=1`` it powers up in Alarm. The default (off, ``[OPT:VL,...]``) keeps the
    in-process rigs of tests and demos unlocked; ``lps emulate-grbl`` is stock.
    """

    firmware_class: type = GrblFirmware  # what answers on the pty (another controller's emulator names its own)

    def __init__(self, stage: SimulatedStage | None = None, faults: Faults | None = None, time_scale: float = 1.0,
                 homing_init_lock: bool = False, stepped: bool = False, line_latency_s: float = 0.0,
                 boot_race: bool = False) -> None:
        super().__init__(stage if stage is not None else SimulatedStage(), time_scale, "grbl-emulator")
        self.faults = faults or Faults()
        self.stepped = stepped
        self.line_latency_s = float(line_latency_s)
        self.boot_race = boot_race
        if stepped and not isinstance(self.stage.clock, SimClock):
            raise ValueError("a stepped GRBL emulator needs a stage on a SimClock")
        self._lock = threading.RLock()  # the firmware is driven by the serving thread and by advance()
        self.bytes_in = 0  # bytes read from the port (a stepped test waits until its writes are in)
        self.firmware = self.firmware_class(self.stage, self.faults, send=self._send, on_drop=self._drop_now,
                                     homing_init_lock=homing_init_lock)
        self._out: list[tuple[float, float, bytes]] = []  # (wall due, due on _now(), bytes), in the order GRBL printed them
        self._n_out = 0

    @property
    def rx_overflow_bytes(self) -> int:
        """Bytes GRBL dropped because the host overran its RX buffer (0 for a correct host)."""
        return self.firmware.rx_overflow_bytes

    @property
    def lines_received(self) -> int:
        return self.firmware.lines_received

    # ------------------------------------------------------------------ lifecycle (hardware/pty_device.PtyEndpoint)
    def _opened(self) -> None:
        """Power-up: the homing lock (if built with it), then the welcome (twice with the boot race)."""
        self.firmware.power_up(boot_race=self.boot_race)
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
                log.debug("emulator output dropped (host not reading)")
            except OSError:
                return

    # ------------------------------------------------------------------ serving loop (PtyEndpoint._serve)
    def _step(self) -> None:
        busy = self.firmware.busy or bool(self._out)
        r, _, _ = select.select([self._master], [], [], 0.002 if busy else 0.02)
        with self._lock:
            if r:
                self._read_input()
            now = time.monotonic()
            if isinstance(self.stage.clock, SimClock) and not self.stepped:
                self.stage.clock.advance((now - self._last_real) * self.time_scale)
            self._last_real = now
            if self._running:
                self.firmware.poll()
            self._flush_out()

    def _read_input(self) -> None:
        """Feed every byte waiting on the pty to the firmware's serial ISR."""
        while self._master >= 0:
            try:
                data = os.read(self._master, 4096)
            except OSError:  # EAGAIN (nothing left), EINTR, or the pty closing under us
                return
            if not data:
                return
            self.bytes_in += len(data)
            for b in data:  # wire speed: the main loop keeps up with every byte unless a line executes
                self.firmware.receive(b)
                self.firmware.drain()

    def advance(self, seconds: float, step_s: float = 0.01) -> None:
        """Stepped clock: let ``seconds`` of simulated time pass, in steps of ``step_s``.

        Bytes already written to the port are read first; after every step the
        firmware runs (lines waiting for planner space, dwells, alarm delays) and
        its output is written, as GRBL's main loop would between those instants.
        """
        if not self.stepped:
            raise RuntimeError("advance() needs GrblEmulator(stepped=True)")
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


def emulated_grbl_stage(time_scale: float = 1.0, faults: Faults | None = None, simulated: SimulatedStage | None = None,
                        **stage_options):
    """A :class:`GrblStage` connected to a fresh emulator (``open_stage("emulator")``).

    The emulator serves ``simulated`` (e.g. the simulated rig's stage, whose
    true pose a simulated camera renders), else a new :class:`SimulatedStage`
    built from ``stage_options`` (``clock`` is replaced: the emulator owns
    simulated time). The returned stage names the simulated stage it serves
    (``Stage.simulated``: a simulated rig's hook seeds its draws through the
    driver) and stops the emulator when it disconnects.
    """
    from lps_gui.hardware.grbl.driver import GrblStage

    return emulated_stage(GrblStage, GrblEmulator, simulated, stage_options, faults=faults, time_scale=time_scale)
