"""The base of stages that cannot be asked where they are: the position is the last one reached by a move.

A manual stage (the operator confirmed it) and a command stage (the program
exited 0) know their position only from the moves they completed; both share
the connection flag, the status built from that position and the axis check.
"""
from __future__ import annotations

import time

from lps_gui.errors import HardwareError
from lps_gui.hardware.stage import AXES, Stage, StageStatus


class ToldPositionStage(Stage):
    """Keeps the position of the last completed move; ``name`` prefixes its errors."""

    can_home = False
    name = "stage"

    def __init__(self, axis: str = "X", start_mm: float = 0.0) -> None:
        super().__init__()
        self.axis = axis
        self._pos = [0.0, 0.0, 0.0]
        self._pos[AXES.index(axis)] = float(start_mm)
        self._connected = False

    def connect(self) -> None:
        self._connected = True

    def disconnect(self) -> None:
        self._connected = False

    @property
    def connected(self) -> bool:
        return self._connected

    def _status(self, state: str) -> StageStatus:
        self.require_connected()
        pos = tuple(self._pos)
        return StageStatus(state, machine_mm=pos, work_mm=pos, time=time.monotonic())  # type: ignore[arg-type]

    def status(self) -> StageStatus:
        return self._status("Idle")

    def _axis(self, axis: str | None) -> str:
        """The axis a move names (default: the measured one), checked; the stage must be connected."""
        self.require_connected()
        ax = (axis or self.axis).upper()
        if ax not in AXES:
            raise HardwareError(f"{self.name}: axis {ax!r} unknown; use X, Y or Z")
        return ax

    def _reached(self, axis: str, position_mm: float) -> None:
        self._pos[AXES.index(axis)] = float(position_mm)
