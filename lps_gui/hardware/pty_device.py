"""Serve an emulated controller on a pseudo-terminal, over the simulated stage, in scaled simulated time.

A vendor's library opens the pty's path as it opens a USB serial port.
:class:`PtyEndpoint` is what every emulator shares: the pty, the serving
thread, simulated time running ``time_scale`` times faster than real time
(a test's 50 mm move takes milliseconds and no outcome depends on timing),
and the cable that goes (:meth:`PtyEndpoint.drop`, the ``drop_when`` fault).
Line-based controllers (GRBL, Marlin, Zaber ASCII) are served by
:class:`~lps_gui.hardware.line_emulator.LineEmulator`; :class:`PtyServer`
serves a binary message protocol (Thorlabs' APT): every chunk it reads goes
to the protocol object (:class:`PtyProtocol`) and what that answers goes back.
"""
from __future__ import annotations

import logging
import os
import select
import threading
import time
import tty
from typing import Any, Callable, Protocol

from lps_gui.core.clock import SimClock
from lps_gui.errors import HardwareError
from lps_gui.hardware.sim_stage import SimulatedStage

log = logging.getLogger(__name__)


class PtyProtocol(Protocol):
    """A controller's protocol: bytes in, bytes out, and time passing."""

    received: int  # commands (lines, messages) received so far

    def receive(self, data: bytes) -> bytes:
        """Bytes from the host; returns the bytes the controller answers at once."""

    def poll(self) -> bytes:
        """The clock moved: what the controller says on its own (a move completed...)."""


class PtyEndpoint:
    """The pty and the serving thread of an emulated controller: open, serve, stop, or vanish like a cable.

    Subclasses implement :meth:`_step` (one turn of the serving loop) and may
    say what the controller prints on power-up in :meth:`_opened`.
    """

    def __init__(self, stage: SimulatedStage, time_scale: float = 1.0, name: str = "emulator") -> None:
        self.stage = stage
        self.time_scale = float(time_scale)
        self.name = name
        self.path = ""
        self.dropped = False
        self.drop_when: Callable[[bytes], bool] | None = None  # fault: drop the port when it returns True for received bytes
        self._master = self._slave = -1
        self._thread: threading.Thread | None = None
        self._running = False
        self._last_real = 0.0

    @property
    def running(self) -> bool:
        """The serving thread is up (False after stop, a drop, or a crash logged as an error)."""
        return self._running

    def start(self) -> str:
        """Open the pty, power the controller up, serve in a thread; return the slave's path."""
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        os.set_blocking(self._master, False)
        self.path = os.ttyname(self._slave)
        if not self.stage.connected:
            self.stage.connect()
        self._running = True
        self._last_real = time.monotonic()
        self._opened()
        self._thread = threading.Thread(target=self._serve, name=self.name, daemon=True)
        self._thread.start()
        return self.path

    def _opened(self) -> None:
        """What the controller does at power-up, before serving (nothing by default)."""

    def stop(self) -> None:
        self._running = False
        if self._thread is not None and threading.current_thread() is not self._thread:
            self._thread.join(timeout=2.0)
        self._close()

    def drop(self) -> None:
        """Vanish like an unplugged USB cable: close both ends of the pty."""
        self.dropped = True
        self.stop()

    def _drop_now(self) -> None:
        """Drop from inside the serving thread (fault injection)."""
        self.dropped = True
        self._running = False
        self._close()

    def _unplugged_by(self, data: bytes) -> bool:
        """The ``drop_when`` fault: the cable goes as these received bytes arrive (the controller never sees them)."""
        if self.drop_when is not None and self.drop_when(data):
            self._drop_now()
            return True
        return False

    def __enter__(self):
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _close(self) -> None:
        for fd in (self._master, self._slave):
            if fd >= 0:
                try:
                    os.close(fd)
                except OSError:
                    pass
        self._master = self._slave = -1

    def _serve(self) -> None:
        try:
            while self._running:
                self._step()
        except HardwareError as exc:  # the simulated stage vanished (SimulatedStage.disconnect_fault)
            log.info("%s: stage gone (%s); dropping the port", self.name, exc)
            self._drop_now()
        except Exception:  # an emulator bug shows in the log and stops serving: the client never hangs
            log.exception("%s stopped", self.name)
            self._running = False

    def _step(self) -> None:
        raise NotImplementedError

    def _tick_clock(self) -> None:
        """Simulated time follows real time, ``time_scale`` times faster (a stage on a real clock runs by itself)."""
        now = time.monotonic()
        if isinstance(self.stage.clock, SimClock):
            self.stage.clock.advance((now - self._last_real) * self.time_scale)
        self._last_real = now


class PtyServer(PtyEndpoint):
    """One controller speaking :class:`PtyProtocol` on a fresh pty; ``start()`` returns the path a client opens."""

    def __init__(self, protocol: PtyProtocol, stage: SimulatedStage, time_scale: float = 1.0, name: str = "emulator",
                 faults: Any = None) -> None:
        super().__init__(stage, time_scale, name)
        self.protocol = protocol
        # the link's drop fault (``lps emulate KIND --drop-after-lines N``, line_emulator.LinkFaults): the cable goes
        # when the Nth command arrives; a line firmware's own switches mean nothing to these controllers
        self.drop_after: int | None = getattr(faults, "drop_after_lines", None)
        self._lock = threading.RLock()

    def _step(self) -> None:
        r, _, _ = select.select([self._master], [], [], 0.002)
        with self._lock:
            self._tick_clock()
            out = self.protocol.poll()
            if r:
                data = self._read()
                if data:
                    if self._unplugged_by(data):
                        return
                    answer = self.protocol.receive(data)
                    if self.drop_after and self.protocol.received >= self.drop_after:
                        self._drop_now()
                        return
                    out += answer
            if out:
                self._write(out)

    def _read(self) -> bytes:
        chunks = []
        while self._master >= 0:
            try:
                data = os.read(self._master, 4096)
            except OSError:  # EAGAIN: nothing left
                break
            if not data:
                break
            chunks.append(data)
        return b"".join(chunks)

    def _write(self, data: bytes) -> None:
        try:
            os.write(self._master, data)
        except OSError:  # host not reading, or closing: lost like bytes on a wire
            log.debug("%s: output dropped", self.name)


def emulated_stage(driver_cls: type, emulator_cls: type, simulated: SimulatedStage | None = None,
                   stage_options: dict | None = None, **emulator_options):
    """A ``driver_cls`` connected to a fresh ``emulator_cls`` serving ``simulated`` (else a new
    :class:`SimulatedStage` from ``stage_options``; its ``clock`` is dropped: the emulator owns simulated time).

    The stage names the simulated stage it serves (``Stage.simulated``: the simulated camera renders its
    true pose, the rig seeds its draws through it); disconnecting stops the emulator.
    """
    options = dict(stage_options or {})
    options.pop("clock", None)
    served = simulated if simulated is not None else SimulatedStage(**options)
    server = emulator_cls(served, **emulator_options)
    path = server.start()

    class Emulated(driver_cls):
        emulator = server
        simulated = served

        def disconnect(self) -> None:
            try:
                super().disconnect()
            finally:
                server.stop()

        def describe(self) -> dict:
            return {**super().describe(), "emulated": served.describe()}

    Emulated.__name__ = Emulated.__qualname__ = f"Emulated{driver_cls.__name__}"
    stage = Emulated(path)
    try:
        stage.connect()
    except BaseException:
        server.stop()
        raise
    return stage
