"""A stage the operator moves by hand: each move shows the nominal position and waits for "moved".

For a stage with no motor or no interface (a micrometer slide, a rail with
a ruler): the capture engine asks for a position, the operator brings the
carriage there and confirms; the position read back is the one confirmed.
In the GUI the panel's Moved button confirms (:meth:`ManualStage.confirm_moved`);
on a terminal the CLI attaches a prompt (:meth:`ManualStage.attach_prompt`)
that reads a line. Declares :class:`~lps_gui.hardware.capabilities.OperatorMoved`.
"""
from __future__ import annotations

import threading
from typing import Callable

from lps_gui.errors import HardwareError
from lps_gui.hardware.capabilities import OperatorMoved
from lps_gui.hardware.stage import StageEvent, StageStatus
from lps_gui.hardware.told_position import ToldPositionStage


class ManualStage(ToldPositionStage, OperatorMoved):
    """Positions are what the operator confirmed; nothing moves by itself."""

    name = "manual stage"

    def __init__(self, axis: str = "X", start_mm: float = 0.0) -> None:
        super().__init__(axis, start_mm)
        self._pending: tuple[str, float] | None = None
        self._confirmed = threading.Event()
        self._stopped = False
        self._ask: Callable[[str], None] | None = None

    def attach_prompt(self, ask: Callable[[str], None]) -> None:
        self._ask = ask

    def disconnect(self) -> None:
        super().disconnect()
        self.stop()

    def status(self) -> StageStatus:
        return self._status("Run" if self._pending else "Idle")

    def move_to(self, position_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        self._pending = (self._axis(axis), float(position_mm))
        self._confirmed.clear()
        self._stopped = False

    def pending_target(self) -> tuple[str, float] | None:
        return self._pending

    def confirm_moved(self) -> None:
        self._confirmed.set()

    def wait_idle(self, timeout_s: float = 60.0) -> StageStatus:
        """Ask the operator to move to the pending target and wait for the confirmation (no timeout: a person)."""
        if self._pending is None:
            return self.status()
        ax, mm = self._pending
        message = f"move {ax} to {mm:.4f} mm, then confirm"
        if self._ask is not None:
            self._ask(message)
        else:
            self.events.emit(StageEvent("message", text=message))  # the GUI's log shows what to do
            while not self._confirmed.wait(0.1):
                if self._stopped or not self._connected:
                    raise HardwareError(f"manual stage: stopped before the operator confirmed {ax} at {mm:.4f} mm")
        self._reached(ax, mm)
        self._pending = None
        return self.status()

    def stop(self) -> None:
        self._stopped = True


def terminal_prompt(message: str) -> None:
    """Ask on the terminal: print the request to stderr and wait for Enter; end of input gives up."""
    import sys

    print(f"lps: {message} (Enter)", file=sys.stderr, flush=True)
    if sys.stdin.readline() == "":
        raise HardwareError("manual stage: no confirmation (end of input); resume with --resume when the stage is there")
