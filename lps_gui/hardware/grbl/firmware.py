"""GRBL 1.1h's behaviour, independent of the wire: RX buffer, real-time bytes, lines, states, reports.

:class:`GrblFirmware` is what runs inside the controller, transcribed from
gnea/grbl (report.c, protocol.c, system.c, gcode.c, jog.c): banner and
homing-lock message after every reset, ``$``, ``$$``, ``$x=val``, ``$#``, ``$G``,
``$I``, ``$N``, ``$C``, ``$X``, ``$H``, ``$SLP``, ``$RST=``, ``$J=``, G0/G1/G4 with
G90/G91/G20/G21/G53, real-time ``?`` ``!`` ``~`` 0x18 0x85, status reports per
``$10`` with GRBL's WCO/Ov refresh counters, a 128-byte RX buffer that drops
overflowing bytes, a 15-block planner that makes a line wait, critical alarms
(1, 2) that ignore everything but a reset. Motion happens in a
:class:`SimulatedStage`. Machine coordinates are GRBL's homed space (0 at the
top of the travel, negative below); the G54 offset makes work coordinates
equal the stage's own coordinates. Multi-axis moves run one axis after the
other; no arcs, probing, spindle or door.

It writes through a ``send(line)`` callback, so the pty transport
(``emulator.py``) adds timing and fault injection around it.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Callable

from lps_gui.hardware.grbl import codes
from lps_gui.hardware.grbl.codes import GrblError, format_setting
from lps_gui.hardware.grbl.gcode import Block, CodeError, clean_line, parse_block
from lps_gui.hardware.grbl.protocol import MM_PER_INCH, StatusReport, format_axes, format_status
from lps_gui.hardware.sim_stage import PLANNER_BLOCKS, RX_BUFFER_BYTES, SimulatedStage
from lps_gui.hardware.stage import AXES

log = logging.getLogger(__name__)

VERSION, BUILD = "1.1h", "20190830"
BANNER = f"\r\nGrbl {VERSION} ['$' for help]\r\n"
HELP = "[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]"
RT_STATUS, RT_HOLD, RT_RESUME, RT_RESET, RT_JOG_CANCEL = 0x3F, 0x21, 0x7E, 0x18, 0x85
BUSY = ("Run", "Hold", "Jog", "Home", "Door")
ALARM_REPORT_DELAY_S = 0.5  # report.c report_alarm_message(): delay_ms(500) after ALARM:N
WCO_BUSY, WCO_IDLE, OVR_BUSY, OVR_IDLE = 30, 10, 20, 10  # config.h refresh counts


@dataclass
class Faults:
    """Fault-injection switches (read on every step; flip them any time).

    drop_after_lines : close the port after this many received lines (None: never).
    alarm_mid_move : raise ALARM:<code> half-way through the next move or jog, once (None: never).
    error_every : answer every Nth command line with ``error:<error_code>`` instead of executing it.
    reply_delay_s : delay everything the emulator sends by this many real seconds.
    garbage_every : send a line of garbage bytes before every Nth message.
    fail_homing : every ``$H`` fails half-way with ``ALARM:<code>`` (8: pull-off did not clear
        the switch, 9: switch not found), then the ``ok`` of ``$H`` and a self-reset (limits.c).
    """

    drop_after_lines: int | None = None
    alarm_mid_move: int | None = None
    error_every: int = 0
    error_code: int = 20
    reply_delay_s: float = 0.0
    garbage_every: int = 0
    fail_homing: int | None = None


class GrblFirmware:
    """GRBL 1.1h's serial ISR and protocol loop over a :class:`SimulatedStage`.

    Feed received bytes to :meth:`receive`, call :meth:`poll` often (it runs
    waiting actions and executes complete lines); output goes to ``send``.
    ``on_drop`` is called when the drop-after-lines fault fires.
    ``homing_init_lock`` is config.h's HOMING_INIT_LOCK (stock 1.1h: on): with
    ``$22=1`` the controller powers up in Alarm; off, ``[OPT:]`` carries ``L``.
    """

    def __init__(self, stage: SimulatedStage, faults: Faults, send: Callable[[str], None], on_drop: Callable[[], None],
                 homing_init_lock: bool = False) -> None:
        self.stage = stage
        self.homing_init_lock = homing_init_lock
        self.faults = faults
        self._send = send
        self._on_drop = on_drop
        self.rx_overflow_bytes = 0  # bytes dropped because the host overran the 128-byte RX buffer
        self.lines_received = 0
        self.halted = False
        self._n_cmd = 0
        self._build_user = ""
        self._initial_settings = dict(stage.settings)
        self._user = [0.0, 0.0, 0.0]  # G54 shift set by G10 (EEPROM in GRBL: survives resets)
        self._reset_state()

    @property
    def busy(self) -> bool:
        """Something waits on time (a line, a move): poll often."""
        return self._pending is not None or self._abort_at is not None or self.stage.next_event_s() is not None

    @property
    def options(self) -> str:
        """``[OPT:]`` letters: V (variable spindle), L (built without HOMING_INIT_LOCK)."""
        return "V" + ("" if self.homing_init_lock else "L")

    def poll(self) -> None:
        """Run the waiting action, fire a due mid-move alarm, execute complete lines.

        During a feed hold nothing runs: protocol.c calls protocol_execute_realtime()
        at every line end (and mc_line() in its planner-full loop), and that stays
        in protocol_exec_rt_suspend() while sys.suspend is set, so no line is
        answered until ``~`` (only ``?``, ``~``, ``!`` and Ctrl-X act).
        """
        self._check_mid_move_alarm()
        if self._abort_at is not None:
            if self.stage.clock.now() < self._abort_at:
                return
            self._finish_abort()
        if self._critical or self.halted or self._held():
            return
        if self._pending is not None and self._pending():
            self._pending = None
        while self._pending is None and not self._critical and not self.halted and b"\n" in self._rx.replace(b"\r", b"\n"):
            self._next_line()

    def _held(self) -> bool:
        return self.stage.status().state == "Hold"

    def power_up(self) -> None:
        """main.c at power-up: with HOMING_INIT_LOCK and ``$22=1`` the state is Alarm, then the welcome."""
        if self.homing_init_lock and self.stage.homing_enabled and self.stage.alarm_code is None:
            self.stage.trigger_alarm(0)  # the silent homing lock (no ALARM:N line)
        self.welcome()

    def _reset_state(self) -> None:
        self._rx = bytearray()
        self._modal = {"motion": 0.0, "distance": 90.0, "units": 21.0, "feed": 0.0}
        self._wco_counter = 0
        self._ovr_counter = 0
        self._critical = False
        self._ok_on_reset = False  # a line was executing when a critical alarm hit: its ok follows the reset
        self._status_in_homing = False  # a '?' during homing is answered when the cycle ends
        self._abort_at: float | None = None  # an alarm's self-reset is due (after report.c's 500 ms delay)
        self._pending: Callable[[], bool] | None = None
        self._check = False
        self._sleep = False

    def welcome(self) -> None:
        """What GRBL prints at power-up and after every reset (main.c, protocol_main_loop()).

        The state survives a reset (main.c keeps ``prior_state``), so the unlock
        message follows the banner whenever the controller comes up in Alarm: at
        power-up with the homing lock, and after a reset out of an alarm.
        """
        self._send(BANNER)
        if self.stage.alarm_code is not None:
            self._send("[MSG:'$H'|'$X' to unlock]")

    def _base(self) -> tuple[float, float, float]:
        """Machine 0 sits at the top of the travel: machine = stage coordinate + base."""
        return (-self.stage.travel_mm[1],) * 3  # type: ignore[return-value]

    def _wco(self) -> tuple[float, float, float]:
        """G54 offset: the base (work = the stage's coordinates) plus what G10 set since (``_user``)."""
        return tuple(b + u for b, u in zip(self._base(), self._user))  # type: ignore[return-value]

    def _status_line(self) -> str:
        st = self.stage.status()
        state = self._state()
        sub = st.substate if state == st.state else None
        wco = self._wco()
        mask = int(self.stage.settings[10])
        work = tuple(s - u for s, u in zip(st.work_mm, self._user))
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
        report = StatusReport(
            state=state,
            substate=sub,
            mpos=tuple(w + o for w, o in zip(work, wco)) if mask & codes.STATUS_MASK_MPOS else None,
            wpos=None if mask & codes.STATUS_MASK_MPOS else tuple(work),
            wco=wco if show_wco else None,
            buffer=(st.buffer[0], RX_BUFFER_BYTES - len(self._rx)) if mask & codes.STATUS_MASK_BUFFER else None,
            feed=st.feed_mm_min,
            spindle=0.0,
            pins="X" if self._critical and self.stage.alarm_code == 1 else "",
            overrides=(100, 100, 100) if show_ovr else None,
        )
        return format_status(report, inches=bool(self.stage.settings[13]))

    # ------------------------------------------------------------------ serial ISR and real-time bytes
    def receive(self, b: int) -> None:
        """GRBL's serial ISR: real-time bytes act at once, the rest goes to the RX buffer."""
        if b == RT_RESET:
            self._soft_reset()
        elif b == RT_STATUS:
            if self._abort_at is not None:
                pass  # the flag is set, then cleared by the reset (main.c): this '?' is lost
            elif self.stage.status().state == "Home":
                self._status_in_homing = True  # flag kept; limits_go_home() never reports
            elif not self._critical:
                self._send(self._status_line())
        elif b == RT_HOLD:
            if not self._critical and self.stage.status().state != "Home":
                self.stage.feed_hold()
        elif b == RT_RESUME:
            if not self._critical:
                self.stage.resume()
        elif b == RT_JOG_CANCEL:
            if not self._critical:
                self.stage.jog_cancel()
        elif b >= 0x80:
            pass  # other real-time commands (overrides, door) have no effect here
        elif len(self._rx) >= RX_BUFFER_BYTES - 1:
            self.rx_overflow_bytes += 1  # GRBL drops the byte: the host broke character counting
        else:
            self._rx.append(b)

    def _soft_reset(self) -> None:
        """Ctrl-X: stop at once (ALARM:3 in motion, ALARM:6 while homing), flush RX, banner again.

        A line still executing (waiting for planner space, homing, dwelling, or
        the one that raised a critical alarm) returns to the main loop on the
        abort and prints its ``ok`` before main() re-initializes (the banner).
        """
        before = self.stage.alarm_code
        line_open = self._pending is not None or self._ok_on_reset
        self.stage.soft_reset()
        if self.stage.alarm_code != before and self.stage.alarm_code:
            self._send(f"ALARM:{self.stage.alarm_code}")
        if line_open:
            self._send("ok")
        if self._sleep and self.stage.alarm_code is None:
            self.stage.trigger_alarm(0)  # GRBL wakes from sleep into the alarm lock
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

        Every alarm but the probe ones comes with mc_reset() (limits.c, motion_control.c):
        hard/soft limit (1, 2) are critical, everything but a reset is ignored and the
        line's ``ok`` follows the user's reset; the others (3, 6-10) abort at once:
        ``ALARM:N``, 500 ms (report.c) in which a ``?`` is lost, the executing line's
        ``ok``, the banner and the unlock message.
        """
        if self.stage.alarm_code != code:
            self.stage.trigger_alarm(code)
        self._pending = None
        self._send(f"ALARM:{code}")
        if code in (1, 2):  # critical: ignore everything until a reset
            self._critical = True
            self._ok_on_reset = line_open
            self._send("[MSG:Reset to continue]")
        elif code not in (4, 5):  # probe failures alone do not reset
            self._ok_on_reset = line_open
            self._abort_at = self.stage.clock.now() + ALARM_REPORT_DELAY_S

    def _finish_abort(self) -> None:
        """The self-reset after an alarm: the executing line's ``ok``, then main() starts again."""
        if self._ok_on_reset:
            self._send("ok")
        self._reset_state()
        self.welcome()

    def _next_line(self) -> None:
        buf = self._rx.replace(b"\r", b"\n")
        end = buf.index(b"\n")
        raw = self._rx[:end].decode("latin-1")
        del self._rx[: end + 1]
        self.lines_received += 1
        f = self.faults
        if f.drop_after_lines is not None and self.lines_received >= f.drop_after_lines:
            log.info("emulator: dropping the connection (fault injection)")
            self.halted = True
            self._on_drop()
            return
        line, overflow = clean_line(raw)
        if overflow:
            self._send("error:11")
            return
        if line:
            self._n_cmd += 1
            if f.error_every and self._n_cmd % f.error_every == 0:
                self._send(f"error:{f.error_code}")
                return
        try:
            self._execute(line)
        except CodeError as e:
            self._send(f"error:{e.code}")
        except GrblError as e:
            if e.kind == "alarm":
                self._alarm(e.code, line_open=True)
            else:
                self._send(f"error:{e.code}")

    # ------------------------------------------------------------------ commands
    def _state(self) -> str:
        """GRBL's state: the stage's motion state, overlaid by check mode and sleep."""
        state = self.stage.status().state
        if self._sleep:
            return "Sleep"
        return "Check" if self._check and state == "Idle" else state

    def _execute(self, line: str) -> None:
        state = self._state()
        if not line:
            self._send("ok")
        elif line[0] == "$":
            self._system(line, state)
        elif state in ("Alarm", "Jog", "Sleep"):
            raise CodeError(9)
        else:
            self._gcode(parse_block(line))

    def _system(self, line: str, state: str) -> None:  # noqa: C901 - one branch per $ command, like system.c
        cmd = line[1:]
        if cmd == "":
            self._send(HELP)
        elif cmd.startswith("J"):
            if state not in ("Idle", "Jog"):
                raise CodeError(8)
            if not cmd.startswith("J="):
                raise CodeError(3)
            self._jog(parse_block(cmd[2:], jog=True))
            return  # the jog answers once it is planned
        elif cmd[:1] in ("$", "G", "C", "X"):
            if len(cmd) != 1:
                raise CodeError(3)
            if cmd == "$":
                if state in ("Run", "Hold"):
                    raise CodeError(8)
                for n in sorted(self.stage.settings):
                    self._send(format_setting(n, self.stage.settings[n]))
            elif cmd == "G":
                m = self._modal
                self._send(f"[GC:G{int(m['motion'])} G54 G17 G{int(m['units'])} G{int(m['distance'])} G94 M5 M9 T0 F{m['feed']:.0f} S0]")
            elif cmd == "C":
                if self._check:
                    self._check = False
                    self._send("[MSG:Disabled]")
                    self._send("ok")
                    self._soft_reset()
                    return
                if state != "Idle":
                    raise CodeError(8)
                self._check = True
                self._send("[MSG:Enabled]")
            elif cmd == "X":
                if state == "Alarm":
                    self.stage.unlock()
                    self._send("[MSG:Caution: Unlocked]")
        else:
            if state not in ("Idle", "Alarm"):
                raise CodeError(8)
            self._system_idle(cmd)
            return
        self._send("ok")

    def _system_idle(self, cmd: str) -> None:
        """``$`` commands allowed only in Idle or Alarm ($#, $H, $SLP, $I, $RST, $N, $x=val)."""
        if cmd == "#":
            wco = self._wco()
            for name in ("G54",):
                self._send(f"[{name}:{format_axes(wco)}]")
            for name in ("G55", "G56", "G57", "G58", "G59", "G28", "G30", "G92"):
                self._send(f"[{name}:0.000,0.000,0.000]")
            self._send("[TLO:0.000]")
            self._send("[PRB:0.000,0.000,0.000:0]")
        elif cmd == "H":
            self.stage.start_home()  # raises error:5 when $22=0
            self._pending = self._homing_done
            return
        elif cmd == "SLP":  # the line's ok comes first; the sleep runs at the next real-time check
            self.stage.soft_reset()
            self._sleep = True
            self._send("ok")
            self._send("[MSG:Sleeping]")
            return
        elif cmd == "I":
            self._send(f"[VER:{VERSION}.{BUILD}:{self._build_user}]")
            self._send(f"[OPT:{self.options},{PLANNER_BLOCKS},{RX_BUFFER_BYTES}]")
        elif cmd.startswith("I="):
            if len(cmd) - 2 > 79 - 1:
                raise CodeError(14)
            self._build_user = cmd[2:]
        elif cmd.startswith("RST="):
            if cmd not in ("RST=$", "RST=#", "RST=*"):
                raise CodeError(3)
            if cmd != "RST=#":
                self.stage.settings.update(self._initial_settings)
            if cmd != "RST=$":
                self._user = [0.0, 0.0, 0.0]
            self._send("[MSG:Restoring defaults]")
            self._send("ok")
            self._soft_reset()
            return
        elif cmd == "N":
            self._send("$N0=")
            self._send("$N1=")
        elif cmd[:1].isdigit():
            name, eq, value = cmd.partition("=")
            if not eq:
                raise CodeError(3)
            try:
                number, val = int(float(name)), float(value)
            except ValueError:
                raise CodeError(2) from None
            if number > 255:
                raise CodeError(3)
            self.stage.write_setting(number, val)
        else:
            raise CodeError(3)
        self._send("ok")

    def _homing_done(self) -> bool:
        """``$H`` ends: a held-back ``?`` is answered (state still Home), then ``ok``.

        With the fail-homing fault the cycle stops half-way with ALARM:8/9, and the
        ``ok`` of ``$H`` still comes (system.c returns STATUS_OK after the abort),
        then the self-reset's banner (limits.c: mc_reset() on a homing failure).
        """
        code = self.faults.fail_homing
        progress = self.stage.motion_progress()
        done = self.stage.status().state != "Home"  # a slow poll may find the cycle over: it fails all the same
        if code and (done or (progress is not None and progress[0] == "Home" and progress[1] >= 0.5)):
            self._status_in_homing = False  # the reset clears the pending report
            self.stage.homed = False
            self._alarm(int(code), line_open=True)
            return True
        if not done:
            return False
        if self._status_in_homing:
            self._status_in_homing = False
            self._send(self._status_line().replace("<Idle", "<Home", 1))
        self._send("ok")
        return True

    # ------------------------------------------------------------------ G-code
    def _targets(self, block: Block, distance: float) -> dict[int, float]:
        """Work-coordinate targets (mm) for the axis words of ``block``."""
        scale = MM_PER_INCH if block.g.get("units", self._modal["units"]) == 20.0 else 1.0
        out = {}
        for letter, value in block.axes.items():
            i = AXES.index(letter)
            v = value * scale
            if block.g.get("non_modal") == 53.0:
                out[i] = v - self._base()[i]
            elif distance == 91.0:
                out[i] = self.stage.planned_mm(i) + v
            else:
                out[i] = v + self._user[i]
        return out

    def _gcode(self, block: Block) -> None:
        m = self._modal
        for key in ("distance", "units"):
            if key in block.g:
                m[key] = block.g[key]
        if "motion" in block.g:
            m["motion"] = block.g["motion"]
        if "F" in block.words:
            m["feed"] = block.words["F"] * (MM_PER_INCH if m["units"] == 20.0 else 1.0)
        if block.g.get("non_modal") == 4.0:
            self._dwell(block.words["P"])
            return
        if block.g.get("non_modal") == 10.0:
            self._set_offset(block)
            return
        targets = self._targets(block, m["distance"])
        if targets and m["motion"] == 1.0 and m["feed"] <= 0:
            raise CodeError(22)
        if block.m.get("stop") in (2, 30):
            self._send("[MSG:Pgm End]")
        if not targets or self._check:
            self._send("ok")
            return
        feed = float("inf") if m["motion"] == 0.0 else m["feed"]  # G0: each axis' max rate
        self._plan_motion([(a, lambda a=a, t=t: self.stage.move_to(t, feed, AXES[a])) for a, t in targets.items()])

    def _plan_motion(self, moves: list[tuple[int, Callable[[], None]]]) -> None:
        """Plan one block per axis; with the planner full the line waits (and RX fills), like GRBL."""

        def plan() -> bool:
            try:
                while moves and self.stage.planner_free() > 0:
                    moves.pop(0)[1]()
            except GrblError as e:
                self._alarm(e.code, line_open=True) if e.kind == "alarm" else self._send(f"error:{e.code}")
                return True
            if moves:
                return False
            self._send("ok")
            return True

        if not plan():
            self._pending = plan

    def _set_offset(self, block: Block) -> None:
        """G10 L2 P1 (offset = the values) / G10 L20 P1 (the current position becomes the values), G54 only.

        gcode.c: G10 waits for the planner (protocol_buffer_synchronize via the
        coordinate-change path) and GRBL reports the new WCO at once.
        """
        scale = MM_PER_INCH if block.g.get("units", self._modal["units"]) == 20.0 else 1.0
        for letter, value in block.axes.items():
            i = AXES.index(letter)
            v = value * scale
            if block.words["L"] == 20:
                self._user[i] = self.stage.planned_mm(i) - v
            else:
                self._user[i] = v - self._base()[i]
        self._wco_counter = 0
        self._send("ok")

    def _dwell(self, seconds: float) -> None:
        """G4: wait for the planner to empty, then dwell (simulated seconds), then ``ok``."""
        end: list[float] = []

        def done() -> bool:
            if self.stage.status().state != "Idle" and not self._check:
                return False
            if not end:
                end.append(self.stage.clock.now() + seconds)
            if self.stage.clock.now() < end[0]:
                return False
            self._send("ok")
            return True

        if not done():
            self._pending = done

    def _jog(self, block: Block) -> None:
        distance = block.g.get("distance", self._modal["distance"])
        targets = self._targets(block, distance)
        feed = block.words["F"] * (MM_PER_INCH if block.g.get("units", self._modal["units"]) == 20.0 else 1.0)
        for axis, target in targets.items():
            if self.stage.soft_limits and not self.stage.travel_mm[0] <= target <= self.stage.travel_mm[1]:
                raise CodeError(15)
        self._plan_motion(
            [(a, lambda a=a, t=t: self.stage.jog(t - self.stage.planned_mm(a), feed, AXES[a])) for a, t in targets.items()]
        )
