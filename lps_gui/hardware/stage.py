"""The Stage interface every driver implements (GRBL, simulated, future ones).

Axis positions are in mm, feeds in mm/min. Drivers push events (alarms,
errors, messages, state changes) to subscribers; subscribers never block the
driver and the driver never knows who listens (models emit, views subscribe).
"""
from __future__ import annotations

import abc
import threading
from dataclasses import dataclass, field
from typing import Any, Callable

from lps_gui.core.clock import Clock
from lps_gui.errors import HardwareError

AXES = ("X", "Y", "Z")
WORK_SYSTEMS = ("G54", "G55", "G56", "G57", "G58", "G59")  # GRBL's work coordinate systems (G10 L2/L20 P1..P6)


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
    code: int | None = None
    text: str = ""


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
    """A motorized stage. Methods block until the controller acknowledged the command.

    What a driver may know beyond the commands is declared here with the
    default of a driver that does not: the capture engine and the GUI read
    these, never probe for them.
    """

    axis: str = "X"  # the axis the LPS measurement moves along
    travel_mm: tuple[float, float] | None = None  # soft-limit range of ``axis`` when known (the simulated stage);
    #   None: the controller guards its limits itself (GRBL's $20 alarms at the offending move)
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
    @abc.abstractmethod
    def home(self) -> None: ...
    @abc.abstractmethod
    def unlock(self) -> None: ...
    @abc.abstractmethod
    def soft_reset(self) -> None: ...
    @abc.abstractmethod
    def feed_hold(self) -> None: ...
    @abc.abstractmethod
    def resume(self) -> None: ...

    # motion
    @abc.abstractmethod
    def move_to(self, position_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        """Start an absolute move (machine-independent work coordinates)."""
    @abc.abstractmethod
    def jog(self, distance_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        """Incremental jog; for continuous jogging send a long one and :meth:`jog_cancel`."""
    @abc.abstractmethod
    def jog_cancel(self) -> None: ...
    @abc.abstractmethod
    def wait_idle(self, timeout_s: float = 60.0) -> StageStatus:
        """Block until the stage is Idle; raise HardwareError on alarm or timeout."""

    # settings
    @abc.abstractmethod
    def read_settings(self) -> list[StageSetting]: ...
    @abc.abstractmethod
    def write_setting(self, number: int, value: float) -> None: ...

    # work coordinates (GRBL's model: work = machine - offset of the selected system)
    work_systems: tuple[str, ...] = ()  # the systems this driver can select and zero; () = work is machine

    def work_system(self) -> str:
        """The selected work coordinate system (G54 when the driver has none)."""
        return WORK_SYSTEMS[0]

    def select_work_system(self, name: str) -> None:
        """Make ``name`` (one of :attr:`work_systems`) the system positions and moves refer to."""
        raise HardwareError(f"{type(self).__name__}: no work coordinate systems; positions are machine positions")

    def work_offsets(self) -> dict[str, tuple[float, float, float]]:
        """Offset of every system in mm, GRBL's sign (``$#``): work = machine - offset."""
        return {}

    def set_work_zero(self, axis: str | None = None, value_mm: float = 0.0) -> None:
        """Make the current position read ``value_mm`` on ``axis`` in the selected system."""
        raise HardwareError(f"{type(self).__name__}: no work coordinate systems; positions are machine positions")

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
