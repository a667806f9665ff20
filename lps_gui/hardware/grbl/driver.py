"""GRBL 1.1 over pyserial: a :class:`Stage` that speaks the real protocol.

Transport apart from protocol (PyMeasure's ``adapters/serial.py`` habit): the
constructor takes a port name (anything ``serial.serial_for_url`` opens:
``/dev/ttyUSB0``, ``COM3``, ``socket://host:port``) or an already-open pyserial
object (an emulator's pty, a scripted fake in protocol tests).

One reader thread turns incoming lines into state: ``ok``/``error:N`` answer
the oldest unacknowledged line (GRBL answers in order), status reports update
the last known status, ``ALARM:N`` / ``[MSG:]`` / the banner become events.
Lines are sent with GRBL's character-counting rule (unacknowledged bytes stay
within the 127 usable bytes of the RX buffer, size read from ``$I``), so a
stream of moves keeps the planner full; settings are sent only with nothing
in flight (send-response), as GRBL's docs require for EEPROM writes.
Real-time bytes (``?`` ``!`` ``~`` 0x18 0x85) go out at once and are never counted.
Every wait has a deadline: a silent controller or a vanished port becomes a
one-line :class:`HardwareError`, never a hang.
"""
from __future__ import annotations

import collections
import logging
import threading
import time
from dataclasses import dataclass, field

import serial

from lps_gui.errors import HardwareError, InputError
from lps_gui.hardware.grbl.codes import GrblError, format_setting, setting_info
from lps_gui.hardware.grbl.protocol import (
    MM_PER_INCH,
    BuildInfo,
    StatusReport,
    classify,
    jog_line,
    move_line,
    parse_build_info,
    parse_settings,
)
from lps_gui.hardware.stage import Stage, StageEvent, StageSetting, StageStatus

log = logging.getLogger(__name__)
RT_STATUS, RT_HOLD, RT_RESUME, RT_RESET, RT_JOG_CANCEL = b"?", b"!", b"~", b"\x18", b"\x85"


class ControllerReset(HardwareError):
    """GRBL printed its banner (it reset) while a line waited for its answer."""


@dataclass
class _Pending:
    """A sent line waiting for its ``ok``/``error:N``; push lines in between are collected."""

    line: str
    nbytes: int
    done: threading.Event = field(default_factory=threading.Event)
    lines: list[str] = field(default_factory=list)
    error: Exception | None = None


class GrblStage(Stage):
    """A GRBL 1.1 controller on a serial port.

    Parameters
    ----------
    port : port name/URL, or an open (or openable) pyserial object.
    baudrate : GRBL's default is 115200.
    timeout_s : longest wait for any reply (homing has its own, longer, limit).
    axis : the axis the measurement moves along.
    poll_interval_s : status polling period while waiting for motion (GRBL: <= 10 Hz recommended 5 Hz).
    homing_timeout_s : longest homing cycle.
    reset_on_connect : send a soft reset on connect and wait for the banner (a real
        Arduino also resets when the port opens); otherwise just ask for status.
    """

    def __init__(
        self,
        port: str | serial.SerialBase,
        baudrate: int = 115200,
        timeout_s: float = 5.0,
        axis: str = "X",
        poll_interval_s: float = 0.05,
        homing_timeout_s: float = 300.0,
        reset_on_connect: bool = True,
    ) -> None:
        super().__init__()
        self.axis = axis
        self.port = port
        self.port_name = port if isinstance(port, str) else (getattr(port, "port", None) or repr(port))
        self.baudrate = baudrate
        self.timeout_s = timeout_s
        self.poll_interval_s = poll_interval_s
        self.homing_timeout_s = homing_timeout_s
        self.reset_on_connect = reset_on_connect
        self.build_info: BuildInfo | None = None
        self.version = ""
        self.settings: dict[int, float] = {}
        self.garbage_lines = 0
        self._serial: serial.SerialBase | None = None
        self._owns_serial = isinstance(port, str)
        self._reader: threading.Thread | None = None
        self._stop = threading.Event()
        self._cond = threading.Condition()
        self._write_lock = threading.Lock()
        self._status_lock = threading.Lock()
        self._pending: collections.deque[_Pending] = collections.deque()
        self._rx_used = 0
        self._rx_size = 128
        self._dead: HardwareError | None = None
        self._banners = 0
        self._status: StageStatus | None = None
        self._status_seq = 0
        self._wco = (0.0, 0.0, 0.0)
        self._overrides: tuple[int, int, int] | None = None
        self._alarm_code: int | None = None
        self._critical = False
        self._homing = False
        self._last_state = ""

    # ------------------------------------------------------------------ connection
    def connect(self) -> None:
        """Open the port, reset (or query) the controller, read ``$I`` and ``$$``."""
        if self.connected:
            return
        self._open()
        self._dead = None
        self._stop.clear()
        self._pending.clear()
        self._rx_used = 0
        self._critical = self._homing = False
        self._reader = threading.Thread(target=self._read_loop, name=f"grbl-reader {self.port_name}", daemon=True)
        self._reader.start()
        try:
            if self.reset_on_connect:
                n = self._banners
                self._write(RT_RESET)
                self._wait_for(lambda: self._banners > n, self.timeout_s,
                               f"no GRBL startup banner within {self.timeout_s:g} s; is a GRBL 1.1 controller on this port at {self.baudrate} baud?")
            for attempt in range(3):  # a boot banner may follow our reset banner (Arduino auto-reset)
                try:
                    self.build_info = parse_build_info(self.command("$I"))
                    break
                except ControllerReset:
                    if attempt == 2:
                        raise
            self._rx_size = self.build_info.rx_buffer_bytes
            self.settings = parse_settings(self.command("$$"))
            self.status()
        except Exception:
            self._shutdown()
            raise
        self.events.emit(StageEvent("connected", text=f"GRBL {self.version or self.build_info.version} on {self.port_name}"))

    def _open(self) -> None:
        try:
            if isinstance(self.port, str):
                self._serial = serial.serial_for_url(self.port, baudrate=self.baudrate, timeout=0.05, write_timeout=self.timeout_s)
            else:
                self._serial = self.port
                if not self._serial.is_open:
                    self._serial.open()
            self._serial.reset_input_buffer()
        except (serial.SerialException, OSError, ValueError) as exc:
            raise HardwareError(f"GRBL: cannot open port {self.port_name!r} ({exc}); check the cable and the port name") from None

    def disconnect(self) -> None:
        self._shutdown()
        self.events.emit(StageEvent("disconnected", text=f"disconnected from {self.port_name}"))

    def _shutdown(self) -> None:
        self._stop.set()
        if self._reader is not None and self._reader is not threading.current_thread():
            self._reader.join(timeout=1.0)
        if self._serial is not None and self._owns_serial:
            try:
                self._serial.close()
            except Exception:  # closing a vanished port may fail; it is gone either way
                pass
        self._fail_pending(HardwareError(f"GRBL on {self.port_name}: disconnected"))
        if self._dead is None:
            self._dead = HardwareError(f"GRBL on {self.port_name}: not connected; connect the stage first")

    @property
    def connected(self) -> bool:
        return self._reader is not None and self._reader.is_alive() and self._dead is None

    def require_connected(self) -> None:
        if self._dead is not None:
            raise self._dead
        super().require_connected()

    # ------------------------------------------------------------------ reading
    def _read_loop(self) -> None:
        buf = bytearray()
        ser = self._serial
        while not self._stop.is_set():
            try:
                data = ser.read(max(1, ser.in_waiting))
            except Exception as exc:  # SerialException, OSError (EIO), TypeError on a closed fd
                if not self._stop.is_set():
                    self._vanished(exc)
                return
            if not data:
                continue
            buf += data
            while True:
                i = min((k for k in (buf.find(b"\n"), buf.find(b"\r")) if k >= 0), default=-1)
                if i < 0:
                    break
                raw = bytes(buf[:i])
                del buf[: i + 1]
                line = raw.decode("ascii", errors="replace").strip()
                if line:
                    try:
                        self._dispatch(line)
                    except Exception:  # a parser bug must not kill the reader
                        log.exception("GRBL: failed to handle %r", line)

    def _vanished(self, exc: BaseException) -> None:
        err = HardwareError(f"GRBL on {self.port_name}: the port vanished ({exc}); reconnect the stage and resume")
        self._dead = err
        self._fail_pending(err)
        self.events.emit(StageEvent("disconnected", text=str(err)))

    def _fail_pending(self, err: Exception) -> None:
        with self._cond:
            while self._pending:
                p = self._pending.popleft()
                p.error = err
                p.done.set()
            self._rx_used = 0
            self._cond.notify_all()

    def _dispatch(self, line: str) -> None:
        log.debug("GRBL << %r", line)
        msg = classify(line)
        kind = msg.kind
        if kind in ("ok", "error"):
            with self._cond:
                if not self._pending:
                    log.warning("GRBL: %r with no command in flight; ignored", line)
                    return
                p = self._pending.popleft()
                self._rx_used -= p.nbytes
                if kind == "error":
                    p.error = GrblError("error", int(msg.code), f"GRBL rejected {p.line!r}")
                p.done.set()
                self._cond.notify_all()
            if kind == "error":
                self.events.emit(StageEvent("error", code=msg.code, text=str(p.error)))
        elif kind == "status":
            self._on_status(msg.status)
        elif kind == "alarm":
            self._alarm_code = int(msg.code)
            err = GrblError("alarm", int(msg.code), f"GRBL on {self.port_name}")
            self._fail_pending(err)
            with self._cond:
                self._cond.notify_all()
            self.events.emit(StageEvent("alarm", code=msg.code, text=str(err)))
        elif kind == "banner":
            self.version = msg.text
            self._critical = False
            self._fail_pending(ControllerReset(f"GRBL on {self.port_name} was reset while a command was in flight; check the stage state"))
            with self._cond:
                self._banners += 1
                self._cond.notify_all()
            self.events.emit(StageEvent("message", text=f"Grbl {msg.text} started"))
        elif kind == "msg":
            if msg.text == "Reset to continue":
                self._critical = True
            self._attach(line)
            self.events.emit(StageEvent("message", text=msg.text))
        elif kind in ("feedback", "setting", "startup"):
            self._attach(line)
        else:
            self.garbage_lines += 1
            log.warning("GRBL: unrecognized line %r ignored", line)

    def _attach(self, line: str) -> None:
        with self._cond:
            if self._pending:
                self._pending[0].lines.append(line)

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
        with self._cond:
            self._status = st
            self._status_seq += 1
            self._cond.notify_all()
        if r.state != self._last_state:
            self._last_state = r.state
            self.events.emit(StageEvent("state", text=r.state))

    # ------------------------------------------------------------------ writing
    def _write(self, data: bytes) -> None:
        self.require_connected()
        try:
            with self._write_lock:
                self._serial.write(data)
        except Exception as exc:
            self._vanished(exc)
            raise self._dead from None

    def _wait_for(self, predicate, timeout_s: float, what: str) -> None:
        deadline = time.monotonic() + timeout_s
        with self._cond:
            while not predicate():
                if self._dead is not None:
                    raise self._dead
                left = deadline - time.monotonic()
                if left <= 0:
                    raise HardwareError(f"GRBL on {self.port_name}: {what}")
                self._cond.wait(min(left, 0.1))

    def send(self, line: str, timeout_s: float | None = None) -> _Pending:
        """Queue a line within the RX-buffer budget (character counting); return without its answer."""
        data = (line.strip() + "\n").encode("ascii")
        if len(data) > min(self._rx_size - 1, 80):
            raise InputError(f"GRBL line too long ({len(data)} bytes > 80): {line!r}")
        timeout_s = self.timeout_s if timeout_s is None else timeout_s
        self._wait_for(lambda: self._rx_used + len(data) <= self._rx_size - 1, timeout_s,
                       f"RX buffer still full after {timeout_s:g} s; the controller stopped answering")
        p = _Pending(line.strip(), len(data))
        with self._cond:
            self._pending.append(p)
            self._rx_used += len(data)
        self._write(data)
        return p

    def wait_reply(self, p: _Pending, timeout_s: float | None = None) -> list[str]:
        """Wait for the answer of a sent line; its push lines, or GrblError/HardwareError."""
        timeout_s = self.timeout_s if timeout_s is None else timeout_s
        if not p.done.wait(timeout_s):
            if self._dead is not None:
                raise self._dead
            raise HardwareError(
                f"GRBL on {self.port_name}: no reply to {p.line!r} within {timeout_s:g} s; check the cable or reset the controller"
            )
        if p.error is not None:
            raise p.error
        return p.lines

    def command(self, line: str, timeout_s: float | None = None) -> list[str]:
        """Send one line and wait for its ``ok`` (send-response); return the lines it printed."""
        return self.wait_reply(self.send(line, timeout_s), timeout_s)

    def stream(self, lines: list[str], timeout_s: float | None = None) -> None:
        """Stream G-code with character counting; wait for every ``ok``; raise on the first error."""
        sent = [self.send(ln, timeout_s) for ln in lines if ln.strip()]
        for p in sent:
            self.wait_reply(p, timeout_s)

    def realtime(self, byte: bytes) -> None:
        """Send a real-time command byte (never counted, acted on at once)."""
        self._write(byte)

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
            self._write(RT_STATUS)
            self._wait_for(lambda: self._status_seq > n or self._critical, self.timeout_s,
                           f"no status report within {self.timeout_s:g} s; check the cable or reset the controller")
        return self._status if not self._critical else self.status()

    def home(self) -> None:
        self._homing = True
        try:
            self.command("$H", timeout_s=self.homing_timeout_s)
            self._alarm_code = None
        finally:
            self._homing = False

    def unlock(self) -> None:
        self.command("$X")
        self._alarm_code = None

    def soft_reset(self) -> None:
        """Ctrl-X and wait for the banner (GRBL raises ALARM:3 if it was moving)."""
        n = self._banners
        self._write(RT_RESET)
        self._wait_for(lambda: self._banners > n, self.timeout_s, f"no banner within {self.timeout_s:g} s after a soft reset")
        self._critical = False

    def feed_hold(self) -> None:
        self.realtime(RT_HOLD)

    def resume(self) -> None:
        self.realtime(RT_RESUME)

    # ------------------------------------------------------------------ Stage: motion
    def move_to(self, position_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        self._alarm_code = None
        self.command(move_line(position_mm, feed_mm_min, axis or self.axis))

    def jog(self, distance_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        self.command(jog_line(distance_mm, feed_mm_min, axis or self.axis))

    def jog_cancel(self) -> None:
        self.realtime(RT_JOG_CANCEL)

    def wait_idle(self, timeout_s: float = 60.0) -> StageStatus:
        """Poll ``?`` until Idle with nothing in flight; alarms and timeouts raise.

        GRBL may report Idle for a moment after acknowledging a move (before the
        cycle starts), so Idle counts once motion was seen, the planner reports
        empty, or two reports in a row agree.
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
            if st.state == "Idle" and not self._pending:
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

    def write_setting(self, number: int, value: float) -> None:
        """``$N=value``, sent only with nothing in flight (EEPROM writes stall GRBL's serial)."""
        self._wait_for(lambda: not self._pending, self.timeout_s, "commands still unanswered before a settings write")
        self.command(format_setting(number, value))
        self.settings[number] = float(value)

    def describe(self) -> dict:
        d = {**super().describe(), "port": str(self.port_name), "baudrate": self.baudrate}
        if self.build_info is not None:
            d.update(version=self.build_info.version, build=self.build_info.build, options=self.build_info.options)
        d["settings"] = {f"${n}": v for n, v in sorted(self.settings.items())}
        return d
