"""A simulated stage: motion in simulated time, soft limits, homing, and a true-position error model.

Motion follows trapezoidal profiles (``hardware/motion.py``) evaluated at the
clock's time, so with a :class:`~lps_gui.core.clock.SimClock` a 500 mm move
"takes" 10 s but :meth:`SimulatedStage.wait_idle` returns at once by
advancing the clock. Where the carriage *really* is comes from the one
:class:`~lps_gui.core.truth.stage_errors.StageErrorModel` every simulator shares
(backlash of the last approach direction, one repeatability draw per
completed move, straightness and angular errors); the simulated camera
renders from :meth:`SimulatedStage.true_pose`.

The machine model speaks no protocol: a refused command raises
:class:`~lps_gui.hardware.refusals.StageRefused` with a neutral reason, an alarm
:class:`~lps_gui.hardware.refusals.StageAlarm` (a move outside the travel is a
soft-limit alarm, a jog there a refusal; commands are locked out in Alarm and
while jogging; a reset during motion is an alarm), and settings are named
(``hardware/machine_settings.py``). A protocol's emulator wraps this class and
says the same in its own words (``hardware/grbl/``: ``error:N``, ``ALARM:N``,
``$N``). Work coordinates: six systems G54-G59 (all offsets zero at start, so
work = machine until the operator zeroes an axis), work = machine - offset of
the selected system; moves, jogs and soft-limit messages are in work coordinates.
"""
from __future__ import annotations

import threading
from contextlib import contextmanager
from typing import Iterator

import numpy as np

from lps_gui.core.clock import Clock, SimClock
from lps_gui.core.truth.stage_errors import PlanarErrorModel, PlanarTruePose, StageErrorModel, TruePose, Vibration
from lps_gui.errors import HardwareError
from lps_gui.hardware.capabilities import Alarms, FeedHold, Jogging, Settings, WorkCoordinates
from lps_gui.hardware.machine_settings import BY_KEY, KEY, MACHINE_SETTINGS, NUMBER, machine_defaults, travel_text
from lps_gui.hardware.motion import Profile
from lps_gui.hardware.planner import PLANNER_BLOCKS, HeldMove, MotionPlanner
from lps_gui.hardware.refusals import Alarm, Refusal, StageAlarm, StageRefused
from lps_gui.hardware.stage import AXES, WORK_SYSTEMS, Stage, StageEvent, StageSetting, StageStatus

__all__ = ["PLANNER_BLOCKS", "SimulatedStage", "Vibration"]  # Vibration: core/truth/stage_errors


class SimulatedStage(Stage, Settings, WorkCoordinates, Jogging, FeedHold, Alarms):
    """A plain-Python stage implementing :class:`Stage` in simulated (or real) time.

    Parameters
    ----------
    errors : true-position error model (zero errors when None).
    seed : seeds the repeatability draws (one per completed move of ``axis``).
    travel_mm : (min, max) soft-limit range of every axis in machine coordinates (mm; equal to the work
        coordinates while every offset is zero, as at start).
    max_rate_mm_min, accel_mm_s2 : velocity and acceleration limits of every axis.
    clock : time source; a fresh SimClock when None (tests never sleep).
    axis : the axis the LPS measurement moves along.
    homing_required : start locked in Alarm until homed or unlocked (a controller's homing lock).
    soft_limits : a move outside the travel raises a soft-limit alarm.
    axis_travel_mm : per-axis soft-limit ranges overriding ``travel_mm`` (e.g. {"Y": (0, 1016)}).
    planar_errors : an XY gantry's error model (SPEC 10); then X and Y both carry the camera
        and :meth:`true_planar_pose` gives the truth.
    vibration : a decaying oscillation of the measured axis after each move (:class:`Vibration`).
    """

    def __init__(
        self,
        errors: StageErrorModel | None = None,
        seed: int = 0,
        travel_mm: tuple[float, float] = (-5.0, 500.0),
        max_rate_mm_min: float = 3000.0,
        accel_mm_s2: float = 200.0,
        clock: Clock | None = None,
        axis: str = "X",
        homing_required: bool = False,
        soft_limits: bool = True,
        start_mm: float = 0.0,
        planar_errors: PlanarErrorModel | None = None,
        axis_travel_mm: dict[str, tuple[float, float]] | None = None,
        vibration: Vibration | None = None,
    ) -> None:
        super().__init__()
        if axis not in AXES:
            raise ValueError(f"axis must be one of {AXES}")
        self.axis = axis
        self.errors = errors or StageErrorModel()
        self.seed = seed
        self.travel_mm = (float(travel_mm[0]), float(travel_mm[1]))
        self.axis_travel_mm = [self.travel_mm] * 3
        for name, (lo, hi) in (axis_travel_mm or {}).items():
            self.axis_travel_mm[AXES.index(name.upper())] = (float(lo), float(hi))
        self.clock: Clock = clock if clock is not None else SimClock()
        self.machine: dict[str, float] = machine_defaults(max_rate_mm_min, accel_mm_s2, self.axis_travel_mm, soft_limits)
        self._rng = np.random.default_rng(seed)
        self._lock = threading.RLock()
        pos_mm = np.zeros(3)
        pos_mm[AXES.index(axis)] = start_mm
        self._motion = MotionPlanner(pos_mm)
        self._homing = False
        self.homed = False
        self._alarm: Alarm | None = Alarm.LOCK if homing_required else None
        self._last_dir = 1
        self._noise_um = 0.0
        self._angle_noise_urad = np.zeros(3)  # the angles' draw of the last move (StageErrorModel.angle_noise_urad)
        self.planar_errors = planar_errors
        self._axis_dir = [1, 1, 1]  # per axis: side of the last approach (planar truth)
        self._axis_noise_um = [0.0, 0.0, 0.0]  # per axis: repeatability draw of its last move
        self._connected = False
        self._vanish_at: float | None = None
        self._vanished = False
        self._last_state = ""
        self.vibration = vibration
        self._stopped_at: float | None = None  # end of the last completed move of the measured axis
        self._rest_mm: float | None = float(start_mm)  # where the carriage rests (after its last move that moved it)
        self._stuck_mm = 0.0  # the carriage's offset from the commanded position after a move inside the dead band
        self._offsets = {name: [0.0, 0.0, 0.0] for name in WORK_SYSTEMS}  # work = machine - offset
        self._system = WORK_SYSTEMS[0]

    # ------------------------------------------------------------------ settings
    def _ax(self, axis: str | None) -> int:
        name = (axis or self.axis).upper()
        if name not in AXES:
            raise StageRefused(Refusal.UNKNOWN_AXIS, f"axis {name!r}")
        return AXES.index(name)

    def max_rate_mm_min(self, axis: int) -> float:
        return self.machine[f"max_rate_mm_min.{AXES[axis]}"]

    def accel_mm_s2(self, axis: int) -> float:
        return self.machine[f"accel_mm_s2.{AXES[axis]}"]

    @property
    def soft_limits(self) -> bool:
        return bool(self.machine["soft_limits"])

    @property
    def homing_enabled(self) -> bool:
        return bool(self.machine["homing"])

    def home_position_mm(self) -> float:
        """Where homing leaves the carriage: the low switch plus the pull-off."""
        return self.travel_mm[0] + self.machine["homing_pulloff_mm"]

    # ------------------------------------------------------------------ connection
    def connect(self) -> None:
        with self._lock:
            if self._vanished:
                self._vanished = False
                self._vanish_at = None
            self._connected = True
        self.events.emit(StageEvent("connected", text="simulated stage connected"))

    def disconnect(self) -> None:
        with self._lock:
            self._connected = False
        self.events.emit(StageEvent("disconnected", text="simulated stage disconnected"))

    @property
    def connected(self) -> bool:
        with self._lock:
            self._check_vanish(raise_=False)
            return self._connected

    def disconnect_fault(self, at_time_s: float | None = None) -> None:
        """Simulate a vanished port now, or when the stage clock reaches ``at_time_s``.

        Motion stops where it was at that time; every call then raises
        HardwareError until :meth:`connect` is called again (the reconnect).
        """
        with self._lock:
            self._vanish_at = self.clock.now() if at_time_s is None else float(at_time_s)

    def _check_vanish(self, raise_: bool = True) -> None:
        if self._vanish_at is not None and not self._vanished and self.clock.now() >= self._vanish_at:
            self._freeze(self._vanish_at)
            self._vanished = True
            self._connected = False
            self.events.emit(StageEvent("disconnected", text="simulated stage: port vanished"))
        if raise_ and self._vanished:
            raise HardwareError("simulated stage: the port vanished (simulated fault); reconnect the stage and resume")

    def require_connected(self) -> None:
        with self._lock:
            self._check_vanish()
        super().require_connected()

    @contextmanager
    def _command(self) -> Iterator[float]:
        """Every command: under the lock, connected, motion brought up to the clock's time ``t``."""
        with self._lock:
            self.require_connected()
            t = self.clock.now()
            self._update(t)
            yield t

    # ------------------------------------------------------------------ time evolution
    def _freeze(self, t: float) -> None:
        """Stop all motion abruptly at time ``t`` (reset, alarm, vanished port)."""
        self._update(t)
        self._motion.freeze(t)
        self._homing = False

    def _complete(self, p: Profile) -> None:
        """A move ended: its direction sets the backlash side, and it gets its repeatability draw."""
        if p.axis == AXES.index(self.axis) and p.direction != 0 and self.planar_errors is None:
            if self._rest_mm is not None:  # stick-slip (the error model's dead band): a short move leaves it there
                reached, moved = self.errors.reached_mm(np.array([self._rest_mm, p.end_mm]))
                if not moved[-1]:
                    self._stuck_mm = float(reached[-1]) - p.end_mm
                    return
            self._rest_mm, self._stuck_mm = p.end_mm, 0.0
            self._last_dir = p.direction
            self._stopped_at = p.t_end
            rep = self.errors.repeatability_um
            self._noise_um = float(self._rng.normal(0.0, rep)) if rep > 0 else 0.0
            if self.errors.angle_noise_urad > 0:
                self._angle_noise_urad = self._rng.normal(0.0, self.errors.angle_noise_urad, 3)
        if self.planar_errors is not None and p.axis in (0, 1) and p.direction != 0:
            self._axis_dir[p.axis] = p.direction
            rep = (self.planar_errors.x, self.planar_errors.y)[p.axis].repeatability_um
            self._axis_noise_um[p.axis] = float(self._axis_rng(p.axis).normal(0.0, rep)) if rep > 0 else 0.0

    def _axis_rng(self, axis: int) -> np.random.Generator:
        """The generator of an XY axis' repeatability draw (a seeded rig draws the same value per stop)."""
        return self._rng

    def _update(self, t: float | None = None) -> None:
        """Retire motion finished by time ``t`` and emit a state event on change."""
        t = self.clock.now() if t is None else t
        for p in self._motion.update(t):
            self._complete(p)
        if self._homing and not self._motion.queue:
            self._homing = False
            self.homed = True
        state, _ = self._state()
        if state != self._last_state:
            self._last_state = state
            self.events.emit(StageEvent("state", text=state))

    def _state(self) -> tuple[str, int | None]:
        return ("Alarm", None) if self._alarm is not None else self._motion.state()

    def planner_free(self) -> int:
        """Free planner blocks (a wrapping firmware reports them)."""
        with self._lock:
            self._update()
            return self._motion.free

    def planned_mm(self, axis: int) -> float:
        """Where ``axis`` will rest once all planned (or held) motion is done (for G91 targets)."""
        with self._lock:
            return self._motion.planned_mm(axis)

    def motion_progress(self) -> tuple[str, float] | None:
        """(kind, fraction of its duration done) of the profile moving now, None when resting."""
        with self._lock:
            t = self.clock.now()
            self._update(t)
            p = self._motion.active()
            if p is None or p.t_end <= p.t0:
                return None
            return p.kind, (t - p.t0) / (p.t_end - p.t0)

    def next_event_s(self) -> float | None:
        """Clock time of the next state change in motion (for waiting), None when resting."""
        with self._lock:
            return self._motion.next_event_s()

    # ------------------------------------------------------------------ work coordinates
    work_systems = WORK_SYSTEMS

    def _offset(self, axis: int) -> float:
        return self._offsets[self._system][axis]

    def work_system(self) -> str:
        with self._lock:
            return self._system

    def select_work_system(self, name: str) -> None:
        with self._command():
            if name not in WORK_SYSTEMS:
                raise StageRefused(Refusal.UNKNOWN_WORK_SYSTEM, f"work coordinate system {name!r}")
            self._require_unlocked()
            self._system = name

    def work_offsets(self) -> dict[str, tuple[float, float, float]]:
        with self._lock:
            return {name: (o[0], o[1], o[2]) for name, o in self._offsets.items()}

    def set_work_zero(self, axis: str | None = None, value_mm: float = 0.0) -> None:
        """``G10 L20``: the selected system's offset becomes what makes the position read ``value_mm`` now."""
        with self._command() as t:
            i = self._ax(axis)
            self._require_unlocked()
            pos, _ = self._motion.positions(t)
            self._offsets[self._system][i] = float(pos[i]) - float(value_mm)

    # ------------------------------------------------------------------ status
    def status(self) -> StageStatus:
        with self._command() as t:
            state, sub = self._state()
            pos, feed = self._motion.positions(t)
            work = tuple(float(p) - o for p, o in zip(pos, self._offsets[self._system]))
            return StageStatus(
                state=state, substate=sub, machine_mm=tuple(pos), work_mm=work,
                feed_mm_min=feed, time=t,  # no serial buffer nor overrides: a wrapping firmware reports its own
            )

    def true_pose(self) -> TruePose:
        """Where the carriage really is now (K=1), from the shared error model.

        Backlash follows the direction of the last approach; the repeatability
        draw of the last completed move is added to the axis position, and the
        ringing of :attr:`vibration` while the stage stands. A move shorter than
        the error model's dead band leaves the carriage where it was (stick-slip).
        """
        return self.resting_pose(ringing=True)

    def resting_pose(self, ringing: bool = False) -> TruePose:
        """:meth:`true_pose` without the vibration: where the carriage comes to rest (the settle tests' truth)."""
        with self._lock:
            t = self.clock.now()
            self._update(t)
            pos, _ = self._motion.positions(t)
            i = AXES.index(self.axis)
            p = self._motion.active()
            direction = p.direction if p is not None and p.direction else self._last_dir
            stuck = self._stuck_mm if p is None else 0.0
            pose = self.errors.true_pose(np.array([pos[i] + stuck]), np.array([float(direction)]))
            ring_um = 0.0
            if ringing and self.vibration is not None and p is None and self._stopped_at is not None:
                ring_um = self.vibration.offset_um(t - self._stopped_at, self._last_dir)
            return TruePose(
                axis_mm=pose.axis_mm + 1e-3 * (self._noise_um + ring_um),
                straightness_um=pose.straightness_um,
                angles_urad=pose.angles_urad + self._angle_noise_urad,
            )

    def true_planar_pose(self) -> PlanarTruePose:
        """Where an XY carriage really is now (K=1), from the planar error model.

        Each axis keeps the backlash side of its last approach and the
        repeatability draw of its last completed move.
        """
        if self.planar_errors is None:
            raise ValueError("this simulated stage has no planar error model")
        with self._lock:
            t = self.clock.now()
            self._update(t)
            pos, _ = self._motion.positions(t)
            p = self._motion.active()
            dirs = list(self._axis_dir)
            if p is not None and p.direction and p.axis in (0, 1):
                dirs[p.axis] = p.direction
            pose = self.planar_errors.true_pose(np.array([[pos[0], pos[1]]]), np.array([dirs[:2]], dtype=float))
            noise = 1e-3 * np.array([self._axis_noise_um[:2]])
            return PlanarTruePose(pose.plane_mm + noise, pose.normal_um, pose.angles_urad)

    def describe(self) -> dict:
        return {
            **super().describe(),
            "travel_mm": list(self.travel_mm),
            "max_rate_mm_min": self.max_rate_mm_min(AXES.index(self.axis)),
            "accel_mm_s2": self.accel_mm_s2(AXES.index(self.axis)),
            "seed": self.seed,
            "errors": self.errors.to_dict(),
            **({"axes": ["X", "Y"], "planar_errors": self.planar_errors.to_dict()} if self.planar_errors else {}),
            **({"vibration": self.vibration.to_dict()} if self.vibration is not None else {}),
        }

    # ------------------------------------------------------------------ alarms and locks
    def _raise_alarm(self, alarm: Alarm, context: str) -> StageAlarm:
        self._freeze(self.clock.now())
        self._alarm = alarm
        if alarm is not Alarm.LOCK:  # the lock at start-up is silent
            self.events.emit(StageEvent("alarm", text=f"simulated stage: alarm: {alarm.text}", reason=alarm))
        return StageAlarm(alarm, context, self._alarm_hint(alarm))

    def _alarm_hint(self, alarm: Alarm) -> str:
        return "reset the stage, then unlock it" if alarm in (Alarm.HARD_LIMIT, Alarm.SOFT_LIMIT) else self.lock_hint

    def trigger_alarm(self, alarm: Alarm) -> None:
        """Lock in Alarm now for ``alarm`` (fault injection: a hard limit mid-move...; a wrapping firmware's alarms)."""
        with self._lock:
            self._raise_alarm(alarm, "simulated stage")

    @property
    def alarm(self) -> Alarm | None:
        """Why the stage is locked (``Alarm.LOCK``: at start-up), None when not in Alarm."""
        return self._alarm

    def _require_unlocked(self) -> None:
        state, _ = self._state()
        if state in ("Alarm", "Jog"):
            raise StageRefused(Refusal.LOCKED, f"stage in {state}", f"{self.lock_hint} first" if state == "Alarm" else "")

    def unlock(self) -> None:
        with self._command():
            if self._alarm is not None:
                self._alarm = None
                self.events.emit(StageEvent("message", text="Caution: Unlocked"))
                self._update()

    def soft_reset(self) -> None:
        """Stop at once; a reset during motion or homing locks the stage in Alarm (the position may be lost)."""
        with self._command() as t:
            moving = self._motion.active() is not None
            homing = self._homing
            self._freeze(t)
            if homing:
                self._raise_alarm(Alarm.HOMING_RESET, "reset during homing")
            elif moving:
                self._raise_alarm(Alarm.ABORT_DURING_CYCLE, "reset during motion")
            self._update(t)

    # ------------------------------------------------------------------ motion
    def _accel(self, axis: int) -> float:
        return self.accel_mm_s2(axis)

    def _plan(self, axis: int, kind: str, target_mm: float, feed_mm_min: float) -> None:
        feed = min(feed_mm_min, self.max_rate_mm_min(axis))
        self._motion.plan(self.clock.now(), axis, kind, target_mm, feed, self.accel_mm_s2(axis))

    def _in_travel(self, target_mm: float, axis: int) -> bool:
        lo, hi = self.axis_travel_mm[axis]
        return lo <= target_mm <= hi

    def _wait_planner(self) -> None:
        """Block (in clock time) until a planner block frees, like a controller's command waiting for space."""
        while self.planner_free() <= 0:
            nxt = self.next_event_s()
            if nxt is None:  # nothing moves that could free a block (a hold with a full planner)
                raise HardwareError("simulated stage: planner full while held; resume or reset it first")
            self.clock.sleep(max(nxt - self.clock.now(), 1e-6))

    def move_to(self, position_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        with self._command():
            i = self._ax(axis)
            self._require_unlocked()
            if not feed_mm_min or feed_mm_min <= 0:
                raise StageRefused(Refusal.NO_FEED, f"move to {position_mm} mm")
            off = self._offset(i)
            target = float(position_mm) + off
            if self.soft_limits and not self._in_travel(target, i):
                lo, hi = self.axis_travel_mm[i]
                raise self._raise_alarm(
                    Alarm.SOFT_LIMIT, f"move of {AXES[i]} to {position_mm:.3f} mm is outside its travel {lo - off:g}..{hi - off:g} mm"
                )
            self._wait_planner()
            if self._motion.hold:
                self._motion.held.append(HeldMove(i, "Run", target, float(feed_mm_min)))
            else:
                self._plan(i, "Run", target, float(feed_mm_min))
            self._update()

    def jog(self, distance_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        with self._command():
            i = self._ax(axis)
            state, _ = self._state()
            if state not in ("Idle", "Jog"):
                raise StageRefused(Refusal.NOT_IDLE, f"jog in {state}")
            if not feed_mm_min or feed_mm_min <= 0:
                raise StageRefused(Refusal.NO_FEED, "jog")
            start = self.planned_mm(i)
            target = float(start + distance_mm)
            if self.soft_limits and not self._in_travel(target, i):
                raise StageRefused(Refusal.BEYOND_TRAVEL, f"jog to {target - self._offset(i):.3f} mm",
                                   "choose a target inside the travel")
            self._wait_planner()
            self._plan(i, "Jog", target, float(feed_mm_min))
            self._update()

    def jog_cancel(self) -> None:
        with self._command():
            p = self._motion.active()
            if p is not None and p.kind == "Jog" and self._motion.stopping is None:
                self._motion.decelerate(self.clock.now(), self._accel)
                self._update()

    def feed_hold(self) -> None:
        with self._command():
            state, _ = self._state()
            if state == "Jog":  # a hold cancels a jog (flushes it)
                self._motion.decelerate(self.clock.now(), self._accel)
            elif state in ("Run", "Idle"):
                self._motion.feed_hold(self.clock.now(), self._accel)
            self._update()

    def resume(self) -> None:
        with self._command():
            if self._motion.resume(self.clock.now(), self._accel):
                self._update()

    def stop(self) -> None:
        """A feed hold: the move decelerates and stops (resume continues it, a reset discards it)."""
        self.feed_hold()

    def start_home(self) -> None:
        """Begin homing (seek the low switch, pull off, locate slowly, pull off) without waiting."""
        with self._command():
            if not self.homing_enabled:
                raise StageRefused(Refusal.HOMING_DISABLED, "home")
            state, _ = self._state()
            if state not in ("Idle", "Alarm"):
                raise StageRefused(Refusal.NOT_IDLE, f"home in {state}")
            self._alarm = None
            i = AXES.index(self.axis)
            switch, pulloff = self.travel_mm[0], self.machine["homing_pulloff_mm"]
            seek, locate = self.machine["homing_seek_mm_min"], self.machine["homing_locate_mm_min"]
            self._plan(i, "Home", switch, seek)
            self._plan(i, "Home", switch + pulloff, seek)
            self._plan(i, "Home", switch, locate)
            self._plan(i, "Home", switch + pulloff, seek)
            self._homing = True
            self.homed = False
            self._update()

    def home(self) -> None:
        self.start_home()
        self.wait_idle(timeout_s=3600.0)

    def wait_idle(self, timeout_s: float = 60.0) -> StageStatus:
        """Advance (or sleep) the clock until Idle; HardwareError on alarm or after ``timeout_s``."""
        deadline = self.clock.now() + timeout_s
        simulated = isinstance(self.clock, SimClock)
        while True:
            st = self.status()
            if st.state == "Idle":
                return st
            if st.state == "Alarm":
                if self._alarm is not None and self._alarm is not Alarm.LOCK:
                    raise StageAlarm(self._alarm, "while waiting for the stage", self._alarm_hint(self._alarm))
                raise HardwareError(f"simulated stage: locked in Alarm; {self.lock_hint} first")
            now = self.clock.now()
            if now >= deadline:
                raise HardwareError(
                    f"simulated stage: still {st.state} after {timeout_s:g} s; resume a hold (~) or reset the stage"
                )
            nxt = self.next_event_s()
            dt = (nxt - now) if nxt is not None else deadline - now
            if not simulated:
                dt = min(dt, 0.05)
            self.clock.sleep(min(max(dt, 1e-6), deadline - now))

    # ------------------------------------------------------------------ settings
    def read_settings(self) -> list[StageSetting]:
        with self._lock:
            self.require_connected()
            return [StageSetting(NUMBER[s.key], self.machine[s.key], s.name, s.unit, s.description)
                    for s in MACHINE_SETTINGS]

    settings_title = "Simulated machine settings"
    lock_hint = "home it or unlock it"

    def setting_label(self, setting: StageSetting) -> str:
        return KEY.get(setting.number, str(setting.number))

    def travel_text(self, settings: list[StageSetting]) -> str:
        return travel_text({KEY[st.number]: st.value for st in settings if st.number in KEY})

    def write_setting(self, number: int, value: float) -> None:
        """Change setting ``number`` (see :meth:`read_settings`); refused while moving, for an unknown number,
        a negative value, or soft limits without homing (homing off turns soft limits off too)."""
        with self._command():
            key = KEY.get(number)
            context = f"setting {key or number} = {value:g}"
            state, _ = self._state()
            if state not in ("Idle", "Alarm"):
                raise StageRefused(Refusal.NOT_IDLE, context)
            if value < 0:
                raise StageRefused(Refusal.NEGATIVE_VALUE, context)
            if key is None:
                raise StageRefused(Refusal.UNKNOWN_SETTING, context)
            if key == "soft_limits" and value and not self.machine["homing"]:
                raise StageRefused(Refusal.SOFT_LIMITS_NEED_HOMING, context)
            self.set_machine(key, value)

    def set_machine(self, key: str, value: float) -> None:
        """Store named setting ``key`` unchecked (a wrapping firmware checked it by its own rules): flags are
        0 or 1, homing off turns soft limits off, the measured axis' travel moves its high end."""
        with self._lock:
            if key not in BY_KEY:
                raise StageRefused(Refusal.UNKNOWN_SETTING, f"setting {key}")
            self.machine[key] = float(bool(value)) if BY_KEY[key].flag else float(value)
            if key == "homing" and not value:
                self.machine["soft_limits"] = 0.0
            if key == f"travel_mm.{self.axis}":
                self.travel_mm = (self.travel_mm[0], self.travel_mm[0] + self.machine[key])
