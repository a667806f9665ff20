"""GRBL 1.1 over pyserial: a :class:`Stage` that speaks the real protocol.

The constructor takes a port name (anything ``serial.serial_for_url`` opens:
``/dev/ttyUSB0``, ``COM3``, ``socket://host:port``) or an already-open pyserial
object (an emulator's pty, a scripted fake in protocol tests); the line
traffic lives in :class:`~lps_gui.hardware.grbl.link.GrblLink`.

This module gives GRBL's messages their meaning for a stage: status reports
(MPos or WPos per ``$10``, the last WCO remembered, inches per ``$13``) become
:class:`StageStatus`; ``ALARM:N`` fails every line in flight and is raised by
the next wait; the banner means a reset; ``[MSG:]`` lines become events.
What GRBL 1.1h's source does after an alarm or during a hold (docs/hardware.md):
the lines an alarm cut short still get an ``ok`` (kept as orphans by the link);
ALARM:3 and 6-10 reset GRBL by itself 500 ms later (the next line waits for the
banner, a ``?`` is re-sent); ALARM:1/2 need a reset (lines are refused with
that advice); during a feed hold GRBL answers no line until ``~`` (new lines
are refused, lines in flight wait through the hold).
Moves and jogs are acknowledged when planned; :meth:`GrblStage.wait_idle`
polls ``?`` until the motion is over. Settings are written only with nothing
in flight (send-response), as GRBL's docs require for EEPROM writes.
Every wait has a deadline: a silent controller or a vanished port becomes a
one-line :class:`HardwareError`, never a hang.
"""
from __future__ import annotations

import threading
import time
from typing import Any

from lps_gui.errors import HardwareError
from lps_gui.hardware.grbl.codes import GrblError, format_setting, setting_info, stored_settings, travel_text
from lps_gui.hardware.grbl.link import ControllerReset, GrblLink, Pending
from lps_gui.hardware.grbl.protocol import (
    MM_PER_INCH,
    BuildInfo,
    Message,
    StatusReport,
    jog_line,
    move_line,
    parse_build_info,
    parse_offsets,
    parse_settings,
    parse_work_system,
)
from lps_gui.hardware.capabilities import Alarms, Console, FeedHold, Jogging, Settings, WorkCoordinates
from lps_gui.hardware.stage import WORK_SYSTEMS, Stage, StageEvent, StageSetting, StageStatus

RT_STATUS, RT_HOLD, RT_RESUME, RT_RESET, RT_JOG_CANCEL = b"?", b"!", b"~", b"\x18", b"\x85"
RESETS_AFTER_OK = ("[MSG:Disabled]", "[MSG:Restoring defaults]")  # system.c: mc_reset() after these
CRITICAL_ALARMS = (1, 2)  # protocol_exec_rt_system(): hard/soft limit block everything until a reset
SELF_RESET_ALARMS = (3, 6, 7, 8, 9, 10)  # raised with mc_reset(): GRBL re-initializes on its own
HELD_STATES = ("Hold", "Door")  # protocol_exec_rt_suspend(): no line is read until resumed
MOVING_STATES = ("Run", "Jog")
HOLD_IGNORED_STATES = ("Alarm", "Check", "Sleep", "Home")  # protocol_exec_rt_system(): no hold there  # a line may wait for planner space (mc_line) or the end of motion (G4)
UNLOCK_MESSAGE = "'$H'|'$X' to unlock"
__all__ = ["ControllerReset", "GrblStage"]


class GrblStage(Stage, Settings, Console, WorkCoordinates, Jogging, FeedHold, Alarms):
    """A GRBL 1.1 controller on a serial port.

    Parameters
    ----------
    port : port name/URL, or an open (or openable) pyserial-like object.
    baudrate : GRBL's default is 115200.
    timeout_s : longest wait for any reply (homing has its own, longer, limit).
    axis : the axis the measurement moves along.
    poll_interval_s : status polling period while waiting for motion (GRBL: <= 10 Hz recommended 5 Hz).
    homing_timeout_s : longest homing cycle.
    reset_on_connect : send a soft reset on connect and wait for the banner (a real
        Arduino also resets when the port opens); otherwise just ask for ``$I``.
    """

    settings_title = "Controller settings ($$)"
    console_hint = "G-code or $ command, e.g. $$  $#  G0 X10  (Up/Down: history)"
    lock_hint = "home it ($H) or unlock it ($X)"

    def __init__(
        self,
        port: Any,
        baudrate: int = 115200,
        timeout_s: float = 5.0,
        axis: str = "X",
        poll_interval_s: float = 0.05,
        homing_timeout_s: float = 300.0,
        reset_on_connect: bool = True,
    ) -> None:
        super().__init__()
        self.axis = axis
        self.link = GrblLink(port, baudrate, timeout_s, self._on_message)
        self.poll_interval_s = poll_interval_s
        self.homing_timeout_s = homing_timeout_s
        self.reset_on_connect = reset_on_connect
        self.build_info: BuildInfo | None = None
        self.version = ""
        self.settings: dict[int, float] = {}
        self._status_lock = threading.Lock()
        self._banners = 0
        self._status: StageStatus | None = None
        self._status_seq = 0
        self._wco = (0.0, 0.0, 0.0)
        self._overrides: tuple[int, int, int] | None = None
        self._alarm_code: int | None = None
        self._critical = False
        self._reset_due = False
        self._held = False
        self._locked = False
        self._homing = False
        self._reset_ready = False  # [MSG:Reset to continue] seen: a reset now is not lost
        self._last_state = ""
        self._idle_since: float | None = None  # Idle seen while a dwell is in flight
        self._last_busy_pos: tuple | None = None

    @property
    def port_name(self) -> str:
        return self.link.port_name

    @property
    def timeout_s(self) -> float:
        return self.link.timeout_s

    @timeout_s.setter
    def timeout_s(self, value: float) -> None:
        self.link.timeout_s = value

    @property
    def locked(self) -> bool:
        """GRBL is in its alarm lock (power-up with homing enabled, after an alarm): home or unlock first."""
        return self._locked

    @property
    def garbage_lines(self) -> int:
        """Unrecognized lines skipped so far (line noise, a wrong baud rate)."""
        return self.link.garbage_lines

    # ------------------------------------------------------------------ connection
    def connect(self) -> None:
        """Open the port, reset (or not) the controller, read ``$I``, ``$$`` and one status."""
        if self.connected:
            return
        self._critical = self._homing = self._reset_due = self._held = self._locked = False
        self.link.open()
        try:
            if self.reset_on_connect:
                n = self._banners
                self.link.write(RT_RESET)
                self.link.wait_for(lambda: self._banners > n, self.timeout_s,
                                   f"no GRBL startup banner within {self.timeout_s:g} s; "
                                   f"is a GRBL 1.1 controller on this port at {self.link.baudrate} baud?")
                # The banner may be the boot banner of a board that reset as the port opened, with our
                # reset byte still to act on (a second banner). protocol_exec_rt_system() acts on a reset
                # before it reports, and our '?' follows the reset byte: once a report is in, every banner
                # our reset causes is in, and no line is lost in it.
                self.status()
            self.build_info = parse_build_info(self.command("$I"))
            self.link.rx_size = self.build_info.rx_buffer_bytes
            self.settings = parse_settings(self.command("$$"))
            if not self.settings:
                raise HardwareError(f"GRBL on {self.port_name}: '$$' listed no settings; reset the controller and connect again")
            self.status()
        except Exception:
            self.link.close()
            raise
        self.events.emit(StageEvent("connected", text=f"GRBL {self.version or self.build_info.version} on {self.port_name}"))

    def disconnect(self) -> None:
        self.link.close()
        self.events.emit(StageEvent("disconnected", text=f"disconnected from {self.port_name}"))

    @property
    def connected(self) -> bool:
        return self.link.alive

    def require_connected(self) -> None:
        if self.link.dead is not None:
            raise self.link.dead
        super().require_connected()

    # ------------------------------------------------------------------ what GRBL says on its own
    def _on_message(self, msg: Message) -> None:
        kind = msg.kind
        if kind == "status":
            self._on_status(msg.status)
        elif kind == "error":
            self.events.emit(StageEvent("error", code=msg.code, text=msg.text))
        elif kind == "alarm":
            code = int(msg.code)
            self._alarm_code = code
            self._locked = True
            with self.link.cond:
                self._reset_ready = self._reset_ready and code not in CRITICAL_ALARMS
                self._critical = self._critical or code in CRITICAL_ALARMS
                self._reset_due = self._reset_due or code in SELF_RESET_ALARMS
            err = GrblError("alarm", code, f"GRBL on {self.port_name}")
            self.link.orphan_pending(err)
            self.events.emit(StageEvent("alarm", code=msg.code, text=str(err), reason=err.reason))
        elif kind == "banner":
            self.version = msg.text
            self._critical = self._reset_due = self._held = self._reset_ready = False
            self.link.fail_pending(ControllerReset(
                f"GRBL on {self.port_name} was reset while a command was in flight; check the stage state"))
            with self.link.cond:
                self._banners += 1
                self.link.cond.notify_all()
            self.events.emit(StageEvent("message", text=f"Grbl {msg.text} started"))
        elif kind == "msg":
            if msg.text == UNLOCK_MESSAGE:
                self._locked = True
            if msg.text == "Reset to continue":
                self._critical = self._reset_ready = True
                with self.link.cond:
                    self.link.cond.notify_all()
            self.events.emit(StageEvent("message", text=msg.text))
        elif kind == "disconnected":
            self.events.emit(StageEvent("disconnected", text=msg.text))

    def _on_status(self, r: StatusReport) -> None:
        scale = MM_PER_INCH if self.settings.get(13) else 1.0
        if r.wco is not None:
            self._wco = tuple(v * scale for v in r.wco)
        if r.overrides is not None:
            self._overrides = r.overrides
        if r.mpos is not None:
            machine = tuple(v * scale for v in r.mpos)
            work = tuple(m - o for m, o in zip(machine, self._wco))
        else:
            work = tuple(v * scale for v in r.wpos)
            machine = tuple(w + o for w, o in zip(work, self._wco))
        st = StageStatus(
            state=r.state, substate=r.substate, machine_mm=machine, work_mm=work,
            feed_mm_min=(r.feed or 0.0) * scale, spindle_rpm=r.spindle or 0.0, buffer=r.buffer,
            overrides=self._overrides, pins=r.pins, time=time.monotonic(),
        )
        with self.link.cond:
            self._status = st
            self._status_seq += 1
            self.link.cond.notify_all()
        self._held = r.state in HELD_STATES
        if r.state == "Idle":
            self._locked = False
        if r.state != self._last_state:
            self._last_state = r.state
            self.events.emit(StageEvent("state", text=r.state))

    # ------------------------------------------------------------------ lines
    def send(self, line: str, timeout_s: float | None = None, refuse_in_hold: bool = True) -> Pending:
        """Queue a line with character counting; see :meth:`GrblLink.send`.

        Refused while GRBL would not read it: in a critical alarm (its reset flushes
        the line unanswered) and, unless ``refuse_in_hold`` is off (the rest of a
        stream that began before the hold), in a feed hold (answered only after
        ``~``). After an alarm that resets GRBL by itself, the line waits for the
        banner (sent earlier, the reset would flush it).
        """
        self.require_connected()
        self._refuse_if_critical(line)
        if self._reset_due:
            self.link.wait_for(lambda: not self._reset_due, self.timeout_s,
                               f"no reset banner within {self.timeout_s:g} s after ALARM:{self._alarm_code}; reset the controller")
        if refuse_in_hold and self._held and self.status().state in HELD_STATES:
            raise HardwareError(f"GRBL on {self.port_name} is in a feed hold: {line.strip()!r} not sent; "
                                f"resume (~) or reset the controller first")
        return self.link.send(line, timeout_s, keep_waiting=self._still_busy)

    def _refuse_if_critical(self, what: str) -> None:
        if self._critical:
            code = self._alarm_code if self._alarm_code in CRITICAL_ALARMS else 2
            raise HardwareError(
                f"GRBL on {self.port_name}: {GrblError('alarm', code).args[0].split('.')[0]} needs a reset "
                f"('Reset to continue'): {what.strip()!r} not sent; reset the controller, then unlock ($X) or home ($H)")

    def _still_busy(self) -> bool:
        """A reply is overdue: is GRBL alive and holding it back legitimately (not a cable fault)?

        GRBL answers a line only once it is planned (mc_line() waits for a free
        planner block), a dwell only after the planner empties and P seconds pass,
        nothing during a feed hold. A controller that answers ``?`` with Hold or
        Door, with Run or Jog while its position or feed says it moves, or with
        Idle while a dwell is in flight (for that dwell's P), is alive: the line
        waits. Only silence to ``?`` (or a controller idle with nothing to wait
        for) is a fault.
        """
        try:
            st = self.status()
        except HardwareError:
            return False
        if st.state in HELD_STATES or st.state == "Home":
            self._idle_since = None
            return True
        if st.state in MOVING_STATES:
            moved = st.machine_mm != self._last_busy_pos
            self._last_busy_pos = st.machine_mm
            self._idle_since = None
            return moved or st.feed_mm_min > 0
        dwell = self.link.dwell_in_flight_s()
        if st.state not in ("Idle", "Check") or dwell <= 0:
            return False
        now = time.monotonic()
        if self._idle_since is None:
            self._idle_since = now
        return now - self._idle_since < dwell

    def command(self, line: str, timeout_s: float | None = None) -> list[str]:
        """Send one line and wait for its ``ok`` (send-response); return the lines it printed.

        Leaving check mode (``$C``) and ``$RST=`` make GRBL reset right after its
        ``ok``; then this also waits for the banner, so the next line is not lost.
        """
        n = self._banners
        self._idle_since = None
        lines = self.link.wait_reply(self.send(line, timeout_s), timeout_s, keep_waiting=self._still_busy)
        if any(ln in RESETS_AFTER_OK for ln in lines):
            self.link.wait_for(lambda: self._banners > n, self.timeout_s, f"no banner after {line!r} within {self.timeout_s:g} s")
        return lines

    def stream(self, lines: list[str], timeout_s: float | None = None) -> None:
        """Stream G-code with character counting; wait for every ``ok``; raise on the first error.

        A feed hold that begins mid-stream holds the stream (GRBL buffers the
        rest and runs it after ``~``); a stream is refused only if it starts in a hold.
        """
        self._idle_since = None
        todo = [ln for ln in lines if ln.strip()]
        sent = [self.send(ln, timeout_s, refuse_in_hold=k == 0) for k, ln in enumerate(todo)]
        for p in sent:
            self.link.wait_reply(p, timeout_s, keep_waiting=self._still_busy)

    def realtime(self, byte: bytes) -> None:
        """Send a real-time command byte (never counted, acted on at once)."""
        self.require_connected()
        self.link.write(byte)

    # ------------------------------------------------------------------ Stage: state
    def status(self) -> StageStatus:
        """Ask ``?`` and return the report (cached while GRBL ignores ``?``: homing, critical alarm)."""
        self.require_connected()
        if self._homing or self._critical:
            st = self._status or StageStatus(state="Alarm")
            state = "Home" if self._homing else "Alarm"
            return StageStatus(state, None, st.machine_mm, st.work_mm, 0.0, time=time.monotonic())
        with self._status_lock:
            n = self._status_seq
            self.realtime(RT_STATUS)
            # a reset swallows a pending '?' (main.c clears the flags): ask again while waiting;
            # GRBL ignores extra '?' before its report
            self.link.wait_for(lambda: self._status_seq > n or self._critical, self.timeout_s,
                               f"no status report within {self.timeout_s:g} s; check the cable or reset the controller",
                               retry=lambda: self.realtime(RT_STATUS))
        return self._status if not self._critical else self.status()

    def home(self) -> None:
        """``$H``; a homing failure (ALARM:6-9) raises, and GRBL resets itself right after."""
        self._refuse_if_critical("$H")
        self._homing = True
        try:
            self.command("$H", timeout_s=self.homing_timeout_s)
            self._alarm_code = None
            self._locked = False
        finally:
            self._homing = False

    def unlock(self) -> None:
        """``$X``; in a critical alarm (ALARM:1/2) GRBL needs a reset first, and this says so."""
        self._refuse_if_critical("$X")
        self.command("$X")
        self._alarm_code = None
        self._locked = False

    def soft_reset(self) -> None:
        """Ctrl-X and wait for the banner (GRBL raises ALARM:3 if it was moving).

        After ALARM:1/2, protocol_exec_rt_system() prints the alarm, waits 500 ms
        (report.c), prints ``[MSG:Reset to continue]`` and then clears the reset
        flag: a reset sent before that message is lost. So the reset goes out
        once the message is in (or, if it never comes, after the timeout, and
        once more if that one brought no banner).
        """
        n = self._banners
        if self._critical and not self._reset_ready:
            try:
                self.link.wait_for(lambda: self._reset_ready or self._banners > n, self.timeout_s, "")
            except HardwareError:
                if self.link.dead is not None:
                    raise
        if self._banners > n:
            self._critical = False
            return
        blind = self._critical and not self._reset_ready  # the message never came: this reset may be cleared
        what = f"no banner within {self.timeout_s:g} s after a soft reset"
        self.realtime(RT_RESET)
        try:
            self.link.wait_for(lambda: self._banners > n, self.timeout_s, what)
        except HardwareError:
            if not blind or self.link.dead is not None:
                raise
            self.realtime(RT_RESET)
            self.link.wait_for(lambda: self._banners > n, self.timeout_s, what)
        self._critical = False

    def feed_hold(self) -> None:
        """``!`` and wait until GRBL reports the hold (or that it ignores or only cancels it).

        A report asked for before the ``!`` may arrive after it (a poll from
        another thread, a USB adapter's latency): protocol_exec_rt_system() even
        reports before it acts on a hold that came with the ``?``. Such a report
        says Idle or Run; believed, the next line would be sent into the hold and
        wait for ``~`` forever. So only a report that shows the hold ends the wait;
        a jog that the hold cancels ends Idle.
        """
        self.realtime(RT_HOLD)
        self._held = True  # until a status report says otherwise (a hold in Jog only cancels it)
        jogging = False

        def held(st: StageStatus) -> bool:
            nonlocal jogging
            jogging = jogging or st.state == "Jog"
            return st.state in HELD_STATES or st.state in HOLD_IGNORED_STATES or (jogging and st.state == "Idle")

        self._await_report(held, "did not report the feed hold")

    def resume(self) -> None:
        """``~`` once the hold is complete, then wait until GRBL reports it left the hold.

        protocol_exec_rt_system() ignores a cycle start while a hold still
        decelerates (Hold:1), and a report asked before the ``~`` still says Hold:
        a line sent on it would be refused as "in a feed hold".
        """
        st = self.status()
        if st.state == "Door" and st.substate == 1:
            raise HardwareError(f"GRBL on {self.port_name}: the safety door is open (Door:1); close it, then resume")
        if st.state == "Hold" and st.substate == 1:
            self._await_report(lambda s: not (s.state == "Hold" and s.substate == 1), "did not complete the feed hold")
        self.realtime(RT_RESUME)
        if self._held or st.state in HELD_STATES:
            self._await_report(lambda s: s.state not in HELD_STATES, "is still in a hold after '~'")

    def _await_report(self, done, what: str) -> None:
        """Poll ``?`` until a report satisfies ``done``; the deadline moves while the carriage moves."""
        deadline = time.monotonic() + self.timeout_s
        last = None
        while True:
            st = self.status()
            if done(st):
                return
            if st.machine_mm != last:
                last, deadline = st.machine_mm, time.monotonic() + self.timeout_s
            if time.monotonic() >= deadline:
                raise HardwareError(f"GRBL on {self.port_name} {what} within {self.timeout_s:g} s "
                                    f"(state {st.state}); reset the controller")
            time.sleep(self.poll_interval_s)

    def stop(self) -> None:
        """A feed hold: the move decelerates and stops (resume continues it, a reset discards it)."""
        self.feed_hold()

    # ------------------------------------------------------------------ Stage: motion
    def move_to(self, position_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        self._alarm_code = None
        self.command(move_line(position_mm, feed_mm_min, axis or self.axis))

    def jog(self, distance_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        self.command(jog_line(distance_mm, feed_mm_min, axis or self.axis))

    def jog_cancel(self) -> None:
        self.realtime(RT_JOG_CANCEL)

    # ------------------------------------------------------------------ Stage: work coordinates
    work_systems = WORK_SYSTEMS

    def work_system(self) -> str:
        """The active system from ``$G`` (G54 if the reply names none)."""
        return parse_work_system(self.command("$G")) or WORK_SYSTEMS[0]

    def select_work_system(self, name: str) -> None:
        if name not in WORK_SYSTEMS:
            raise HardwareError(f"work coordinate system {name!r} unknown; choose one of {', '.join(WORK_SYSTEMS)}")
        self.command(name)

    def work_offsets(self) -> dict[str, tuple[float, float, float]]:
        """``$#``: the stored offsets in mm (GRBL's sign: work = machine - offset)."""
        scale = MM_PER_INCH if self.settings.get(13) else 1.0
        return {name: tuple(v * scale for v in axes)  # type: ignore[misc]
                for name, axes in parse_offsets(self.command("$#")).items() if name in WORK_SYSTEMS}

    def set_work_zero(self, axis: str | None = None, value_mm: float = 0.0) -> None:
        """Make the current position read ``value_mm`` on ``axis`` in the active system (``G10 L20 P0``).

        P0 is the active system (G54 = P1 ... G59 = P6), kept in EEPROM; GRBL
        reports the new WCO in the next status report, so :meth:`status` stays right.
        """
        self.command(f"G10 L20 P0 {(axis or self.axis).upper()}{value_mm:.3f}")

    def wait_idle(self, timeout_s: float = 60.0) -> StageStatus:
        """Poll ``?`` until Idle with nothing in flight; alarms and timeouts raise.

        GRBL may report Idle for a moment after acknowledging a move (before the
        cycle starts), so Idle counts when the planner reports empty (``Bf``, with
        ``$10`` bit 1) or two reports in a row agree.
        """
        deadline = time.monotonic() + timeout_s
        idle_reports = 0
        blocks = self.build_info.planner_blocks if self.build_info else 15
        while True:
            if self._alarm_code is not None:
                raise GrblError("alarm", self._alarm_code, f"GRBL on {self.port_name} while waiting for motion to end")
            st = self.status()
            if st.state == "Alarm":
                if self._alarm_code is not None:
                    continue
                raise HardwareError(f"GRBL on {self.port_name}: locked in Alarm; home ($H) or unlock ($X) first")
            if st.state == "Sleep":
                raise HardwareError(f"GRBL on {self.port_name}: the controller is asleep ($SLP); reset it, then home or unlock")
            if st.state in ("Idle", "Check") and not self.link.in_flight:  # Check: $C mode, nothing moves
                idle_reports += 1
                if idle_reports >= 2 or (st.buffer is not None and st.buffer[0] >= blocks):
                    return st
            else:
                idle_reports = 0
            if time.monotonic() >= deadline:
                raise HardwareError(
                    f"GRBL on {self.port_name}: still {st.state} after {timeout_s:g} s; resume a hold (~) or reset the stage"
                )
            time.sleep(self.poll_interval_s)

    # ------------------------------------------------------------------ Stage: settings
    def read_settings(self) -> list[StageSetting]:
        self.settings = parse_settings(self.command("$$"))
        out = []
        for n, v in sorted(self.settings.items()):
            info = setting_info(n)
            out.append(StageSetting(n, v, info.name, info.unit, info.description))
        return out

    def setting_label(self, setting: StageSetting) -> str:
        return f"${setting.number}"

    def travel_text(self, settings: list[StageSetting]) -> str:
        return travel_text({st.number: st.value for st in settings})

    def write_setting(self, number: int, value: float) -> None:
        """``$N=value``, sent only with nothing in flight (EEPROM writes stall GRBL's serial)."""
        self.link.wait_for(lambda: not self.link.in_flight, self.timeout_s, "commands still unanswered before a settings write")
        self.command(format_setting(number, value))
        self.settings.update(stored_settings(number, value))  # settings.c: $22=0 also clears $20

    def describe(self) -> dict:
        d = {**super().describe(), "port": str(self.port_name), "baudrate": self.link.baudrate}
        if self.build_info is not None:
            d.update(version=self.build_info.version, build=self.build_info.build, options=self.build_info.options)
        d["settings"] = {f"${n}": v for n, v in sorted(self.settings.items())}
        return d
