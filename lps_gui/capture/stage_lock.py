"""A stage locked in Alarm before a capture: home it, unlock it, or say how (never silently).

A stage that declares :class:`~lps_gui.hardware.capabilities.Alarms` may be
locked (a controller with homing enabled may power up so and refuse every move); a
capture must not start there and fail on its first move. The operator
chooses: home (the position is then referenced to the switch) or unlock (the
position is wherever the controller believes it is); the driver's
``lock_hint`` says how in its own terms. The CLI asks with ``--home`` /
``--unlock``, the GUI with a prompt. A stage without alarms is never locked.
"""
from __future__ import annotations

from typing import Literal

from lps_gui.errors import HardwareError
from lps_gui.hardware.capabilities import Alarms
from lps_gui.hardware.stage import Stage

LockAction = Literal["home", "unlock"]


class StageLocked(HardwareError):
    """The stage is in Alarm and nobody said whether to home or unlock it."""


def is_locked(stage: Stage) -> bool:
    """The stage declares alarms and is locked in one (a homing lock at power-up, or an alarm since)."""
    return isinstance(stage, Alarms) and stage.in_alarm(stage.status())


def release_lock(stage: Stage, action: LockAction | None, what: str = "--home or --unlock") -> str | None:
    """Home or unlock a locked stage as asked; raise :class:`StageLocked` naming ``what`` when not asked.

    Returns what was done ("homed", "unlocked") or None when the stage was not locked.
    """
    if not is_locked(stage):
        return None
    assert isinstance(stage, Alarms)  # is_locked says so
    if action == "home":
        stage.home()
        done = "homed"
    elif action == "unlock":
        stage.unlock()
        done = "unlocked"
    else:
        raise StageLocked(
            f"the stage is locked in Alarm; {stage.lock_hint} first: {what}"
        )
    if is_locked(stage):
        raise HardwareError(f"the stage is still in Alarm after it was {done}; reset the controller and try again")
    return done
