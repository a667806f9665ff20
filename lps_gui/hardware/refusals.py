"""Why a stage refuses a command or locks itself, in no protocol's terms.

The simulated stage raises these; a protocol's emulator translates them into
its own words (``hardware/grbl/codes.py`` maps them to ``error:N`` and
``ALARM:N``), so the machine model knows no controller's numbering and a new
protocol's emulator needs only its own table.
"""
from __future__ import annotations

import enum

from lps_gui.errors import HardwareError


class _Reason(enum.Enum):
    """A reason whose value is its one line of text."""

    @property
    def text(self) -> str:
        return self.value


def _message(context: str, text: str, hint: str) -> str:
    return f"{context}{': ' if context else ''}{text}{'; ' + hint if hint else ''}"


class Refusal(_Reason):
    """A command the stage did not execute (nothing moved, the stage stays as it was)."""

    UNKNOWN_AXIS = "no such axis"
    UNKNOWN_WORK_SYSTEM = "no such work coordinate system"
    LOCKED = "commands are locked out while the stage is in Alarm or jogging"
    NOT_IDLE = "the stage must be idle for this command"
    NO_FEED = "no feed rate given"
    BEYOND_TRAVEL = "the jog's target is outside the travel; the jog was ignored"
    HOMING_DISABLED = "homing is not enabled in the settings"
    NEGATIVE_VALUE = "a setting cannot be negative"
    UNKNOWN_SETTING = "no such setting"
    SOFT_LIMITS_NEED_HOMING = "soft limits need homing enabled first"


class Alarm(_Reason):
    """Why the stage locked itself (state Alarm) until it is unlocked or homed; ``LOCK`` is the silent power-up lock."""

    LOCK = "locked until homed or unlocked"
    HARD_LIMIT = "a limit switch was hit; the position is likely lost: home again"
    SOFT_LIMIT = "a move's target is outside the travel; the position is kept"
    ABORT_DURING_CYCLE = "stopped at once during motion; the position is likely lost: home again"
    PROBE_FAIL_INITIAL = "the probe was not in the expected state before probing"
    PROBE_FAIL_CONTACT = "the probe did not touch within the programmed travel"
    HOMING_RESET = "homing was stopped by a reset"
    HOMING_DOOR = "homing was stopped by the safety door"
    HOMING_PULLOFF = "homing's pull-off did not clear the limit switch"
    HOMING_NOT_FOUND = "homing did not find the limit switch within the travel"
    HOMING_DUAL = "homing did not find the second switch of a dual axis"


class StageRefused(HardwareError):
    """The stage refused a command: ``reason`` says why (nothing moved)."""

    def __init__(self, reason: Refusal, context: str = "", hint: str = "") -> None:
        self.reason = reason
        super().__init__(_message(context, reason.text, hint))


class StageAlarm(HardwareError):
    """The stage is locked in Alarm: ``alarm`` says why."""

    def __init__(self, alarm: Alarm, context: str = "", hint: str = "") -> None:
        self.alarm = alarm
        self.reason = alarm
        super().__init__(_message(context, f"alarm: {alarm.text}", hint))
