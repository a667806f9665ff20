"""The Stage interface every driver implements (GRBL, Marlin, manual, simulated...); capabilities beyond it
are declared through ``hardware/capabilities.py``.

Axis positions are in mm, feeds in mm/min. Drivers push events (alarms,
errors, messages, state changes) to subscribers; subscribers never block the
driver and the driver never knows who listens (models emit, views subscribe).
"""
from __future__ import annotations

import abc
import threading
from dataclasses import dataclass, field
from enum import Enum
from typing import Any, Callable

from lps_gui.core.clock import Clock
from lps_gui.errors import HardwareError

AXES = ("X", "Y", "Z")
WORK_SYSTEMS = ("G54", "G55", "G56", "G57", "G58", "G59")  # G-code's (RS274/NGC) six work coordinate systems


@dataclass(frozen=True)
class StageStatus:
    """A snapshot of the controller (GRBL's status report, generalized)."""

    state: str  # Idle, Run, Hold, Jog, Alarm, Door, Check, Home, Sleep, Disconnected
    substate: int | None = None
    machine_mm: tuple[float, float, float] = (0.0, 0.0, 0.0)
    work_mm: tuple[float, float, float] = (0.0, 0.0, 0.0)
    feed_mm_min: float = 0.0
    spindle_rpm: float = 0.0
    buffer: tuple[int, int] | None = None  # planner blocks free, RX bytes free
    overrides: tuple[int, int, int] | None = None  # feed, rapid, spindle %
    pins: str = ""
    time: float = 0.0  # stage clock (simulated or monotonic) in s

    @property
    def idle(self) -> bool:
        return self.state == "Idle"


@dataclass(frozen=True)
class StageEvent:
    """Something the controller said on its own: alarm, error, message, state change."""

    kind: str  # "alarm", "error", "message", "state", "disconnected", "connected"
    code: int | None = None  # the controller's own number for it (GRBL's ALARM:N), when it has one
    text: str = ""
    reason: Enum | None = None  # why, in no protocol's terms (hardware/refusals.py's Alarm), when known


@dataclass(frozen=True)
class StageSetting:
    """One controller setting ($N=value) with its meaning."""

    number: int
    value: float
    name: str = ""
    unit: str = ""
    description: str = ""


EventHandler = Callable[[StageEvent], None]


@dataclass
class EventSource:
    """Fan out events to subscribers; a failing subscriber does not stop the driver."""

    _handlers: list[EventHandler] = field(default_factory=list)
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def subscribe(self, handler: EventHandler) -> Callable[[], None]:
        with self._lock:
            self._handlers.append(handler)

        def unsubscribe() -> None:
            with self._lock:
                if handler in self._handlers:
                    self._handlers.remove(handler)

        return unsubscribe

    def emit(self, event: StageEvent) -> None:
        with self._lock:
            handlers = list(self._handlers)
        for h in handlers:
            try:
                h(event)
            except Exception:  # a listener's bug must not kill the stage
                import logging

                logging.getLogger(__name__).exception("stage event handler failed")


class Stage(abc.ABC):
    """A motorized stage: what every stage has. Methods block until the controller acknowledged the command.

    Connect, home (when :attr:`can_home`), move to absolute positions on its
    axes, wait until still, read the position, stop. Anything more (settings,
    a console, work coordinates, jogging, feed hold, alarms, an operator who
    moves it) is a capability the driver declares by also inheriting its
    interface from :mod:`lps_gui.hardware.capabilities`; the capture engine and
    the GUI ask those declarations, never the protocol. What a driver may know
    beyond the commands is declared here with the default of a driver that
    does not.
    """

    axis: str = "X"  # the axis the LPS measurement moves along
    axes: tuple[str, ...] = AXES  # the axes it can move
    can_home: bool = True  # home() drives to a reference switch; False: home() raises
    travel_mm: tuple[float, float] | None = None  # soft-limit range of ``axis`` when known (the simulated stage);
    #   None: the controller guards its limits itself (an alarm at the offending move)
    axis_travel_mm: list[tuple[float, float]] | None = None  # the range of each of X, Y, Z when known
    clock: Clock | None = None  # the stage's own clock (simulated time); None: real time
    simulated: "Stage | None" = None  # a driver in front of a simulated stage (the GRBL emulator): that stage

    def true_pose(self) -> Any:
        """Where the carriage really is, where a simulator knows it (the camera of a simulated rig renders
        it); None on a real stage."""
        return None

    def __init__(self) -> None:
        self.events = EventSource()

    # connection
    @abc.abstractmethod
    def connect(self) -> None: ...
    @abc.abstractmethod
    def disconnect(self) -> None: ...
    @property
    @abc.abstractmethod
    def connected(self) -> bool: ...

    # state
    @abc.abstractmethod
    def status(self) -> StageStatus: ...

    def home(self) -> None:
        """Drive to the reference switch (drivers with :attr:`can_home` override this)."""
        raise HardwareError(f"{type(self).__name__}: this stage cannot home; move it to its start instead")

    # motion
    @abc.abstractmethod
    def move_to(self, position_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        """Start an absolute move (machine-independent work coordinates)."""
    @abc.abstractmethod
    def wait_idle(self, timeout_s: float = 60.0) -> StageStatus:
        """Block until the stage is Idle; raise HardwareError on alarm or timeout."""

    def stop(self) -> None:
        """Stop motion now, as well as this stage can (a controller's quick stop, a feed hold)."""
        raise HardwareError(f"{type(self).__name__}: cannot be stopped from here; use the controller's own stop")

    # conveniences shared by all drivers
    def position_mm(self, axis: str | None = None) -> float:
        st = self.status()
        return st.work_mm[AXES.index(axis or self.axis)]

    def describe(self) -> dict:
        """What a session.json records about this stage."""
        return {"driver": type(self).__name__, "axis": self.axis}

    def require_connected(self) -> None:
        if not self.connected:
            raise HardwareError(f"{type(self).__name__}: not connected; connect the stage first")
