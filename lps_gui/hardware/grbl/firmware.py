"""GRBL 1.1h's behaviour, independent of the wire: RX buffer, real-time bytes, lines, states, reports.

:class:`GrblFirmware` is what runs inside the controller, transcribed from
gnea/grbl (report.c, protocol.c, system.c, settings.c, gcode.c, jog.c,
limits.c, motion_control.c; docs/hardware.md lists what was checked where):
banner and homing-lock message after every reset, ``$``, ``$$``, ``$x=val``,
``$#``, ``$G``, ``$I``, ``$N`` and startup lines, ``$C``, ``$X``, ``$H``,
``$SLP``, ``$RST=`` (defaults.h), ``$J=``, G-code as gcode.c checks and
executes it (G0-G3, G4, G10 L2/L20, G17-G19, G20/G21, G28/G30 and their .1,
G38.x probing with no probe wired, G43.1/G49, G53, G54-G59, G80, G90/G91,
G92/G92.1, G93/G94, M0-M9), real-time ``?`` ``!`` ``~`` 0x18 0x85, the safety
door 0x84, feed/rapid/spindle overrides and the flood toggle, status reports
per ``$10`` with GRBL's WCO/Ov refresh counters and ``Pn:``, a 128-byte RX
buffer that protocol_main_loop() drains as bytes arrive (overflowing bytes
dropped while a line executes), a 15-block planner that makes a line wait,
hard-limit switches at the travel ends (``$21``), and alarms as protocol.c raises them: ``ALARM:N``, then
report.c's 500 ms delay; critical ones (1, 2) then print ``[MSG:Reset to
continue]``, drop any reset that came in the delay and ignore everything but
a new reset. Motion happens in a :class:`SimulatedStage`, which speaks no
protocol: its refusals and alarms come back as GRBL's codes (``codes.as_grbl``),
and ``$N`` reads and writes its named settings (``grbl/settings.py``). Machine
coordinates are GRBL's homed space (0 at the top of the travel, negative
below); G54 is stored as the base, so G54 work coordinates equal the stage's
own coordinates. Multi-axis moves run one axis after the other; arcs are
checked along mc_arc()'s segments and end at their target; the probe never
touches and the door switch reads closed (docs/hardware.md: by design).

It writes through a ``send(line)`` callback, so the pty transport
(``emulator.py``) adds timing and fault injection around it.
"""
from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Callable, Iterator

from lps_gui.hardware.grbl import codes
from lps_gui.hardware.grbl.codes import GrblError, format_setting
from lps_gui.hardware.grbl import gcode as gc
from lps_gui.hardware.grbl.gcode import CodeError, ParserState, check_block, read_float
from lps_gui.hardware.grbl.protocol import MM_PER_INCH, StatusReport, format_axes, format_status
from lps_gui.hardware.grbl.settings import GrblSettings
from lps_gui.hardware.line_emulator import LinkedFirmware, LinkFaults
from lps_gui.hardware.refusals import StageAlarm, StageRefused
from lps_gui.hardware.sim_stage import PLANNER_BLOCKS, SimulatedStage
from lps_gui.hardware.stage import AXES

log = logging.getLogger(__name__)

VERSION, BUILD = "1.1h", "20190830"
BANNER = f"\r\nGrbl {VERSION} ['$' for help]\r\n"
HELP = "[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]"
RT_STATUS, RT_HOLD, RT_RESUME, RT_RESET, RT_JOG_CANCEL, RT_DOOR = 0x3F, 0x21, 0x7E, 0x18, 0x85, 0x84
FEED_OVR_RANGE, SPINDLE_OVR_RANGE = (10, 200), (10, 200)  # config.h MIN/MAX_FEED_RATE_OVERRIDE, ..._SPINDLE_SPEED_...
BUSY = ("Run", "Hold", "Jog", "Home", "Door")
RX_BUFFER_BYTES = 128  # serial.h RX_BUFFER_SIZE
ALARM_REPORT_DELAY_S = 0.5  # report.c report_alarm_message(): delay_ms(500) after ALARM:N
CRITICAL_ALARMS = (1, 2)  # protocol_exec_rt_system(): hard and soft limit
WCO_BUSY, WCO_IDLE, OVR_BUSY, OVR_IDLE = 30, 10, 20, 10  # config.h refresh counts
TRAVEL_EPS_MM = 1e-6  # float noise of offset arithmetic, far below GRBL's step resolution
Steps = Iterator[None]  # an executing line: each yield waits for simulated time to pass
SILENT = object()  # returned by steps that print no 'ok' when they end (startup lines after a reset)


def _parameter(cmd: str, start: int) -> tuple[float, int]:
    """system.c's default branch: the number read_float() finds at ``start`` (error:2), then '=' (error:3).

    Returns the number and the index after the '='.
    """
    got = read_float(cmd, start)
    if got is None:
        raise CodeError(2)
    number, i = got
    if cmd[i:i + 1] != "=":
        raise CodeError(3)
    return number, i + 1


@dataclass
class Faults(LinkFaults):
    """The link's fault switches (a vanished port, slow replies, garbage: line_emulator.LinkFaults) and GRBL's own
    (read on every step; flip them any time).

    alarm_mid_move : raise ALARM:<code> half-way through the next move or jog, once (None: never).
    error_every : answer every Nth command line with ``error:<error_code>`` instead of executing it.
    fail_homing : every ``$H`` fails half-way with ``ALARM:<code>`` (8: pull-off did not clear
        the switch, 9: switch not found), then the ``ok`` of ``$H`` and a self-reset (limits.c).
    """

    alarm_mid_move: int | None = None
    error_every: int = 0
    error_code: int = 20
    fail_homing: int | None = None


class GrblFirmware(LinkedFirmware):
    """GRBL 1.1h's serial ISR and protocol loop over a :class:`SimulatedStage`.

    Feed received bytes to :meth:`receive`, call :meth:`poll` often (it runs
    the executing line and executes complete lines); output goes to ``send``.
    ``on_drop`` is called when the drop-after-lines fault fires.
    ``homing_init_lock`` is config.h's HOMING_INIT_LOCK (stock 1.1h: on): with
    ``$22=1`` the controller powers up in Alarm; off, ``[OPT:]`` carries ``L``.
    """

    def __init__(self, stage: SimulatedStage, faults: Faults, send: Callable[[str], None], on_drop: Callable[[], None],
                 homing_init_lock: bool = False) -> None:
        super().__init__(faults, send, on_drop)
        self.faults: Faults = faults
        self.stage = stage
        self.homing_init_lock = homing_init_lock
        self.rx_overflow_bytes = 0  # bytes dropped because the host overran the 128-byte RX buffer
        self.lines_received = 0
        self.resets_received = 0  # Ctrl-X bytes, and those an alarm's delay swallowed
        self.resets_lost = 0
        self._booting = False
        self._n_cmd = 0
        self._build_user = ""
        self._limit_hit: set[int] = set()  # axes whose hard-limit switch is pressed (physical: survives resets)
        self._startup = ["", ""]  # EEPROM startup lines $N0, $N1 (N_STARTUP_LINE 2)
        self.settings = GrblSettings(stage)  # $N: the stage's named settings and the firmware's own
        self._coords = self._default_coords()  # EEPROM: G54-G59, G28, G30 (machine mm); survives resets
        self._reset_state()

    @property
    def busy(self) -> bool:
        """Something waits on time (a line, a move, an alarm's delay): poll often."""
        return (self._pending is not None or self._abort_at is not None or self._critical_msg_at is not None
                or self.stage.next_event_s() is not None)

    @property
    def options(self) -> str:
        """``[OPT:]`` letters: V (variable spindle), L (built without HOMING_INIT_LOCK)."""
        return "V" + ("" if self.homing_init_lock else "L")

    @property
    def parser(self) -> ParserState:
        """The G-code parser state (gcode.c gc_state), for tests and the docs' examples."""
        return self._gc

    def poll(self) -> None:
        """Run the executing line, fire a due alarm message or self-reset, execute complete lines.

        During a feed hold nothing runs: protocol.c calls protocol_execute_realtime()
        at every line end (and mc_line() in its planner-full loop), and that stays
        in protocol_exec_rt_suspend() while sys.suspend is set, so no line is
        answered until ``~`` (only ``?``, ``~``, ``!`` and Ctrl-X act). Asleep,
        only real-time bytes act until a reset. After an alarm that resets GRBL
        by itself, no line is read before the reset, which flushes them all.
        """
        self._check_mid_move_alarm()
        self._check_hard_limit()
        now = self.stage.clock.now()
        if self._critical_msg_at is not None and now >= self._critical_msg_at:
            self._critical_msg_at = None
            self._send("[MSG:Reset to continue]")
        if self._abort_at is not None:
            if now < self._abort_at:
                return
            self._finish_abort()
        if self._critical or self.halted or self._sleep or self._held():
            return
        if self._pending is not None:
            self._step_pending()
        self.drain()

    def _ready(self) -> bool:
        return (self._pending is None and self._abort_at is None and not self._critical and not self.halted
                and not self._sleep)

    def drain(self) -> None:
        """protocol_main_loop(): take bytes out of the RX buffer while no line executes; run each line at its end.

        The loop filters as it reads (whitespace and control characters, ``(...)``
        and ``;`` comments, ``/`` dropped, letters upcased, characters past the
        80-byte line buffer flagged as overflow), so a long line with a comment
        never needs to fit in the 128-byte RX buffer.
        """
        while self._rx and self._ready() and not self._held():
            c = chr(self._rx.pop(0))
            if c in "\r\n":
                line, overflow = "".join(self._linebuf), self._line_overflow
                self._linebuf, self._line_comment, self._line_overflow = [], "", False
                self._end_of_line(line, overflow)
            elif self._line_comment or self._line_overflow:
                if c == ")" and self._line_comment == "(":
                    self._line_comment = ""
            elif c <= " " or c == "/":
                pass
            elif c in "(;":
                self._line_comment = c
            elif len(self._linebuf) >= gc.LINE_BUFFER_SIZE - 1:
                self._line_overflow = True
            else:
                self._linebuf.append(c.upper())

    def _step_pending(self) -> None:
        """Advance the executing line; its ``ok`` when it ends, its error or alarm when it fails."""
        try:
            next(self._pending)
        except StopIteration as stop:
            self._pending = None
            if stop.value is not SILENT:
                self._send("ok")
        except CodeError as e:
            self._pending = None
            self._send(f"error:{e.code}")
        except (GrblError, StageRefused, StageAlarm) as e:
            self._pending = None
            self._failed(e)

    def _failed(self, e: GrblError | StageRefused | StageAlarm) -> None:
        """A line failed: ``error:N``, or the alarm it raised; the stage's neutral reasons said as GRBL's codes."""
        g = e if isinstance(e, GrblError) else codes.as_grbl(e)
        if g.kind == "alarm":
            self._alarm(g.code, line_open=True)
        else:
            self._send(f"error:{g.code}")

    @property
    def alarm_code(self) -> int | None:
        """GRBL's number of the stage's alarm (0: the silent homing lock), None when not in Alarm."""
        return codes.alarm_number(self.stage.alarm)

    def _trigger(self, code: int) -> None:
        """Lock the stage in Alarm for GRBL's ``ALARM:code`` (0: the homing lock)."""
        self.stage.trigger_alarm(codes.ALARM_REASONS[code])

    def _held(self) -> bool:
        return self.stage.status().state == "Hold" or self._door

    def power_up(self, boot_race: bool = False) -> None:
        """main.c at power-up: with HOMING_INIT_LOCK and ``$22=1`` the state is Alarm, then the welcome.

        ``boot_race``: the board boots as the host opens the port, so the welcome
        waits for the host's first byte; a reset byte that came during init is
        acted on right after it (a second banner).
        """
        if self.homing_init_lock and self.stage.homing_enabled and self.alarm_code is None:
            self._trigger(0)  # the silent homing lock (no ALARM:N line)
        self._booting = boot_race
        if not boot_race:
            self.welcome()

    def _default_coords(self) -> list[list[float]]:
        """What this emulator's EEPROM holds when new: G54 at the base, the rest zero (docs/hardware.md)."""
        return [list(self._base())] + [[0.0, 0.0, 0.0] for _ in range(7)]

    def _reset_state(self) -> None:
        """main.c's loop after every abort: flags cleared, RX flushed, gc_init(), positions synced."""
        self._rx = bytearray()  # serial.c's RX ring: bytes the main loop has not read yet
        self._linebuf: list[str] = []  # protocol_main_loop()'s line buffer, filtered as it is read
        self._line_comment = ""
        self._line_overflow = False
        self._gc = ParserState(coord_system=list(self._coords[0]))
        self._gc.position = self._machine_planned()
        self._spindle_rpm = 0.0
        self._wco_counter = 0
        self._ovr_counter = 0
        self._critical = False
        self._critical_msg_at: float | None = None  # report.c's delay before [MSG:Reset to continue]
        self._ok_on_reset = False  # a line was executing when a critical alarm hit: its ok follows the reset
        self._status_in_homing = False  # a '?' during homing is answered when the cycle ends
        self._abort_at: float | None = None  # an alarm's self-reset is due (after report.c's 500 ms delay)
        self._pending: Steps | None = None
        self._check = False
        self._sleep = False
        self._stuck_homing = False  # system.c '$H' sets STATE_HOMING before it rejects '$HX'
        self._probe_mpos = [0.0, 0.0, 0.0]  # sys_probe_position: cleared by main() on every reset
        self._probe_ok = False
        self._ovr = [100, 100, 100]  # main(): feed, rapid, spindle overrides back to 100 % on every reset
        self._flood = False
        self._door = False  # 0x84 came: Door until '~'
        self._door_in_homing = False
        self._hard_limit_at: tuple[int, float] | None = None  # a move planned into a switch: (axis, where)
        self._homing_pulloff = False  # the homing cycle pulls off its switch (limits.c: !approach)

    def welcome(self) -> None:
        """What GRBL prints at power-up and after every reset (main.c, protocol_main_loop()).

        The state survives a reset (main.c keeps ``prior_state``), so the unlock
        message follows the banner whenever the controller comes up in Alarm: at
        power-up with the homing lock, and after a reset out of an alarm.
        """
        self._send(BANNER)
        if self.settings[21] and self._limits_pressed():  # protocol.c CHECK_LIMITS_AT_INIT
            if self.alarm_code is None:
                self._trigger(0)  # sys.state = STATE_ALARM, no ALARM:N line
            self._send("[MSG:Check Limits]")
        if self.alarm_code is not None:
            self._send("[MSG:'$H'|'$X' to unlock]")
        elif any(self._startup):
            self._pending = self._after_welcome()

    def _after_welcome(self) -> Steps:
        yield from self._startup_lines()
        return SILENT

    def _startup_lines(self) -> Steps:
        """system.c system_execute_startup(): each stored line through gc_execute_line(), ``>line:ok`` or ``>line:error:N``."""
        for text in self._startup:
            if not text:
                continue
            try:
                yield from self._gcode(text)
            except CodeError as e:
                self._send(f">{text}:error:{e.code}")
            else:
                self._send(f">{text}:ok")

    def _base(self) -> tuple[float, float, float]:
        """Machine 0 sits at the top of the travel: machine = stage coordinate + base.

        The simulated stage's own work offsets stay zero under the emulator (its
        coordinates are its machine ones); the firmware keeps GRBL's offsets itself.
        """
        return (-self.stage.travel_mm[1],) * 3  # type: ignore[return-value]

    def _machine_planned(self) -> list[float]:
        """Where the planner will leave each axis, in machine mm (the parser's position when synced)."""
        return [self.stage.planned_mm(i) + b for i, b in enumerate(self._base())]

    def _status_line(self) -> str:
        st = self.stage.status()
        state = self._state()
        sub = st.substate if state == st.state else None
        if state == "Door":  # report.c: 2 while the hold stops the motion, 0 once stopped with the door closed
            sub = 2 if st.state == "Hold" and st.substate == 1 else 0
        wco = self._gc.wco()
        mask = int(self.settings[10])
        mpos = tuple(p + b for p, b in zip(st.machine_mm, self._base()))
        busy = state in BUSY
        show_wco = self._wco_counter == 0
        if show_wco:
            self._wco_counter = (WCO_BUSY if busy else WCO_IDLE) - 1
            if self._ovr_counter == 0:
                self._ovr_counter = 1
        else:
            self._wco_counter -= 1
        show_ovr = self._ovr_counter == 0
        if show_ovr:
            self._ovr_counter = (OVR_BUSY if busy else OVR_IDLE) - 1
        else:
            self._ovr_counter -= 1
        m = self._gc.modal
        accessories = ({3: "S", 4: "C"}.get(m.spindle, "") if self._spindle_rpm > 0 else "") + ("F" if self._flood else "")
        report = StatusReport(
            state=state,
            substate=sub,
            mpos=mpos if mask & codes.STATUS_MASK_MPOS else None,
            wpos=None if mask & codes.STATUS_MASK_MPOS else tuple(p - o for p, o in zip(mpos, wco)),
            wco=wco if show_wco else None,
            buffer=(self.stage.planner_free(), RX_BUFFER_BYTES - len(self._rx)) if mask & codes.STATUS_MASK_BUFFER else None,
            feed=st.feed_mm_min,
            spindle=self._spindle_rpm,
            pins=self._pins(),
            overrides=tuple(self._ovr) if show_ovr else None,
            accessories=accessories,
        )
        return format_status(report, inches=bool(self.settings[13]))

    def _pins(self) -> str:
        """report.c ``Pn:``: the probe pin, then the limit pins, as read through ``$6`` and ``$5`` (no switch wired).

        Unwired inputs are pulled up and read open; an inverted pin then reads
        triggered, so ``$5=1`` shows ``XYZ`` and ``$6=1`` shows ``P``. A hard limit
        (ALARM:1) leaves its switch pressed.
        """
        pressed = set(self._limits_pressed())
        if not pressed and self._critical and self.alarm_code == 1:
            pressed = {"X"}  # a hard limit injected by the alarm_mid_move fault
        if self.settings[5]:
            pressed = {"X", "Y", "Z"} - pressed
        return ("P" if self.settings[6] else "") + "".join(a for a in "XYZ" if a in pressed)

    # ------------------------------------------------------------------ serial ISR and real-time bytes
    def receive(self, b: int) -> None:
        """GRBL's serial ISR: real-time bytes act at once, the rest goes to the RX buffer."""
        if self._booting:  # main.c: report_init_message() of the boot, then the flags set during init act
            self._booting = False
            self.welcome()
        if b == RT_RESET:
            self.resets_received += 1
            if self._abort_at is not None or self._critical_msg_at is not None:
                self.resets_lost += 1  # mc_reset() already flagged the reset; protocol_exec_rt_system() clears it for 1/2
            else:
                self._soft_reset()
        elif b == RT_STATUS:
            if self._abort_at is not None or self._critical:
                pass  # the flag is set, then cleared by the reset (main.c): this '?' is lost
            elif self.stage.status().state == "Home":
                self._status_in_homing = True  # flag kept; limits_go_home() never reports
            else:
                self._send(self._status_line())
        elif b == RT_HOLD:
            if not self._critical and self._state() not in ("Home", "Alarm", "Check", "Sleep"):
                self.stage.feed_hold()
        elif b == RT_RESUME:
            st = self.stage.status()  # a door resumes only once stopped (Door:0): EXEC_CYCLE_START needs HOLD_COMPLETE
            if not self._critical and not (self._door and (st.state == "Jog" or st.substate == 1)):
                self._door = False
                self.stage.resume()
        elif b == RT_JOG_CANCEL:
            if not self._critical:
                self.stage.jog_cancel()
        elif b >= 0x80:
            if not self._critical:
                self._extended_realtime(b)
        elif len(self._rx) >= RX_BUFFER_BYTES - 1:
            self.rx_overflow_bytes += 1  # GRBL drops the byte: the host broke character counting
        else:
            self._rx.append(b)

    def _extended_realtime(self, b: int) -> None:
        """serial.c's extended real-time bytes, acted on as protocol_exec_rt_system() does.

        0x84 safety door: ``[MSG:Check Door]``, a hold (a jog is cancelled), state
        Door (Door:2 while stopping, Door:0 once stopped: no door switch is wired, so
        the door reads closed and ``~`` resumes); during homing ALARM:7. Feed (0x90-0x94),
        rapid (0x95-0x97) and spindle (0x99-0x9D) overrides within config.h's limits,
        reported at once (``Ov:``); 0xA0 toggles flood coolant. 0xA1 (mist) needs
        ENABLE_M7, off in config.h: ignored, as 0x9E (spindle stop) outside a hold.
        """
        state = self._state()
        f, r, sp = self._ovr
        if b == RT_DOOR:
            if state == "Home":
                self._door_in_homing = True
            elif state not in ("Alarm", "Check", "Sleep"):
                self._send("[MSG:Check Door]")
                if state == "Jog":
                    self.stage.jog_cancel()
                elif not self._door:
                    self.stage.feed_hold()
                self._door = True
        elif 0x90 <= b <= 0x94:
            f = 100 if b == 0x90 else f + {0x91: 10, 0x92: -10, 0x93: 1, 0x94: -1}[b]
            f = min(max(f, FEED_OVR_RANGE[0]), FEED_OVR_RANGE[1])
        elif 0x95 <= b <= 0x97:
            r = {0x95: 100, 0x96: 50, 0x97: 25}[b]
        elif 0x99 <= b <= 0x9D:
            sp = 100 if b == 0x99 else sp + {0x9A: 10, 0x9B: -10, 0x9C: 1, 0x9D: -1}[b]
            sp = min(max(sp, SPINDLE_OVR_RANGE[0]), SPINDLE_OVR_RANGE[1])
        elif b == 0xA0 and (state in ("Idle", "Run", "Hold", "Jog")):
            m = self._gc.modal
            m.coolant = 9 if m.coolant == 8 else 8
            self._flood = m.coolant == 8
            self._ovr_counter = 0  # coolant_set_state()
        if [f, r, sp] != self._ovr:
            self._ovr = [f, r, sp]
            if self._spindle_on:
                self._spindle_rpm = self._rpm(self._gc.spindle_speed)
            self._ovr_counter = 0  # "report change immediately"

    def _soft_reset(self) -> None:
        """Ctrl-X: stop at once (ALARM:3 in motion, ALARM:6 while homing), flush RX, banner again.

        A line still executing (waiting for planner space, homing, dwelling, or
        the one that raised a critical alarm) returns to the main loop on the
        abort and prints its ``ok`` before main() re-initializes (the banner).
        """
        before = self.alarm_code
        line_open = self._pending is not None or self._ok_on_reset
        self.stage.soft_reset()
        if self._stuck_homing:  # motion_control.c mc_reset(): STATE_HOMING -> EXEC_ALARM_HOMING_FAIL_RESET
            self._trigger(6)
        elif self.alarm_code == 6 and self._homing_pulloff:
            # limits.c limits_go_home(): after the reset's ALARM:6, a pull-off whose switch is still engaged
            # sets EXEC_ALARM_HOMING_FAIL_PULLOFF, which replaces it
            self._trigger(8)
        if self.alarm_code != before and self.alarm_code:
            # mc_reset() sets the alarm with the reset: protocol_exec_rt_system() prints ALARM:N and waits
            # report.c's 500 ms before it acts on the reset (a '?' or a line sent meanwhile is lost)
            self._alarm(self.alarm_code, line_open)
            return
        if line_open:
            self._send("ok")
        if self._sleep and self.alarm_code is None:
            self._trigger(0)  # GRBL wakes from sleep into the alarm lock
        self._reset_state()
        self.welcome()

    def _check_mid_move_alarm(self) -> None:
        code = self.faults.alarm_mid_move
        if code is None:
            return
        progress = self.stage.motion_progress()
        fire = progress is not None and progress[0] in ("Run", "Jog") and progress[1] >= 0.5
        if fire:
            self.faults.alarm_mid_move = None
            self._alarm(code, line_open=self._pending is not None)

    def _alarm(self, code: int, line_open: bool) -> None:
        """An alarm as protocol_exec_rt_system() handles it; ``line_open``: a line is executing.

        ``ALARM:N``, then report.c's 500 ms delay. Every alarm but the probe ones
        comes with mc_reset() (limits.c, motion_control.c). Hard/soft limit (1, 2)
        are critical: after the delay ``[MSG:Reset to continue]``, the reset flag
        is cleared (a reset sent in the delay is lost), and everything but a new
        reset is ignored; the line's ``ok`` follows that reset. The others (3,
        6-10) reset by themselves after the delay (a ``?`` in it is lost): the
        executing line's ``ok``, the banner and the unlock message.
        """
        if self.alarm_code != code:
            self._trigger(code)
        self._pending = None
        self._send(f"ALARM:{code}")
        due = self.stage.clock.now() + ALARM_REPORT_DELAY_S
        if code in CRITICAL_ALARMS:
            self._critical = True
            self._ok_on_reset = line_open
            self._critical_msg_at = due
        elif code not in (4, 5):  # probe failures alone do not reset
            self._ok_on_reset = line_open
            self._abort_at = due

    def _finish_abort(self) -> None:
        """The self-reset after an alarm: the executing line's ``ok``, then main() starts again."""
        if self._ok_on_reset:
            self._send("ok")
        self._reset_state()
        self.welcome()

    def _end_of_line(self, line: str, overflow: bool) -> None:
        """A line end in protocol_main_loop(): overflow is error:11, the rest is executed and answered."""
        self.lines_received += 1
        f = self.faults
        if self._cable_goes(self.lines_received):
            return
        if overflow:
            self._send("error:11")
            return
        if line:
            self._n_cmd += 1
            if f.error_every and self._n_cmd % f.error_every == 0:
                self._send(f"error:{f.error_code}")
                return
        try:
            steps = self._execute(line)
        except CodeError as e:
            self._send(f"error:{e.code}")
            return
        except (GrblError, StageRefused, StageAlarm) as e:
            self._failed(e)
            return
        if steps is None:
            return  # answered already (a line followed by a reset)
        self._pending = steps
        self._step_pending()

    # ------------------------------------------------------------------ commands
    def _state(self) -> str:
        """GRBL's state: the stage's motion state, overlaid by check mode, sleep and a '$HX' left in Home."""
        state = self.stage.status().state
        if self._sleep:
            return "Sleep"
        if self._stuck_homing:
            return "Home"
        if self._door and state in ("Hold", "Idle"):
            return "Door"
        return "Check" if self._check and state == "Idle" else state

    def _execute(self, line: str) -> Steps | None:
        """protocol_main_loop(): an empty line, a ``$`` command, or G-code (locked in Alarm and Jog)."""
        state = self._state()
        if not line:
            return iter(())
        if line[0] == "$":
            return self._system(line, state)
        if state in ("Alarm", "Jog"):
            raise CodeError(9)
        return self._gcode(line)

    def _gcode(self, text: str) -> Steps:
        """gc_execute_line(): the parser's position synced to the planner (not in check mode), checked, then run."""
        if not self._check:
            self._gc.position = self._machine_planned()
        return self._run_block(check_block(text, self._gc, self._coords))

    def _system(self, line: str, state: str) -> Steps | None:  # noqa: C901 - one branch per $ command, like system.c
        """system.c system_execute_line(): the ``$`` commands, their state rules and errors."""
        cmd = line[1:]
        c = cmd[:1]
        if cmd == "":
            self._send(HELP)
        elif c == "J":
            if state not in ("Idle", "Jog"):
                raise CodeError(8)
            if cmd[1:2] != "=":
                raise CodeError(3)
            return self._jog(cmd[2:])
        elif c in ("$", "G", "C", "X"):
            if len(cmd) != 1:
                raise CodeError(3)
            if c == "$":
                if state in ("Run", "Hold"):
                    raise CodeError(8)
                for n in sorted(self.settings):
                    self._send(format_setting(n, self.settings[n]))
            elif c == "G":
                self._send(self._gcode_modes())
            elif c == "C":
                if self._check:
                    self._send("[MSG:Disabled]")
                    self._send("ok")
                    self._soft_reset()
                    return None
                if state != "Idle":
                    raise CodeError(8)
                self._check = True
                self._send("[MSG:Enabled]")
            elif state == "Alarm":  # $X
                self.stage.unlock()
                self._send("[MSG:Caution: Unlocked]")
        else:
            if state not in ("Idle", "Alarm"):
                raise CodeError(8)
            return self._system_idle(cmd)
        return iter(())

    def _gcode_modes(self) -> str:
        """report.c report_gcode_modes()."""
        g, m = self._gc, self._gc.modal
        motion = f"38.{m.motion - 138}" if m.motion in gc.PROBE_MODES else str(m.motion)
        inches = bool(self.settings[13])
        feed = f"{g.feed_rate / MM_PER_INCH:.1f}" if inches else f"{g.feed_rate:.0f}"
        return (f"[GC:G{motion} G{54 + m.coord_select} G{17 + m.plane} G{m.units} G{m.distance} G{m.feed_mode} "
                f"M{m.spindle} M{m.coolant} T{g.tool} F{feed} S{g.spindle_speed:.0f}]")

    def _system_idle(self, cmd: str) -> Steps | None:
        """``$`` commands allowed only in Idle or Alarm ($#, $H, $SLP, $I, $RST, $N, $x=val)."""
        c = cmd[:1]
        if c == "#":
            if len(cmd) != 1:
                raise CodeError(3)
            self._ngc_parameters()
        elif c == "H":
            if not self.stage.homing_enabled:
                raise CodeError(5)
            if len(cmd) != 1:  # HOMING_SINGLE_AXIS_COMMANDS is off in stock config.h
                self._stuck_homing = True  # sys.state = STATE_HOMING came first: it stays until a reset
                raise CodeError(3)
            self.stage.start_home()
            return self._homing()
        elif c == "S":
            if cmd != "SLP":
                raise CodeError(3)
            self.stage.soft_reset()  # the line's ok comes first; the sleep runs at the next real-time check
            self._sleep = True
            self._send("ok")
            self._send("[MSG:Sleeping]")
            return None
        elif c == "I":
            if cmd == "I":
                self._send(f"[VER:{VERSION}.{BUILD}:{self._build_user}]")
                self._send(f"[OPT:{self.options},{PLANNER_BLOCKS},{RX_BUFFER_BYTES}]")
            elif cmd[1] != "=":
                raise CodeError(3)
            elif len(cmd) - 2 > 79 - 1:
                raise CodeError(14)
            else:
                self._build_user = cmd[2:]
        elif c == "R":
            if cmd not in ("RST=$", "RST=#", "RST=*"):
                raise CodeError(3)
            if cmd != "RST=#":  # settings.c settings_restore(): settings = defaults (defaults.h DEFAULTS_GENERIC)
                self.settings.update(codes.DEFAULT_SETTINGS)
            if cmd != "RST=$":
                self._coords = self._default_coords()  # G54 back to the base, by design (docs/hardware.md)
            if cmd == "RST=*":  # SETTINGS_RESTORE_ALL also wipes the startup lines and the build info
                self._startup = ["", ""]
                self._build_user = ""
            self._send("[MSG:Restoring defaults]")
            self._send("ok")
            self._soft_reset()
            return None
        elif cmd == "N":
            for n, text in enumerate(self._startup):
                self._send(f"$N{n}={text}")
        elif c == "N":
            return self._store_startup(cmd)
        else:
            self._store_setting(cmd)
        return iter(())

    def _store_startup(self, cmd: str) -> Steps:
        """system.c ``$Nx=line`` (Idle only): the line runs through gc_execute_line(); stored if it is ok."""
        if self._state() != "Idle":
            raise CodeError(8)
        number, i = _parameter(cmd, 1)
        text = cmd[i:]
        yield from self._gcode(text)
        if 0 <= int(number) < len(self._startup):  # settings_store_startup_line(): other numbers go unread
            self._startup[int(number)] = text

    def _store_setting(self, cmd: str) -> None:
        """system.c's default branch: ``$<number>=<value>`` with its read_float() errors (2, 3)."""
        number, i = _parameter(cmd, 0)
        got = read_float(cmd, i)
        if got is None:
            raise CodeError(2)
        value, end = got
        if end != len(cmd) or number > 255:
            raise CodeError(3)
        self.settings.write(int(number), value)
        if int(number) == 13:
            self._wco_counter = 0  # settings.c: system_flag_wco_change()

    def _ngc_parameters(self) -> None:
        """report.c report_ngc_parameters(): G54-G59, G28, G30 from EEPROM, G92, TLO, PRB."""
        inches = bool(self.settings[13])
        names = ["G54", "G55", "G56", "G57", "G58", "G59", "G28", "G30"]
        for name, data in zip(names, self._coords):
            self._send(f"[{name}:{format_axes(tuple(data), inches)}]")
        self._send(f"[G92:{format_axes(tuple(self._gc.coord_offset), inches)}]")
        tlo = self._gc.tool_length_offset
        self._send(f"[TLO:{tlo / MM_PER_INCH:.4f}]" if inches else f"[TLO:{tlo:.3f}]")
        self._send(self._probe_line())

    def _probe_line(self) -> str:
        """report.c report_probe_parameters(): the last probe position (machine) and whether it succeeded."""
        return f"[PRB:{format_axes(tuple(self._probe_mpos), bool(self.settings[13]))}:{int(self._probe_ok)}]"

    def _homing(self) -> Steps:
        """``$H`` runs: a held-back ``?`` is answered when it ends (state still Home), then ``ok``.

        With the fail-homing fault the cycle stops half-way with ALARM:8/9, and the
        ``ok`` of ``$H`` still comes (system.c returns STATUS_OK after the abort),
        after report.c's delay, then the self-reset's banner (limits.c: mc_reset()
        on a homing failure). Lines sent meanwhile stay in RX and the reset flushes them.
        """
        axis = AXES.index(self.stage.axis)
        switch, last = self.stage.travel_mm[0], self.stage.status().machine_mm[axis]
        while True:
            pos = self.stage.status().machine_mm[axis]
            if pos != last:  # moving up off the low switch, not yet the pull-off away: it may still be engaged
                self._homing_pulloff = pos > last and pos < switch + self.settings[27] - TRAVEL_EPS_MM
                last = pos
            code = self.faults.fail_homing
            progress = self.stage.motion_progress()
            done = self.stage.status().state != "Home"  # a slow poll may find the cycle over: it fails all the same
            if self._door_in_homing:  # limits.c limits_go_home(): EXEC_SAFETY_DOOR -> EXEC_ALARM_HOMING_FAIL_DOOR
                self.stage.soft_reset()
                code, done = 7, True
            if code and (done or (progress is not None and progress[0] == "Home" and progress[1] >= 0.5)):
                self._status_in_homing = False  # the reset clears the pending report
                self.stage.homed = False
                raise GrblError("alarm", int(code))
            if done:
                break
            yield
        if self._status_in_homing:
            self._status_in_homing = False
            self._send(self._status_line().replace("<Idle", "<Home", 1))
        self._gc.position = self._machine_planned()

    # ------------------------------------------------------------------ G-code (gcode.c step 4)
    def _run_block(self, b: gc.Block) -> Steps:  # noqa: C901 - gcode.c's order of execution
        """Execute a checked block in gcode.c's order: modes, dwell, offsets, motion, program flow."""
        g = self._gc
        g.modal.feed_mode, g.feed_rate = b.modal.feed_mode, b.f
        spindle_sync = g.modal.spindle != b.modal.spindle or (g.spindle_speed != b.s and g.modal.spindle != 5)
        coolant_sync = g.modal.coolant != b.modal.coolant
        g.spindle_speed, g.tool = b.s, b.t
        g.modal.spindle, g.modal.coolant = b.modal.spindle, b.modal.coolant
        if not self._check and (spindle_sync or coolant_sync):  # spindle_sync(), coolant_sync(): [4], [7], [8]
            yield from self._synchronize()
            self._spindle_rpm = self._rpm(g.spindle_speed) if self._spindle_on else 0.0
            self._flood = g.modal.coolant == 8
            self._ovr_counter = 0  # spindle_set_state() / coolant_set_state(): report at once
        if b.non_modal == gc.DWELL and not self._check:  # mc_dwell(): sync, then wait P seconds
            yield from self._synchronize()
            end = self.stage.clock.now() + b.p
            while self.stage.clock.now() < end:
                yield
        g.modal.plane, g.modal.units = b.modal.plane, b.modal.units
        if b.axis_command == gc.AXIS_TLO:
            g.modal.tool_length = b.modal.tool_length
            tlo = 0.0 if b.modal.tool_length == "G49" else b.xyz[gc.Z]
            if tlo != g.tool_length_offset:
                g.tool_length_offset = tlo
                yield from self._wco_changed()
        if g.modal.coord_select != b.modal.coord_select:
            g.modal.coord_select, g.coord_system = b.modal.coord_select, list(b.block_coord_system)
            yield from self._wco_changed()
        g.modal.distance = b.modal.distance
        nm = b.non_modal
        if nm == gc.SET_COORD_DATA:
            yield from self._synchronize()  # FORCE_BUFFER_SYNC_DURING_EEPROM_WRITE
            self._coords[b.coord_index] = list(b.ijk)
            if g.modal.coord_select == b.coord_index:
                g.coord_system = list(b.ijk)
                yield from self._wco_changed()
        elif nm in (gc.GO_HOME_0, gc.GO_HOME_1):
            if b.axis_command:
                yield from self._line(b.xyz, math.inf)
            yield from self._line(b.ijk, math.inf)
            g.position = list(b.ijk)
        elif nm in (gc.SET_HOME_0, gc.SET_HOME_1):
            yield from self._synchronize()
            self._coords[6 if nm == gc.SET_HOME_0 else 7] = list(g.position)
        elif nm == gc.SET_OFFSET:
            g.coord_offset = list(b.xyz)
            yield from self._wco_changed()
        elif nm == gc.RESET_OFFSET:
            g.coord_offset = [0.0, 0.0, 0.0]
            yield from self._wco_changed()
        g.modal.motion = b.modal.motion
        if g.modal.motion != gc.MOTION_NONE and b.axis_command == gc.AXIS_MOTION:
            yield from self._motion(b)
            g.position = list(b.xyz)
        if b.modal.program_flow:
            yield from self._program_flow(b.modal.program_flow)

    def _motion(self, b: gc.Block) -> Steps:
        g = self._gc
        motion = g.modal.motion
        feed = math.inf if motion == gc.SEEK else g.feed_rate
        if g.modal.feed_mode == 93 and motion != gc.SEEK:  # inverse time: F is 1/minutes for the block
            dist = math.dist(b.xyz, g.position)
            feed = dist * g.feed_rate if dist > 0 else math.inf
        if motion in (gc.CW_ARC, gc.CCW_ARC):
            for point in gc.arc_points(b, g.position, self.settings[12])[:-1]:
                self._soft_limit_check(point)
        if motion in gc.PROBE_MODES and not self._check:
            yield from self._probe_cycle(b.xyz, feed, motion)
            return
        yield from self._line(b.xyz, feed)

    def _probe_cycle(self, target: list[float], feed: float, motion: int) -> Steps:
        """motion_control.c mc_probe_cycle() with no probe wired (the pin never changes).

        Toward (G38.2/3) the pin never triggers: the whole move runs; G38.2 then
        raises ALARM:5, G38.3 stores where it stopped. Away (G38.4/5) the inverted
        pin reads triggered before any motion: ALARM:4. Probe alarms do not reset;
        report.c's 500 ms follow the alarm; ``[PRB:]`` (MESSAGE_PROBE_COORDINATES)
        comes after a probing motion, then the line's ``ok`` (gcode.c returns STATUS_OK).
        """
        yield from self._synchronize()
        self._probe_ok = False
        away = motion in (142, 143)
        if away != bool(self.settings[6]):  # PROBE_FAIL_INITIAL: mc_probe_cycle() bails out at once
            yield from self._probe_alarm(4)
            return
        yield from self._line(target, feed)
        yield from self._synchronize()
        if motion in (140, 142):
            yield from self._probe_alarm(5)
        else:
            self._probe_mpos = self._machine_planned()
        self._gc.position = self._machine_planned()
        self._send(self._probe_line())

    def _probe_alarm(self, code: int) -> Steps:
        """A probe alarm: ALARM:N, state Alarm, report.c's 500 ms inside the line (no reset)."""
        self._trigger(code)
        self._send(f"ALARM:{code}")
        end = self.stage.clock.now() + ALARM_REPORT_DELAY_S
        while self.stage.clock.now() < end:
            yield

    def _program_flow(self, flow: int) -> Steps:
        """gcode.c [21]: sync; M0 holds (not in check mode); M2/M30 reset some modes, print Pgm End."""
        yield from self._synchronize()
        g = self._gc
        if flow == 3:
            if not self._check:  # EXEC_FEED_HOLD, then protocol_execute_realtime() suspends until '~'
                self.stage.feed_hold()
                yield  # poll() runs nothing while held: the ok follows the resume
            return
        m = g.modal
        m.motion, m.plane, m.distance, m.feed_mode, m.coord_select = gc.LINEAR, 0, 90, 94, 0
        m.spindle, m.coolant = 5, 9
        self._ovr = [100, 100, 100]  # RESTORE_OVERRIDES_AFTER_PROGRAM_END
        if not self._check:
            g.coord_system = list(self._coords[0])
            self._spindle_rpm = 0.0
            self._flood = False
            self._wco_counter = self._ovr_counter = 0
        self._send("[MSG:Pgm End]")

    @property
    def _spindle_on(self) -> bool:
        return self._gc.modal.spindle in (3, 4)

    def _rpm(self, s: float) -> float:
        """spindle_control.c spindle_compute_pwm_value(): S times the override, clamped to $31..$30 (0 is off)."""
        s *= 0.01 * self._ovr[2]
        hi, lo = self.settings[30], self.settings[31]
        if lo >= hi or s >= hi:
            return hi
        if s <= lo:
            return 0.0 if s == 0 else lo
        return s

    def _synchronize(self) -> Steps:
        """protocol_buffer_synchronize(): wait until the planner is empty and nothing moves."""
        while self.stage.status().state != "Idle" and not self._check:
            yield

    def _wco_changed(self) -> Steps:
        """system_flag_wco_change(): sync (FORCE_BUFFER_SYNC_DURING_WCO_CHANGE), then report WCO next."""
        yield from self._synchronize()
        self._wco_counter = 0

    def _soft_limit_check(self, target: list[float]) -> None:
        """limits.c limits_soft_check() via mc_line(): a target beyond the travel is ALARM:2, in check mode too."""
        if not self.stage.soft_limits:
            return
        for i, (t, b) in enumerate(zip(target, self._base())):
            lo, hi = self.stage.axis_travel_mm[i]
            if not lo - TRAVEL_EPS_MM <= t - b <= hi + TRAVEL_EPS_MM:
                raise GrblError("alarm", 2, f"{AXES[i]} target {t:.3f} (machine) beyond the travel")

    def _line(self, target: list[float], feed: float) -> Steps:
        """motion_control.c mc_line(): soft limits, nothing more in check mode, then planner space per axis."""
        self._soft_limit_check(target)
        if self._check:
            return
        for i, (t, b) in enumerate(zip(target, self._base())):
            t = self._hard_limit_stop(i, t - b) + b
            if abs(self.stage.planned_mm(i) - (t - b)) <= TRAVEL_EPS_MM:
                continue  # plan_buffer_line(): an empty block is not planned
            while self.stage.planner_free() <= 0:
                yield
            rate = (feed * self._ovr[0] if math.isfinite(feed) else self.stage.max_rate_mm_min(i) * self._ovr[1]) / 100
            self.stage.move_to(t - b, rate, AXES[i])  # planned with the overrides in force (not re-planned later)

    def _hard_limit_stop(self, axis: int, target_mm: float) -> float:
        """With ``$21=1`` a switch sits at each end of the travel: a move beyond it stops there and limits.c's
        ISR raises ALARM:1 when the carriage gets there (:meth:`_check_hard_limit`); otherwise the target."""
        lo, hi = self.stage.axis_travel_mm[axis]
        if not self.settings[21] or lo - TRAVEL_EPS_MM <= target_mm <= hi + TRAVEL_EPS_MM:
            return target_mm
        end = min(max(target_mm, lo), hi)
        self._hard_limit_at = (axis, end)
        return end

    def _check_hard_limit(self) -> None:
        """limits.c ISR(LIMIT_INT_vect): the switch closes, mc_reset() and EXEC_ALARM_HARD_LIMIT (critical)."""
        if self._hard_limit_at is None or self._critical:
            return
        axis, end = self._hard_limit_at
        if abs(self.stage.status().machine_mm[axis] - end) <= TRAVEL_EPS_MM:
            self._hard_limit_at = None
            self._limit_hit.add(axis)
            self._alarm(1, line_open=self._pending is not None)

    def _limits_pressed(self) -> str:
        """The switches a hard limit left pressed (the carriage still at that end of the travel)."""
        pos = self.stage.status().machine_mm
        self._limit_hit = {i for i in self._limit_hit
                           if min(abs(pos[i] - e) for e in self.stage.axis_travel_mm[i]) <= TRAVEL_EPS_MM}
        return "".join(AXES[i] for i in sorted(self._limit_hit))

    def _jog(self, text: str) -> Steps:
        """``$J=``: gcode.c with G1/G94 enforced, the jog rules (16), jog.c's travel check (15)."""
        self._gc.position = self._machine_planned()
        b = check_block(text, self._gc, self._coords, jog=True)
        b.check_jog()
        if not b.axis_words:  # gcode.c: the jog's target array is never filled: machine zero
            b.xyz = [0.0, 0.0, 0.0]
        if self.stage.soft_limits:
            try:
                self._soft_limit_check(b.xyz)
            except GrblError:
                raise CodeError(15) from None
        self._gc.position = list(b.xyz)
        return self._plan_jog(b.xyz, b.f)

    def _plan_jog(self, target: list[float], feed: float) -> Steps:
        for i, (t, base) in enumerate(zip(target, self._base())):
            dist = (t - base) - self.stage.planned_mm(i)
            if abs(dist) <= TRAVEL_EPS_MM:
                continue
            while self.stage.planner_free() <= 0:
                yield
            self.stage.jog(dist, feed, AXES[i])
