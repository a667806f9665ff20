"""What a stage can do beyond moving: small interfaces a driver declares by inheriting them.

Every :class:`~lps_gui.hardware.stage.Stage` connects, moves to absolute
positions, waits until still, reads its position and stops. Anything more is
a capability a driver *declares* (``class GrblStage(Stage, Settings, Console,
...)``); the GUI and the capture engine ask ``isinstance(stage, Settings)``,
never which protocol is behind it, so a new driver gets exactly the widgets
and checks it declares (docs/hardware.md lists them).
"""
from __future__ import annotations

import abc
from typing import Callable

from lps_gui.hardware.stage import StageSetting, StageStatus


class Settings(abc.ABC):
    """Numbered controller settings (GRBL ``$N``, Marlin's ``M503`` values) the operator may read and change."""

    settings_title: str = "Controller settings"  # the GUI's group title

    @abc.abstractmethod
    def read_settings(self) -> list[StageSetting]: ...

    @abc.abstractmethod
    def write_setting(self, number: int, value: float) -> None: ...

    def setting_label(self, setting: StageSetting) -> str:
        """How the controller names the setting (GRBL ``$110``, Marlin ``M203 X``)."""
        return str(setting.number)

    def travel_text(self, settings: list[StageSetting]) -> str:
        """One line on the axes' travel and limits as these settings say (the driver knows their meaning)."""
        return "travel: unknown"


class Console(abc.ABC):
    """A raw command line to the controller (G-code consoles): one line out, the lines it answered back."""

    console_hint: str = "a controller command"  # what the console's placeholder says it takes

    @abc.abstractmethod
    def command(self, line: str, timeout_s: float | None = None) -> list[str]:
        """Send ``line`` and wait for the controller's acknowledgement; return what it printed before it."""


class WorkCoordinates(abc.ABC):
    """Selectable work coordinate systems with offsets (work = machine - offset, GRBL's sign)."""

    work_systems: tuple[str, ...] = ()

    @abc.abstractmethod
    def work_system(self) -> str: ...

    @abc.abstractmethod
    def select_work_system(self, name: str) -> None: ...

    @abc.abstractmethod
    def work_offsets(self) -> dict[str, tuple[float, float, float]]: ...

    @abc.abstractmethod
    def set_work_zero(self, axis: str | None = None, value_mm: float = 0.0) -> None: ...


class Jogging(abc.ABC):
    """Incremental jogs that can be cancelled (a held jog button)."""

    @abc.abstractmethod
    def jog(self, distance_mm: float, feed_mm_min: float, axis: str | None = None) -> None: ...

    @abc.abstractmethod
    def jog_cancel(self) -> None: ...


class FeedHold(abc.ABC):
    """Pause a move and continue it later."""

    @abc.abstractmethod
    def feed_hold(self) -> None: ...

    @abc.abstractmethod
    def resume(self) -> None: ...


class Alarms(abc.ABC):
    """A controller that locks itself after an alarm (or at power-up) until it is homed or unlocked."""

    lock_hint: str = "home it or unlock it first"  # how the operator releases the lock, said in errors and prompts

    def in_alarm(self, status: StageStatus) -> bool:
        """The controller refuses moves now (locked)."""
        return status.state == "Alarm"

    @abc.abstractmethod
    def unlock(self) -> None: ...

    @abc.abstractmethod
    def soft_reset(self) -> None: ...


class OperatorMoved(abc.ABC):
    """A stage the operator moves by hand: each move waits for the operator to confirm it.

    The GUI's Moved button calls :meth:`confirm_moved`; a terminal attaches a
    prompt (:meth:`attach_prompt`) that asks and blocks until the operator answers.
    """

    @abc.abstractmethod
    def attach_prompt(self, ask: Callable[[str], None]) -> None:
        """Ask the operator through ``ask(message)`` (returns once confirmed, raises to give up) instead of
        waiting for :meth:`confirm_moved`."""

    @abc.abstractmethod
    def confirm_moved(self) -> None:
        """The operator says the carriage is at the position asked for (the GUI's Moved button)."""

    @abc.abstractmethod
    def pending_target(self) -> tuple[str, float] | None:
        """(axis, mm) the stage waits for the operator to move to, or None."""


CAPABILITIES: dict[str, type] = {
    "settings": Settings, "console": Console, "work coordinates": WorkCoordinates, "jogging": Jogging,
    "feed hold": FeedHold, "alarms": Alarms, "operator moved": OperatorMoved,
}


def declared(stage: object) -> list[str]:
    """The names of the capabilities ``stage`` declares (for session.json and the docs' table)."""
    return [name for name, cls in CAPABILITIES.items() if isinstance(stage, cls)]


SPEC_NAMES = {"settings": "settings", "console": "console", "work coordinates": "work_coordinates", "jogging": "jog",
              "feed hold": "feed_hold", "alarms": "alarms", "operator moved": "operator_moved"}


def session_stage(stage: object) -> dict:
    """What session.json records of a stage (SPEC 16): its own description, and the capabilities its driver declared
    (``home`` first where it can home); a simulated rig following another stage records that stage's."""
    driver = getattr(stage, "driver", stage)
    names = (["home"] if getattr(driver, "can_home", False) else []) + [SPEC_NAMES[n] for n in declared(driver)]
    return {**stage.describe(), "capabilities": names}
