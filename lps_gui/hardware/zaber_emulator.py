"""A Zaber ASCII-protocol device (one linear axis, X-LSM-like) on a pseudo-terminal, over the simulated stage.

Written from Zaber's ASCII Protocol Manual (firmware 7): a command is
``/[device] [axis] [id] command [data][:CC]`` ended by CR or LF; the device
answers ``@dd a [id] FL STATUS WW data`` CR LF, where FL is ``OK`` or ``RJ``
(data then names why: ``BADCOMMAND``, ``BADDATA``, ``BADAXIS``), STATUS is
``BUSY`` while the axis moves and ``IDLE`` otherwise, and WW the highest
warning (``--`` none, ``WR`` no reference position until homed, ``NI`` a
move interrupted by a newer command). Device 0 (or none) addresses every
device; axis 0 the device. A checksum ``:CC`` is the two's complement of the
byte sum after the leading ``/`` (or ``@``), mod 256, in two hex digits; a
command whose checksum does not match is rejected (``BADDATA``), and replies
carry one when ``comm.checksum`` is 1.

Units are the device's own: positions in microsteps; ``maxspeed`` and the
speed of ``move abs N speed accel`` in microsteps/s x 1.6384; ``accel`` in
microsteps/s^2 x 1.6384 / 10000 (the manual's unit conversion appendix).
The emulated product has the X-LSM series' 3.048 um full step at the default
64 microsteps (0.047625 um per microstep). Position 0 is where the simulated
stage starts at 0 mm until ``home``, which (as the manual says) retracts to
the home sensor, backs off and resets the position to 0 there; then
``limit.min`` is 0 and ``limit.max`` the rest of the travel. The device is
served by the line emulator (:class:`~lps_gui.hardware.line_emulator.LineEmulator`:
the pty loop, simulated time, the link's faults) like GRBL's and Marlin's firmware.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from lps_gui.hardware.line_emulator import LineEmulator, LinkedFirmware, LinkFaults
from lps_gui.hardware.pty_device import emulated_stage
from lps_gui.hardware.sim_stage import SimulatedStage
from lps_gui.hardware.stage import AXES

FULL_STEP_UM = 3.048  # X-LSM series lead screw: one full step (datasheet)
DEFAULT_RESOLUTION = 64  # microsteps per full step
VELOCITY_SCALE = 1.6384  # native speed = microsteps/s * 1.6384
ACCEL_SCALE = 1.6384 / 10000.0  # native accel = microsteps/s^2 * 1.6384 / 10000
DEVICE_ID = 50081  # the id this emulator reports (identification needs Zaber's device database; the driver does not use it)


def checksum(body: str) -> str:
    """Zaber's message checksum: two's complement of the byte sum, mod 256, as two hex digits."""
    return f"{(256 - sum(body.encode('ascii')) % 256) % 256:02X}"


@dataclass
class Command:
    """One parsed ``/`` command."""

    device: int
    axis: int
    msg_id: int | None
    text: str  # command and data, e.g. "move abs 1000"
    checksum_ok: bool = True


def parse_command(line: str) -> Command | None:
    """Split ``/1 1 12 move abs 10:CC``; None for a line that is no command."""
    line = line.strip()
    if not line.startswith("/"):
        return None
    body = line[1:]
    ok = True
    if ":" in body:
        body, cc = body.rsplit(":", 1)
        ok = cc.strip().upper() == checksum(body)
    tokens = body.split()
    nums: list[int] = []
    while tokens and tokens[0].isdigit() and len(nums) < 3:
        nums.append(int(tokens.pop(0)))
    device = nums[0] if nums else 0
    axis = nums[1] if len(nums) > 1 else 0
    msg_id = nums[2] if len(nums) > 2 else None
    return Command(device, axis, msg_id, " ".join(tokens), ok)


class ZaberAsciiDevice:
    """The device's side of the ASCII protocol: lines in, replies out, motion on ``stage``."""

    def __init__(self, stage: SimulatedStage, address: int = 1, serial_number: int = 36036,
                 resolution: int = DEFAULT_RESOLUTION) -> None:
        self.stage = stage
        self.address = address
        self.axis_name = stage.axis
        self.microstep_mm = FULL_STEP_UM / resolution / 1000.0
        lo, hi = stage.axis_travel_mm[AXES.index(stage.axis)]
        self.settings = {
            "deviceid": DEVICE_ID, "system.serial": serial_number, "version": 7.38, "version.build": 17916,
            "system.axiscount": 1, "comm.checksum": 0, "comm.alert": 0, "resolution": resolution,
            "limit.min": round(lo / self.microstep_mm), "limit.max": round(hi / self.microstep_mm),
            "maxspeed": round(self._native_speed(stage.max_rate_mm_min(AXES.index(stage.axis)))),
            "accel": round(stage.accel_mm_s2(AXES.index(stage.axis)) / self.microstep_mm * ACCEL_SCALE),
        }
        self.warnings: set[str] = {"WR"}  # no reference position until homed
        self.homing = False
        self.origin_mm = 0.0  # where position 0 is on the simulated stage: the home position once homed
        self.received = 0  # commands received (the drop-after fault counts them)
        self.log: list[tuple[str, str]] = []  # (command line, reply line) as the device saw them
        self._buf = b""

    # ------------------------------------------------------------------ units
    def _native_speed(self, mm_min: float) -> float:
        return mm_min / 60.0 / self.microstep_mm * VELOCITY_SCALE

    def _mm_min(self, native_speed: float) -> float:
        return native_speed / VELOCITY_SCALE * self.microstep_mm * 60.0

    def _sim_mm(self) -> float:
        return self.stage.status().work_mm[AXES.index(self.axis_name)]

    def position(self) -> int:
        return round((self._sim_mm() - self.origin_mm) / self.microstep_mm)

    def busy(self) -> bool:
        return self.stage.status().state != "Idle"

    # ------------------------------------------------------------------ bytes
    def receive(self, data: bytes) -> bytes:
        self._buf += data
        out = []
        while True:
            ends = [k for k in (self._buf.find(b"\n"), self._buf.find(b"\r")) if k >= 0]
            if not ends:
                break
            raw, self._buf = self._buf[: min(ends)], self._buf[min(ends) + 1:]
            line = raw.decode("ascii", errors="replace")
            cmd = parse_command(line)
            if cmd is None:
                continue
            self.received += 1
            for reply in self.handle(cmd):
                self.log.append((line.strip(), reply))
                out.append(reply + "\r\n")
        return "".join(out).encode("ascii")

    def poll(self) -> bytes:
        if self.homing and not self.busy():  # the manual: homing ends by resetting the position to 0
            self.homing = False
            self.warnings.discard("WR")
            self.origin_mm = self._sim_mm()
            hi = self.stage.axis_travel_mm[AXES.index(self.axis_name)][1]
            self.settings["limit.min"], self.settings["limit.max"] = 0, round((hi - self.origin_mm) / self.microstep_mm)
        return b""

    # ------------------------------------------------------------------ commands
    def handle(self, cmd: Command) -> list[str]:
        """The replies to one command (none when it is for another device)."""
        if cmd.device not in (0, self.address):
            return []
        if not cmd.checksum_ok:
            return [self._reply(cmd, "RJ", "BADDATA")]
        if cmd.axis not in (0, 1):
            return [self._reply(cmd, "RJ", "BADAXIS")]
        words = cmd.text.split()
        try:
            flag, data = self._execute(cmd, words)
        except ValueError:
            flag, data = "RJ", "BADDATA"
        return [self._reply(cmd, flag, data)]

    def _execute(self, cmd: Command, words: list[str]) -> tuple[str, str]:
        if not words:
            return "OK", "0"
        verb, args = words[0], words[1:]
        if verb == "get" and len(args) == 1:
            return self._get(cmd, args[0])
        if verb == "set" and len(args) == 2:
            name = args[0]
            if name not in self.settings or name in ("deviceid", "system.serial", "version", "version.build", "system.axiscount"):
                return "RJ", "BADCOMMAND"
            self.settings[name] = float(args[1]) if "." in args[1] else int(args[1])
            if name == "resolution":
                self.microstep_mm = FULL_STEP_UM / int(args[1]) / 1000.0
            return "OK", "0"
        if verb == "home" and not args:
            self._interrupt()
            self.stage.start_home()
            self.homing = True
            return "OK", "0"
        if verb == "move" and args and args[0] in ("abs", "rel") and 2 <= len(args) <= 4:
            target = int(args[1]) + (self.position() if args[0] == "rel" else 0)
            if not self.settings["limit.min"] <= target <= self.settings["limit.max"]:
                return "RJ", "BADDATA"
            speed = float(args[2]) if len(args) > 2 and float(args[2]) > 0 else float(self.settings["maxspeed"])
            self._interrupt()
            start = self.stage.planned_mm(AXES.index(self.axis_name))
            self.stage.jog(self.origin_mm + target * self.microstep_mm - start, self._mm_min(speed), self.axis_name)
            return "OK", "0"
        if verb == "stop" and not args:
            self.stage.jog_cancel()
            return "OK", "0"
        if verb == "warnings" and (not args or args == ["clear"]):
            flags = sorted(self.warnings)
            if args:
                self.warnings.intersection_update({"WR"})  # WR clears only by homing
            return "OK", " ".join([f"{len(flags):02d}"] + flags)
        return "RJ", "BADCOMMAND"

    def _get(self, cmd: Command, name: str) -> tuple[str, str]:
        if name == "pos":
            return "OK", str(self.position())
        if name not in self.settings:
            return "RJ", "BADCOMMAND"
        v = self.settings[name]
        return "OK", (f"{v:.2f}" if isinstance(v, float) else str(v))

    def _interrupt(self) -> None:
        """A new motion command replaces the one running (warning NI), decelerating first."""
        if self.busy():
            self.stage.jog_cancel()
            self.warnings.add("NI")
            self.homing = False

    def _reply(self, cmd: Command, flag: str, data: str) -> str:
        status = "BUSY" if self.busy() else "IDLE"
        warn = "WR" if "WR" in self.warnings else ("NI" if "NI" in self.warnings else "--")
        body = f"{self.address:02d} {cmd.axis}" + (f" {cmd.msg_id:02d}" if cmd.msg_id is not None else "")
        body += f" {flag} {status} {warn} {data}"
        if self.settings["comm.checksum"]:
            body += ":" + checksum(body)
        return "@" + body


class ZaberFirmware(LinkedFirmware):
    """:class:`ZaberAsciiDevice` as the line emulator's firmware: each line the host ends goes to the device, its
    replies go out line by line; the link's drop fault counts the device's commands."""

    def __init__(self, device: ZaberAsciiDevice, faults: LinkFaults, send: Callable[[str], None],
                 on_drop: Callable[[], None]) -> None:
        super().__init__(faults, send, on_drop)
        self.device = device
        self._line = bytearray()

    @property
    def lines_received(self) -> int:
        return self.device.received

    @property
    def busy(self) -> bool:
        return self.device.homing or self.device.busy()

    def power_up(self) -> None:
        """A Zaber device says nothing until asked."""

    def receive(self, b: int) -> None:
        self._line.append(b)

    def drain(self) -> None:
        if self.halted or self._line[-1:] not in (b"\n", b"\r"):
            return
        data, self._line = bytes(self._line), bytearray()
        out = self.device.receive(data)
        if not self._cable_goes(self.device.received) and out:
            self._send(out.decode("ascii"))

    def poll(self) -> None:
        if not self.halted and (out := self.device.poll()):
            self._send(out.decode("ascii"))


class ZaberEmulator(LineEmulator):
    """A Zaber device on a pty: ``with ZaberEmulator(stage) as emu: ZaberStage(emu.path)``."""

    firmware: ZaberFirmware

    def __init__(self, stage: SimulatedStage | None = None, faults: LinkFaults | None = None, time_scale: float = 1.0,
                 stepped: bool = False, **device_options) -> None:
        super().__init__(stage, faults or LinkFaults(), time_scale, stepped, name="zaber-emulator")
        self.device = ZaberAsciiDevice(self.stage, **device_options)
        self.firmware = ZaberFirmware(self.device, self.faults, send=self._send, on_drop=self._drop_now)


def emulated_zaber_stage(time_scale: float = 1.0, simulated: SimulatedStage | None = None, **stage_options):
    """A :class:`~lps_gui.hardware.zaber.ZaberStage` connected to a fresh emulator that serves ``simulated``
    (else a new :class:`SimulatedStage` from ``stage_options``); disconnecting stops the emulator."""
    from lps_gui.hardware.zaber import ZaberStage

    return emulated_stage(ZaberStage, ZaberEmulator, simulated, stage_options, time_scale=time_scale)
