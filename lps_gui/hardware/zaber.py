"""A Zaber stage over the ASCII protocol, through Zaber's own library (zaber-motion) as the client.

zaber-motion frames every command (message ids, checksums), matches replies,
polls for IDLE and raises on rejections, so this driver only maps the Stage
interface onto one device's axis (``device`` and ``axis`` by number, as the
daisy chain numbers them).

Units: zaber-motion converts mm to microsteps only for a device it has
*identified* from Zaber's device database, which it fetches from Zaber's web
service (``api.zaber.io/device-db/v2/public/device/ID?fw=...``) or reads from
Zaber's downloadable SQLite file. So the driver asks the library to identify
the device and, when it can, takes the scales from it
(``convert_to_native_units`` for position, speed and acceleration); where the
database is out of reach (a lab PC offline: the library raises
DeviceDbFailedException) it converts with the manual's rules: position = mm /
microstep size, where microstep size = the stage's full step
(``full_step_um``, from its datasheet: 3.048 um for the X-LSM series) / ``get
resolution`` (microsteps per step, read from the device); speed = microsteps/s
x 1.6384. ``describe()["units_from"]`` says which.
"""
from __future__ import annotations

import contextlib
import time
from typing import Iterator

from lps_gui.errors import HardwareError
from lps_gui.hardware.capabilities import FeedHold, Jogging, Settings
from lps_gui.hardware.stage import AXES, Stage, StageEvent, StageSetting, StageStatus

VELOCITY_SCALE = 1.6384  # Zaber native speed = microsteps/s * 1.6384 (ASCII protocol manual, unit conversions)
ACCEL_SCALE = 1.6384 / 10000.0  # native accel = microsteps/s^2 * 1.6384 / 10000
X_LSM_FULL_STEP_UM = 3.048

# numbered settings (the Stage interface's numbers): name on the device, unit shown, kind of conversion
SETTINGS = {
    1: ("maxspeed", "mm/min", "speed"),
    2: ("accel", "mm/s^2", "accel"),
    3: ("limit.min", "mm", "position"),
    4: ("limit.max", "mm", "position"),
    5: ("resolution", "microsteps/step", "raw"),
}


class ZaberStage(Stage, Settings, Jogging, FeedHold):
    """One axis of one Zaber device on a serial port (``zaber:PORT``)."""

    def __init__(self, port: str, device: int = 1, axis_number: int = 1, full_step_um: float = X_LSM_FULL_STEP_UM,
                 baudrate: int = 115200, timeout_s: float = 5.0, poll_interval_s: float = 0.01) -> None:
        super().__init__()
        self.port = port
        self.device_address = int(device)
        self.axis_number = int(axis_number)
        self.full_step_um = float(full_step_um)
        self.baudrate = baudrate
        self.timeout_s = timeout_s
        self.poll_interval_s = poll_interval_s
        self.units_from = "manual"  # or "zaber-motion": who gave the scales (describe())
        self._set_scales(self.full_step_um / 64 / 1000.0)  # the default resolution until the device says its own
        self.serial_number: int | None = None
        self._conn = None
        self._axis = None
        self._held_target: int | None = None  # a stopped move's target (feed hold), re-issued by resume
        self._last_target: int | None = None
        self._dead: HardwareError | None = None

    # ------------------------------------------------------------------ errors
    @contextlib.contextmanager
    def _talk(self, what: str) -> Iterator[None]:
        """Every library call: its exceptions become one-line HardwareErrors; a lost port is remembered."""
        from zaber_motion import exceptions as zx

        if self._dead is not None:
            raise self._dead
        if self._conn is None:
            raise HardwareError(f"Zaber on {self.port}: not connected; connect the stage first")
        try:
            yield
        except (zx.ConnectionClosedException, zx.ConnectionFailedException) as exc:
            self._dead = HardwareError(f"Zaber on {self.port}: the port vanished during {what} ({_first_line(exc)}); "
                                       "reconnect the stage and resume")
            self.events.emit(StageEvent("disconnected", text=str(self._dead)))
            raise self._dead from None
        except zx.RequestTimeoutException:
            raise HardwareError(f"Zaber on {self.port}: no answer to {what} within {self.timeout_s:g} s; the port "
                                "vanished or the device is off: reconnect the stage and resume") from None
        except zx.CommandFailedException as exc:
            raise HardwareError(f"Zaber device {self.device_address} axis {self.axis_number} rejected {what}: "
                                f"{exc.details.response_data}") from None
        except zx.MotionLibException as exc:
            raise HardwareError(f"Zaber on {self.port}: {what} failed ({_first_line(exc)}); check the cable and the "
                                f"device number") from None

    # ------------------------------------------------------------------ connection
    def connect(self) -> None:
        from zaber_motion import exceptions as zx
        from zaber_motion.ascii import Connection

        try:
            self._conn = Connection.open_serial_port(self.port, baud_rate=self.baudrate)
        except zx.MotionLibException as exc:
            raise HardwareError(f"Zaber: cannot open port {self.port!r} ({_first_line(exc)}); check the cable and "
                                "the port name") from None
        self._dead = None
        self._conn.default_request_timeout = int(self.timeout_s * 1000)
        device = self._conn.get_device(self.device_address)
        try:
            with self._talk("reading the serial number"):
                self.serial_number = int(device.settings.get("system.serial"))
        except HardwareError:
            found = self._scan()
            self.disconnect()
            raise HardwareError(f"Zaber on {self.port}: no device {self.device_address} (found {found}); "
                                "give the device number of the stage") from None
        self._axis = device.get_axis(self.axis_number)
        try:
            with self._talk("reading the device"):
                resolution = int(self._axis.settings.get("resolution"))
                self._set_scales(self.full_step_um / resolution / 1000.0)
                self._library_scales(device)
            self._read_travel()
        except BaseException:
            self.disconnect()  # a half-read device is not connected
            raise
        self.events.emit(StageEvent("connected", text=f"Zaber device {self.device_address} on {self.port}"))

    def _set_scales(self, microstep_mm: float, speed_per_mm_s: float | None = None,
                    accel_per_mm_s2: float | None = None) -> None:
        """mm per microstep and the native speed / acceleration per mm/s, mm/s^2 (the manual's rules by default)."""
        self.microstep_mm = microstep_mm
        self._speed_per_mm_s = speed_per_mm_s if speed_per_mm_s is not None else VELOCITY_SCALE / microstep_mm
        self._accel_per_mm_s2 = accel_per_mm_s2 if accel_per_mm_s2 is not None else ACCEL_SCALE / microstep_mm

    def _library_scales(self, device) -> None:
        """The library's own unit scales when it can identify the device; else the manual's stay (say why once)."""
        from zaber_motion import Units
        from zaber_motion import exceptions as zx

        try:
            device.identify()
            native = self._axis.settings.convert_to_native_units
            per_mm = native("pos", 1.0, Units.LENGTH_MILLIMETRES)
            self._set_scales(1.0 / per_mm, native("maxspeed", 1.0, Units.VELOCITY_MILLIMETRES_PER_SECOND),
                             native("accel", 1.0, Units.ACCELERATION_MILLIMETRES_PER_SECOND_SQUARED))
            self.units_from = "zaber-motion"
        except zx.DeviceDbFailedException:
            self.units_from = "manual"
            self.events.emit(StageEvent("message", text=(
                "Zaber: the device database is out of reach (offline?); units from the manual's rules with a "
                f"{self.full_step_um:g} um full step")))

    def _read_travel(self) -> None:
        with self._talk("reading the travel limits"):
            lo, hi = (self._axis.settings.get(n) for n in ("limit.min", "limit.max"))
        self.travel_mm = (lo * self.microstep_mm, hi * self.microstep_mm)

    def _scan(self) -> list[int]:
        """Addresses of the devices that answer on the port (all answer an empty command to device 0)."""
        try:
            return [d.device_address for d in self._conn.detect_devices(identify_devices=False)]
        except Exception:  # nothing answers, or the port is gone: nothing found
            return []

    def disconnect(self) -> None:
        conn, self._conn, self._axis = self._conn, None, None
        if conn is not None:
            with contextlib.suppress(Exception):  # closing a vanished port may fail; it is gone either way
                conn.close()

    @property
    def connected(self) -> bool:
        return self._conn is not None and self._dead is None

    # ------------------------------------------------------------------ units
    def _native(self, mm: float) -> int:
        return round(mm / self.microstep_mm)

    def _speed(self, feed_mm_min: float) -> float:
        return feed_mm_min / 60.0 * self._speed_per_mm_s

    def _check_axis(self, axis: str | None) -> None:
        if (axis or self.axis) != self.axis:
            raise HardwareError(f"Zaber device {self.device_address}: only axis {self.axis} (axis number "
                                f"{self.axis_number}) is driven; {axis} is not")

    # ------------------------------------------------------------------ state
    def _reply(self, command: str):
        with self._talk(command or "a status request"):
            return self._conn.generic_command(command, device=self.device_address, axis=self.axis_number)

    def status(self) -> StageStatus:
        r = self._reply("")
        with self._talk("get pos"):
            pos = self._axis.get_position() * self.microstep_mm
        state = "Run" if r.status == "BUSY" else ("Hold" if self._held_target is not None else "Idle")
        mm = [0.0, 0.0, 0.0]
        mm[AXES.index(self.axis)] = pos
        return StageStatus(state=state, machine_mm=tuple(mm), work_mm=tuple(mm), pins=r.warning_flag,
                           time=time.monotonic())

    def home(self) -> None:
        self._held_target = None
        with self._talk("home"):
            self._axis.home(wait_until_idle=False)
        self.wait_idle(timeout_s=max(self.timeout_s, 120.0))
        self._read_travel()  # homing resets the position to 0 and the limits with it

    def unlock(self) -> None:
        """Clear the device's warning flags (Zaber has no alarm lock; a fault shows as a warning)."""
        self._reply("warnings clear")

    def soft_reset(self) -> None:
        """Stop at once and forget a held move (no device reboot: that would lose the home reference)."""
        self._held_target = None
        with self._talk("stop"):
            self._axis.stop(wait_until_idle=False)

    def feed_hold(self) -> None:
        """Zaber has no hold: stop, and remember the target so :meth:`resume` goes on to it."""
        if self._reply("").status == "BUSY" and self._last_target is not None:
            self._held_target = self._last_target
        with self._talk("stop"):
            self._axis.stop(wait_until_idle=False)

    def resume(self) -> None:
        target, self._held_target = self._held_target, None
        if target is not None:
            with self._talk("move abs"):
                self._axis.move_absolute(target, wait_until_idle=False)

    # ------------------------------------------------------------------ motion
    def move_to(self, position_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        self._check_axis(axis)
        target = self._native(position_mm)
        self._held_target = None
        with self._talk(f"move abs to {position_mm:g} mm"):
            self._axis.move_absolute(target, wait_until_idle=False, velocity=self._speed(feed_mm_min))
        self._last_target = target

    def jog(self, distance_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        self._check_axis(axis)
        with self._talk(f"move rel by {distance_mm:g} mm"):
            self._axis.move_relative(self._native(distance_mm), wait_until_idle=False,
                                     velocity=self._speed(feed_mm_min))
        self._last_target = None

    def jog_cancel(self) -> None:
        with self._talk("stop"):
            self._axis.stop(wait_until_idle=False)

    def stop(self) -> None:
        """Decelerate to a stop now (Zaber's ``stop``); a held target is forgotten."""
        self._held_target = None
        self.jog_cancel()

    def wait_idle(self, timeout_s: float = 60.0) -> StageStatus:
        """Poll the axis until IDLE (the device answers BUSY while it moves); a fault flag (F*) is an error."""
        deadline = time.monotonic() + timeout_s
        while True:
            st = self.status()
            if st.state == "Hold":
                raise HardwareError(f"Zaber device {self.device_address}: stopped in Hold; resume to reach the target")
            if st.pins.startswith("F"):
                raise HardwareError(f"Zaber device {self.device_address} axis {self.axis_number}: fault {st.pins}; "
                                    "clear it (unlock) after checking the stage")
            if st.idle:
                return st
            if time.monotonic() >= deadline:
                raise HardwareError(f"Zaber device {self.device_address}: still moving after {timeout_s:g} s")
            time.sleep(self.poll_interval_s)

    # ------------------------------------------------------------------ settings
    def read_settings(self) -> list[StageSetting]:
        out = []
        for number, (name, unit, kind) in SETTINGS.items():
            with self._talk(f"get {name}"):
                native = self._axis.settings.get(name)
            out.append(StageSetting(number, self._from_native(native, kind), name, unit))
        return out

    def write_setting(self, number: int, value: float) -> None:
        if number not in SETTINGS:
            raise HardwareError(f"Zaber: no setting {number}; the settings are {sorted(SETTINGS)}")
        name, _, kind = SETTINGS[number]
        with self._talk(f"set {name}"):
            self._axis.settings.set(name, round(self._to_native(value, kind)))

    settings_title = "Zaber settings"

    def setting_label(self, setting: StageSetting) -> str:
        """The device's own name of the setting (``get maxspeed``)."""
        return setting.name

    def travel_text(self, settings: list[StageSetting]) -> str:
        by_name = {st.name: st.value for st in settings}
        if "limit.min" not in by_name or "limit.max" not in by_name:
            return "travel: unknown"
        return f"travel: {by_name['limit.min']:g} .. {by_name['limit.max']:g} mm (limit.min, limit.max; the device refuses moves beyond)"

    def _from_native(self, v: float, kind: str) -> float:
        return {"speed": v / self._speed_per_mm_s * 60.0, "accel": v / self._accel_per_mm_s2,
                "position": v * self.microstep_mm, "raw": v}[kind]

    def _to_native(self, v: float, kind: str) -> float:
        return {"speed": self._speed(v), "accel": v * self._accel_per_mm_s2,
                "position": v / self.microstep_mm, "raw": v}[kind]

    def describe(self) -> dict:
        return {**super().describe(), "port": self.port, "device": self.device_address, "axis_number": self.axis_number,
                "serial_number": self.serial_number, "microstep_um": self.microstep_mm * 1000.0,
                "units_from": self.units_from}


def _first_line(exc: BaseException) -> str:
    return (str(exc).splitlines() or [type(exc).__name__])[0]
