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

from lps_gui.errors import HardwareError, InputError
from lps_gui.hardware.stage import StageStatus
from lps_gui.hardware.told_position import ToldPositionStage


class CommandStage(ToldPositionStage):
    """Runs ``template`` for every move; it has no other capability."""

    name = "command stage"

    def __init__(self, template: str, axis: str = "X", timeout_s: float = 120.0, start_mm: float = 0.0) -> None:
        super().__init__(axis, start_mm)
        try:
            self.argv = shlex.split(template)
        except ValueError as exc:
            raise InputError(f"command:{template}: cannot split it into arguments ({exc}); check the quotes") from None
        if not self.argv or not any("{mm}" in a for a in self.argv):
            raise InputError(f"command:{template}: give the program and {{mm}} where the position goes, "
                             "e.g. command:'./move.sh {mm}'")
        self.template = template
        self.timeout_s = float(timeout_s)

    def move_to(self, position_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        """Run the program for this move and wait for it (the move is over when it exits 0)."""
        ax = self._axis(axis)
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
        self._reached(ax, position_mm)

    def wait_idle(self, timeout_s: float = 60.0) -> StageStatus:
        return self.status()

    def describe(self) -> dict:
        return {**super().describe(), "command": self.template}
