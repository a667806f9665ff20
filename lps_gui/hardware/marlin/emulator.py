"""A Marlin 2.1 controller on a pseudo-terminal, written from Marlin's own sources.

What it answers mirrors ``Marlin/src/gcode/queue.cpp`` (line numbers and
checksums: ``N<n> <cmd>*<xor>``; a wrong number, a bad or missing checksum is
``Error:<reason>, Last Line: <n>``, then ``Resend: <n+1>`` and ``ok``; ``M110 N``
sets the line number), ``gcode.cpp`` (``echo:busy: processing`` every
``host_keepalive_interval`` = 2 s while a command blocks; ``echo:Unknown
command: "<cmd>"`` then ``ok``), ``M114`` (``X:.. Y:.. Z:.. E:.. Count X:..``),
``M400`` (ok once the planner is empty), ``G28``, ``M92``/``M203``/``M201`` and
``M503`` (the settings as ``echo:`` lines). Soft endstops clamp a move
(``apply_motion_limits``) instead of refusing it. The pty serving loop and the
link's faults (a vanished port, slow replies, garbage) are the line emulator's
(:class:`~lps_gui.hardware.line_emulator.LineEmulator`); Marlin's own switch,
``corrupt_every``, turns every Nth received line into line noise (a checksum
mismatch) so the host's resend is exercised.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Callable, Iterator

from lps_gui.hardware.line_emulator import LineEmulator, LinkedFirmware, LinkFaults
from lps_gui.hardware.sim_stage import SimulatedStage

KEEPALIVE_S = 2.0  # Configuration.h DEFAULT_KEEPALIVE_INTERVAL
AXES = "XYZ"
BANNER = ("start", "echo:Marlin 2.1.2.1 (lps-calib emulator)", "echo: Free Memory: 4096  PlannerBufferBytes: 1232")
_WORD = re.compile(r"([A-Z])\s*([-+]?[0-9]*\.?[0-9]*)")


@dataclass
class MarlinFaults(LinkFaults):
    """The link's switches (drop_after_lines, reply_delay_s, garbage_every) plus Marlin's ``corrupt_every``."""

    corrupt_every: int = 0


def checksum(text: str) -> int:
    """queue.cpp: XOR of every byte before ``*``."""
    cs = 0
    for ch in text.encode("latin-1"):
        cs ^= ch
    return cs


class MarlinFirmware(LinkedFirmware):
    """Marlin's serial queue and G-code handlers over a :class:`SimulatedStage` (one command at a time).

    A :class:`~lps_gui.hardware.line_emulator.LineFirmware`: bytes go to
    :meth:`receive`, :meth:`poll` runs the executing command, output goes to ``send``.
    """

    def __init__(self, stage: SimulatedStage, faults: LinkFaults, send: Callable[[str], None],
                 on_drop: Callable[[], None]) -> None:
        super().__init__(faults, send, on_drop)
        self.stage = stage
        self.lines_received = 0
        self.last_n = 0
        self.steps_per_mm = [80.0, 80.0, 400.0]
        self._rx = bytearray()
        self._pending: Iterator[None] | None = None
        self._next_busy = 0.0

    @property
    def busy(self) -> bool:
        return self._pending is not None or self.stage.next_event_s() is not None

    def power_up(self) -> None:
        """The start-up lines Marlin prints."""
        for line in BANNER:
            self._send(line)

    def receive(self, b: int) -> None:
        self._rx.append(b)

    def drain(self) -> None:
        """Nothing per byte: Marlin's queue takes whole lines in its idle loop (:meth:`poll`)."""

    def poll(self) -> None:
        if self.halted:
            return
        if self._pending is not None:
            self._step_pending()
        while self._pending is None and not self.halted and b"\n" in self._rx.replace(b"\r", b"\n"):
            self._next_line()

    # ------------------------------------------------------------------ queue.cpp
    def _next_line(self) -> None:
        buf = self._rx.replace(b"\r", b"\n")
        end = buf.index(b"\n")
        raw = self._rx[:end].decode("latin-1").split(";", 1)[0].strip()
        del self._rx[: end + 1]
        if not raw:
            return
        self.lines_received += 1
        if self._cable_goes(self.lines_received):
            return
        every = getattr(self.faults, "corrupt_every", 0)  # a link's faults (lps emulate's switches) have none
        corrupt = bool(every) and self.lines_received % every == 0
        command = self._check_line(raw, corrupt)
        if command is not None:
            self._pending = self._execute(command)
            self._step_pending()

    def _check_line(self, raw: str, corrupt: bool) -> str | None:
        """The command of a line that passes queue.cpp's checks; None after an error and a resend request."""
        if not raw.startswith("N"):
            return raw
        star = raw.rfind("*")
        body = raw[:star] if star >= 0 else raw
        m = re.match(r"N(-?\d+)\s*(.*)", body)
        if m is None:
            return raw
        number, command = int(m.group(1)), m.group(2).strip()
        m110 = command.startswith("M110")
        if m110:
            second = re.search(r"N(-?\d+)", command[4:])
            number = int(second.group(1)) if second else number
        if number != self.last_n + 1 and not m110:
            return self._line_error("Line Number is not Last Line Number+1, Last Line: ")
        if star < 0:
            return self._line_error("No Checksum with line number, Last Line: ")
        if corrupt or raw[star + 1:].strip() != str(checksum(body)):
            return self._line_error("checksum mismatch, Last Line: ")
        self.last_n = number
        return command

    def _line_error(self, reason: str) -> None:
        self._send(f"Error:{reason}{self.last_n}")
        self._rx.clear()  # gcode_line_error() drains the RX buffer
        self._send(f"Resend: {self.last_n + 1}")
        self._send("ok")
        return None

    # ------------------------------------------------------------------ gcode.cpp
    def _step_pending(self) -> None:
        try:
            next(self._pending)  # type: ignore[arg-type]
        except StopIteration:
            self._pending = None
            if not self.halted:
                self._send("ok")
            return
        now = self.stage.clock.now()
        if now >= self._next_busy:  # host_keepalive()
            self._send("echo:busy: processing")
            self._next_busy = now + KEEPALIVE_S

    def _execute(self, command: str) -> Iterator[None]:
        words = [(k, v) for k, v in _WORD.findall(command.upper())]
        if not words:
            self._send(f'echo:Unknown command: "{command}"')
            return
        (letter, number), params = words[0], {k: v for k, v in words[1:]}
        code = f"{letter}{number}"
        self._next_busy = self.stage.clock.now() + KEEPALIVE_S
        if code in ("G0", "G1", "G00", "G01"):
            self._move(params)
        elif code == "G28":
            self.stage.start_home()
            yield from self._synchronize()
        elif code == "M400":
            yield from self._synchronize()
        elif code == "M114":
            self._send(self._position_line())
        elif code in ("M92", "M203", "M201"):
            self._set(code, params)
        elif code == "M503":
            for line in self._settings_lines():
                self._send(line)
        elif code == "M110":
            self.last_n = int(float(params.get("N") or 0))
        elif code == "M112":
            self.halted = True
            self._send("Error:Printer halted. kill() called!")
            return  # no ok: the firmware is dead until a reset (_step_pending)
        elif code == "M410":  # quickstop_stepper()
            self.stage.soft_reset()
            self.stage.unlock()
        elif code in ("G90", "G21", "M17", "M18", "M84", "M500", "M115"):
            if code == "M115":
                self._send("FIRMWARE_NAME:Marlin 2.1.2.1 (lps-calib emulator) PROTOCOL_VERSION:1.0 MACHINE_TYPE:gantry "
                           "EXTRUDER_COUNT:0")
        else:
            self._send(f'echo:Unknown command: "{command}"')
        return
        yield  # a generator even when it never waits

    def _synchronize(self) -> Iterator[None]:
        """planner.synchronize(): wait, answering nothing, until every move ended."""
        while self.stage.status().state not in ("Idle", "Alarm"):
            yield

    def _move(self, params: dict[str, str]) -> None:
        feed = float(params["F"]) if params.get("F") else None
        if feed is not None:
            self._feed = feed
        for i, ax in enumerate(AXES):
            if params.get(ax):
                lo, hi = self.stage.axis_travel_mm[i]
                target = min(max(float(params[ax]), lo), hi)  # soft endstops clamp (apply_motion_limits)
                self.stage.move_to(target, getattr(self, "_feed", 3000.0), ax)

    def _position_line(self) -> str:
        """M114: report_current_position_projected() then the stepper counts."""
        pos = self.stage.status().work_mm
        xyz = " ".join(f"{ax}:{p:.2f}" for ax, p in zip(AXES, pos))
        counts = " ".join(f"{ax}:{round(p * s)}" for ax, p, s in zip(AXES, pos, self.steps_per_mm))
        return f"{xyz} E:0.00 Count {counts}"

    def _set(self, code: str, params: dict[str, str]) -> None:
        for i, ax in enumerate(AXES):
            if not params.get(ax):
                continue
            v = float(params[ax])
            if code == "M92":
                self.steps_per_mm[i] = v
            elif code == "M203":  # mm/s
                self.stage.set_machine(f"max_rate_mm_min.{ax}", v * 60.0)
            else:
                self.stage.set_machine(f"accel_mm_s2.{ax}", v)

    def _settings_lines(self) -> list[str]:
        """M503's report (MarlinSettings::report) for the values this emulator keeps."""
        st = self.stage.machine
        return [
            "echo:; Steps per unit:",
            "echo: M92 " + " ".join(f"{ax}{s:.2f}" for ax, s in zip(AXES, self.steps_per_mm)) + " E500.00",
            "echo:; Maximum feedrates (units/s):",
            "echo: M203 " + " ".join(f"{ax}{st[f'max_rate_mm_min.{ax}'] / 60.0:.2f}" for ax in AXES) + " E25.00",
            "echo:; Maximum Acceleration (units/s2):",
            "echo: M201 " + " ".join(f"{ax}{st[f'accel_mm_s2.{ax}']:.2f}" for ax in AXES) + " E10000.00",
        ]


class MarlinEmulator(LineEmulator):
    """Marlin 2.1 on a pty: ``start()`` returns the device path ``marlin:PATH`` opens."""

    firmware: MarlinFirmware

    def __init__(self, stage: SimulatedStage | None = None, faults: LinkFaults | None = None, time_scale: float = 1.0,
                 stepped: bool = False) -> None:
        super().__init__(stage, faults or MarlinFaults(), time_scale, stepped, name="marlin-emulator")
        self.firmware = MarlinFirmware(self.stage, self.faults, send=self._send, on_drop=self._drop_now)
