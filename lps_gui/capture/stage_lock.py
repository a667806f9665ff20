"""A stage locked in Alarm before a capture: home it, unlock it, or say how (never silently).

GRBL with homing enabled powers up in Alarm (``[MSG:'$H'|'$X' to unlock]``) and
answers every move with ``error:9``; a capture must not start there and fail on
its first move. The operator chooses: home (``$H``, the position is then
referenced to the switch) or unlock (``$X``, the position is wherever GRBL
believes it is). The CLI asks with ``--home`` / ``--unlock``, the GUI with a prompt.
"""
from __future__ import annotations

from typing import Literal

from lps_gui.errors import HardwareError
from lps_gui.hardware.stage import Stage

LockAction = Literal["home", "unlock"]


class StageLocked(HardwareError):
    """The stage is in Alarm and nobody said whether to home or unlock it."""


def is_locked(stage: Stage) -> bool:
    """The stage reports Alarm (a homing lock at power-up, or an alarm since)."""
    return stage.status().state == "Alarm"


def release_lock(stage: Stage, action: LockAction | None, what: str = "--home or --unlock") -> str | None:
    """Home or unlock a locked stage as asked; raise :class:`StageLocked` naming ``what`` when not asked.

    Returns what was done ("homed", "unlocked") or None when the stage was not locked.
    """
    if not is_locked(stage):
        return None
    if action == "home":
        stage.home()
        done = "homed"
    elif action == "unlock":
        stage.unlock()
        done = "unlocked"
    else:
        raise StageLocked(
            "the stage is locked in Alarm (GRBL with homing enabled starts so); "
            f"home it ($H) or unlock it ($X) first: {what}"
        )
    if is_locked(stage):
        raise HardwareError(f"the stage is still in Alarm after it was {done}; reset the controller and try again")
    return done
