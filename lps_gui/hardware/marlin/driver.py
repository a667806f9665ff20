"""A Marlin 2.x controller on a serial port: G-code with line numbers and checksums, one command at a time.

Every line goes out as ``N<n> <cmd>*<xor>`` (the host protocol of Pronterface and
OctoPrint, checked by Marlin's ``queue.cpp``) and waits for its ``ok``. A
``Resend: N`` (line noise, a lost byte) sends line N again; ``echo:busy:
processing`` (host_keepalive, every 2 s while a command blocks) means "still
working" and extends the wait; an ``Error:`` that no resend follows fails the
command with Marlin's own words. ``G0`` is acknowledged once planned, so
:meth:`MarlinStage.wait_idle` sends ``M400`` (ok once every move ended), and
positions come from ``M114``. Settings are those ``M503`` reports, numbered
M-code * 10 + axis (920 = ``M92 X`` steps/mm, 2030 = ``M203 X`` max feed mm/s,
2010 = ``M201 X`` max acceleration mm/s2).
"""
from __future__ import annotations

import re
import threading
import time
from typing import Any

from lps_gui.errors import HardwareError
from lps_gui.hardware.capabilities import Console, Settings
from lps_gui.hardware.stage import AXES, Stage, StageSetting, StageStatus

_M114 = re.compile(r"X:\s*(-?[\d.]+)\s+Y:\s*(-?[\d.]+)\s+Z:\s*(-?[\d.]+)")
_M503 = re.compile(r"echo:\s*M(92|203|201)\s+(.*)")
SETTING_NAMES = {92: ("steps per mm", "steps/mm"), 203: ("max feedrate", "mm/s"), 201: ("max acceleration", "mm/s^2")}
BOOT_S = 3.0  # an Arduino resets when the port opens and Marlin boots: the first M110 may go unanswered


def checksum(text: str) -> int:
    """Marlin's line checksum: XOR of every byte before ``*``."""
    cs = 0
    for ch in text.encode("ascii"):
        cs ^= ch
    return cs


class MarlinStage(Stage, Settings, Console):
    """Marlin 2.x on ``port`` (a device name or a pyserial URL); positions in mm, feeds in mm/min."""

    settings_title = "Marlin settings (M503)"
    console_hint = "G-code, e.g. M503  M114  G0 X10 F600  (Up/Down: history)"

    def __init__(self, port: Any, baudrate: int = 115200, timeout_s: float = 5.0, axis: str = "X",
                 move_timeout_s: float = 600.0) -> None:
        super().__init__()
        self.port = port
        self.baudrate = baudrate
        self.timeout_s = timeout_s
        self.move_timeout_s = move_timeout_s
        self.axis = axis
        self._serial: Any = None
        self._n = 0
        self._lock = threading.RLock()
        self._moving = False
        self._last = StageStatus("Disconnected")
        self.settings: dict[int, float] = {}
        self.resends = 0  # lines Marlin asked for again (line noise shows here)

    @property
    def port_name(self) -> str:
        return str(self.port)

    # ------------------------------------------------------------------ connection
    def connect(self) -> None:
        import serial

        try:
            self._serial = serial.serial_for_url(self.port, baudrate=self.baudrate, timeout=0.05)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise HardwareError(f"Marlin on {self.port_name}: cannot open the port ({exc}); check the cable and the name")
        try:
            self._n = 0
            self._exchange("M110 N0", numbered=False, timeout_s=BOOT_S, retries=1)
        except BaseException:
            self.disconnect()
            raise

    def disconnect(self) -> None:
        if self._serial is not None:
            try:
                self._serial.close()
            except Exception:  # a vanished port cannot be closed cleanly
                pass
        self._serial = None

    @property
    def connected(self) -> bool:
        return self._serial is not None

    # ------------------------------------------------------------------ the line protocol
    def _write(self, text: str) -> None:
        try:
            self._serial.write((text + "\n").encode("ascii"))
        except Exception as exc:
            self.disconnect()
            raise HardwareError(f"Marlin on {self.port_name}: the port is gone ({exc}); reconnect it") from None

    def _readline(self) -> str:
        try:
            raw = self._serial.readline()
        except Exception as exc:
            self.disconnect()
            raise HardwareError(f"Marlin on {self.port_name}: the port is gone ({exc}); reconnect it") from None
        return raw.decode("ascii", "replace").strip()

    def _exchange(self, command: str, numbered: bool = True, timeout_s: float | None = None, retries: int = 0) -> list[str]:
        """Send one command and wait for its ``ok``; return the lines Marlin printed before it."""
        self.require_connected()
        with self._lock:
            if numbered:
                self._n += 1
                body = f"N{self._n} {command}"
                line = f"{body}*{checksum(body)}"
            else:
                line = command
            wait_s = self.timeout_s if timeout_s is None else timeout_s
            out: list[str] = []
            resend = False
            error = ""
            self._write(line)
            deadline = time.monotonic() + wait_s
            while True:
                if time.monotonic() > deadline:
                    if retries > 0:
                        retries -= 1
                        self._write(line)
                        deadline = time.monotonic() + wait_s
                        continue
                    raise HardwareError(f"Marlin on {self.port_name}: no answer to {command!r} within {wait_s:g} s; "
                                        "check the port and the baud rate")
                text = self._readline()
                if not text:
                    if self._serial is not None and not self._port_alive():
                        raise HardwareError(f"Marlin on {self.port_name}: the port is gone; reconnect it")
                    continue
                if text.startswith("echo:busy"):
                    deadline = time.monotonic() + wait_s  # host_keepalive: still working
                elif text.startswith(("Resend:", "rs ")):
                    resend = True  # the ok that follows belongs to the refused line
                    self.resends += 1
                elif text.startswith("Error:"):
                    error = text[6:].strip()
                    if "kill() called" in error or "halted" in error:
                        raise HardwareError(f"Marlin on {self.port_name}: {error}; reset the controller")
                elif text == "ok" or text.startswith("ok "):
                    if resend:
                        resend, error = False, ""
                        self._write(line)
                        deadline = time.monotonic() + wait_s
                        continue
                    if error:
                        raise HardwareError(f"Marlin on {self.port_name}: {command!r}: {error}")
                    return out
                else:
                    if text.startswith("echo:Unknown command"):
                        error = text[5:].strip()
                    out.append(text)

    def _port_alive(self) -> bool:
        """A pty whose other end closed reads empty forever: ask the port whether it is still there."""
        try:
            self._serial.in_waiting
        except Exception:
            self.disconnect()
            return False
        return True

    def command(self, line: str, timeout_s: float | None = None) -> list[str]:
        return self._exchange(line.strip(), timeout_s=timeout_s)

    # ------------------------------------------------------------------ Stage
    def status(self) -> StageStatus:
        """``M114``; while a move is waited for (M400 holds the line), the last position marked Run."""
        if not self._lock.acquire(timeout=0.05):
            return StageStatus("Run", machine_mm=self._last.machine_mm, work_mm=self._last.work_mm, time=time.monotonic())
        try:
            for text in self._exchange("M114"):
                m = _M114.search(text)
                if m:
                    pos = tuple(float(v) for v in m.groups())
                    self._last = StageStatus("Idle", machine_mm=pos, work_mm=pos, time=time.monotonic())  # type: ignore[arg-type]
                    return self._last
            raise HardwareError(f"Marlin on {self.port_name}: M114 reported no position")
        finally:
            self._lock.release()

    def home(self) -> None:
        self._exchange(f"G28 {self.axis}", timeout_s=self.move_timeout_s)

    def move_to(self, position_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        ax = (axis or self.axis).upper()
        if ax not in AXES:
            raise HardwareError(f"Marlin: axis {ax!r} unknown; use X, Y or Z")
        self._exchange(f"G1 {ax}{position_mm:.4f} F{feed_mm_min:.1f}")

    def wait_idle(self, timeout_s: float = 60.0) -> StageStatus:
        self._exchange("M400", timeout_s=timeout_s)
        return self.status()

    def stop(self) -> None:
        """``M410`` quickstop: the planner is emptied, the steppers stop (the position is kept)."""
        self._exchange("M410")

    # ------------------------------------------------------------------ settings
    def read_settings(self) -> list[StageSetting]:
        values: dict[int, float] = {}
        for text in self._exchange("M503"):
            m = _M503.match(text)
            if not m:
                continue
            code = int(m.group(1))
            for word in m.group(2).split():
                if word[:1] in AXES and len(word) > 1:
                    values[code * 10 + AXES.index(word[0])] = float(word[1:])
        self.settings = values
        out = []
        for number, v in sorted(values.items()):
            name, unit = SETTING_NAMES[number // 10]
            out.append(StageSetting(number, v, f"{AXES[number % 10]} {name}", unit, f"M{number // 10} {AXES[number % 10]}"))
        return out

    def write_setting(self, number: int, value: float) -> None:
        code, axis = divmod(int(number), 10)
        if code not in SETTING_NAMES or axis > 2:
            raise HardwareError(f"Marlin setting {number}: unknown; read the settings (M503) for their numbers")
        self._exchange(f"M{code} {AXES[axis]}{value:g}")
        self.settings[number] = float(value)

    def setting_label(self, setting: StageSetting) -> str:
        return f"M{setting.number // 10} {AXES[setting.number % 10]}"

    def travel_text(self, settings: list[StageSetting]) -> str:
        return "travel: Marlin's soft endstops clamp moves to the bed size (Configuration.h X_MAX_POS...)"

    def describe(self) -> dict:
        return {**super().describe(), "port": self.port_name, "baudrate": self.baudrate,
                "settings": {f"M{n // 10} {AXES[n % 10]}": v for n, v in sorted(self.settings.items())}}
