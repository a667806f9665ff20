"""A stage moved by a program: ``command:'./move.sh {mm}'`` runs it once per move and waits for its exit.

Any vendor's command-line tool or a script of the operator's moves the
stage; the template is split like a shell would (``shlex``) but run without
one, and ``{mm}``, ``{axis}`` and ``{feed}`` are filled in each argument, so a
position never becomes shell syntax. Exit status 0 means "there"; another
status or no exit within ``timeout_s`` is a one-line error naming the command.
The position read back is the last one reached.
"""
from __future__ import annotations

import shlex
import subprocess
import time

from lps_gui.errors import HardwareError, InputError
from lps_gui.hardware.stage import AXES, Stage, StageStatus


class CommandStage(Stage):
    """Runs ``template`` for every move; it has no other capability."""

    can_home = False

    def __init__(self, template: str, axis: str = "X", timeout_s: float = 120.0, start_mm: float = 0.0) -> None:
        super().__init__()
        try:
            self.argv = shlex.split(template)
        except ValueError as exc:
            raise InputError(f"command:{template}: cannot split it into arguments ({exc}); check the quotes") from None
        if not self.argv or not any("{mm}" in a for a in self.argv):
            raise InputError(f"command:{template}: give the program and {{mm}} where the position goes, "
                             "e.g. command:'./move.sh {mm}'")
        self.template = template
        self.axis = axis
        self.timeout_s = float(timeout_s)
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

    def status(self) -> StageStatus:
        self.require_connected()
        pos = tuple(self._pos)
        return StageStatus("Idle", machine_mm=pos, work_mm=pos, time=time.monotonic())  # type: ignore[arg-type]

    def move_to(self, position_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        """Run the program for this move and wait for it (the move is over when it exits 0)."""
        self.require_connected()
        ax = (axis or self.axis).upper()
        if ax not in AXES:
            raise HardwareError(f"command stage: axis {ax!r} unknown; use X, Y or Z")
        values = {"mm": f"{position_mm:.6f}", "axis": ax, "feed": f"{feed_mm_min:g}"}
        argv = [a.format(**values) for a in self.argv]
        shown = shlex.join(argv)
        try:
            done = subprocess.run(argv, capture_output=True, text=True, timeout=self.timeout_s, check=False)
        except subprocess.TimeoutExpired:
            raise HardwareError(f"command stage: `{shown}` did not exit within {self.timeout_s:g} s") from None
        except OSError as exc:
            raise HardwareError(f"command stage: `{shown}` cannot run ({exc.strerror}); check the program's path") from None
        if done.returncode != 0:
            said = (done.stderr or done.stdout or "").strip().splitlines()
            raise HardwareError(f"command stage: `{shown}` exited with status {done.returncode}"
                                + (f": {said[-1]}" if said else ""))
        self._pos[AXES.index(ax)] = float(position_mm)

    def wait_idle(self, timeout_s: float = 60.0) -> StageStatus:
        return self.status()

    def describe(self) -> dict:
        return {**super().describe(), "command": self.template}
