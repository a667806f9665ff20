"""A Thorlabs stage on a KDC101 K-Cube over the APT protocol, through the thorlabs-apt-device library.

The library (chosen over pylablib, which pulls in PyQt5, numba and pandas for
the same messages) frames the APT messages, polls MOT_REQ_DCSTATUSUPDATE
every 10 ms on its own thread and keeps the decoded status; it converts no
units. So this driver converts encoder counts with the stage's documented
scale (``counts_per_mm``: 34304 for MTS25/50-Z8 stages and Z8xx actuators)
and speeds with the APT manual's DC-servo rule (counts/s x T x 65536,
T = 2048 / 6e6 s). Commands are fire-and-forget in APT; completion is the
controller's MOT_MOVE_COMPLETED / MOT_MOVE_STOPPED / MOT_MOVE_HOMED message,
which the driver counts. A port that vanishes stops the library's reads: the
driver notices the failed read (or status that stopped coming) and raises one
line.
"""
from __future__ import annotations

import threading
import time

from lps_gui.errors import HardwareError
from lps_gui.hardware.capabilities import FeedHold, Jogging, Settings
from lps_gui.hardware.stage import AXES, Stage, StageEvent, StageSetting, StageStatus

HOST, USB = 0x01, 0x50
Z8_COUNTS_PER_MM = 34304.0
T_S = 2048 / 6e6
VEL_SCALE = T_S * 65536  # APT velocity = counts/s * VEL_SCALE
ACC_SCALE = T_S * T_S * 65536  # APT acceleration = counts/s^2 * ACC_SCALE
DONE_MESSAGES = ("mot_move_completed", "mot_move_stopped", "mot_move_homed")


def _kdc101_class():
    """The library's KDC101 with what the driver needs to see: HW_GET_INFO, completions, a failed port."""
    from thorlabs_apt_device.devices.kdc101 import KDC101

    class WatchedKDC101(KDC101):
        def __init__(self, *args, **kwargs) -> None:
            self.cond = threading.Condition()
            self.info: dict | None = None
            self.done = 0  # completion messages received
            self.updates = 0  # status messages received
            self.updates_at_done = 0  # ``updates`` when the last completion came: later ones show the stage at rest
            self.last_update = time.monotonic()
            self.failure: BaseException | None = None
            super().__init__(*args, **kwargs)

        def send(self, message: bytes) -> None:
            """Queue a message the library has a builder for but no method (HW_REQ_INFO...)."""
            self._loop.call_soon_threadsafe(self._write, message)

        def _process_message(self, m) -> None:
            super()._process_message(m)
            with self.cond:
                self.last_update = time.monotonic()
                if m.msg == "hw_get_info":
                    self.info = m._asdict()
                elif m.msg in DONE_MESSAGES:
                    self.done += 1
                    self.updates_at_done = self.updates
                if m.msg == "mot_get_dcstatusupdate":
                    self.updates += 1
                self.cond.notify_all()

        def _schedule_reads(self) -> None:
            try:
                super()._schedule_reads()
            except Exception as exc:  # SerialException/OSError: the port is gone; stop reading, say so
                self._fail(exc)

        def _write(self, command_bytes) -> None:
            try:
                super()._write(command_bytes)
            except Exception as exc:
                self._fail(exc)

        def _fail(self, exc: BaseException) -> None:
            with self.cond:
                if self.failure is None:
                    self.failure = exc
                self.cond.notify_all()

    return WatchedKDC101


class ThorlabsStage(Stage, Settings, Jogging, FeedHold):
    """One KDC101 channel driving a linear stage (``thorlabs:PORT``)."""

    def __init__(self, port: str, counts_per_mm: float = Z8_COUNTS_PER_MM, timeout_s: float = 5.0,
                 stale_s: float = 1.0, accel_mm_s2: float = 1.5) -> None:
        super().__init__()
        self.port = port
        self.counts_per_mm = float(counts_per_mm)
        self.timeout_s = timeout_s
        self.stale_s = stale_s  # status older than this (the library polls every 10 ms): the link is lost
        self.accel_mm_s2 = accel_mm_s2
        self.model = ""
        self.serial_number: int | None = None
        self._dev = None
        self._dead: HardwareError | None = None
        self._expect_done: int | None = None  # completions count to exceed before the stage is idle
        self._held_target: int | None = None
        self._last_target: int | None = None

    # ------------------------------------------------------------------ connection
    def connect(self) -> None:
        from thorlabs_apt_device import protocol as apt

        try:
            self._dev = _kdc101_class()(serial_port=self.port, home=False)
        except Exception as exc:  # SerialException, OSError, the library's RuntimeError
            raise HardwareError(f"Thorlabs: cannot open port {self.port!r} ({exc}); check the cable and the port "
                                "name") from None
        self._dead = None
        try:
            self._dev.send(apt.hw_no_flash_programming(dest=USB, source=HOST))
            self._dev.send(apt.hw_req_info(dest=USB, source=HOST))
            self._wait(lambda: self._dev.info is not None, self.timeout_s, "no answer to HW_REQ_INFO; is it a "
                       "KDC101 and powered?")
            self.model = self._dev.info["model_number"].split(b"\0")[0].decode("ascii", "replace")
            self.serial_number = int(self._dev.info["serial_number"])
            self._dev.set_enabled(True)
            self._wait(lambda: self._dev.status["channel_enabled"], self.timeout_s, "the channel did not enable")
        except BaseException:
            self.disconnect()  # the library's thread and port go with the failed connection
            raise
        self.events.emit(StageEvent("connected", text=f"Thorlabs {self.model} {self.serial_number} on {self.port}"))

    def disconnect(self) -> None:
        dev, self._dev = self._dev, None
        if dev is not None:
            try:
                dev.close()
                dev._thread.join(timeout=2.0)  # the library closes its port when its loop ends
            except Exception:  # a vanished port: nothing left to close
                pass

    @property
    def connected(self) -> bool:
        return self._dev is not None and self._dead is None and self._dev.failure is None

    # ------------------------------------------------------------------ link health
    def _check(self) -> None:
        if self._dead is not None:
            raise self._dead
        if self._dev is None:
            raise HardwareError(f"Thorlabs on {self.port}: not connected; connect the stage first")
        failure = self._dev.failure
        stale = time.monotonic() - self._dev.last_update > self.stale_s
        if failure is not None or stale:
            why = f"({str(failure).splitlines()[0] if str(failure) else type(failure).__name__})" if failure else \
                f"(no status for {self.stale_s:g} s)"
            self._dead = HardwareError(f"Thorlabs {self.model or 'controller'} on {self.port}: the port vanished {why}; "
                                       "reconnect the stage and resume")
            self.events.emit(StageEvent("disconnected", text=str(self._dead)))
            raise self._dead

    def _wait(self, predicate, timeout_s: float, what: str) -> None:
        deadline = time.monotonic() + timeout_s
        with self._dev.cond:
            while not predicate():
                if self._dev.failure is not None:
                    break
                left = deadline - time.monotonic()
                if left <= 0:
                    raise HardwareError(f"Thorlabs on {self.port}: {what} (waited {timeout_s:g} s)")
                self._dev.cond.wait(min(left, 0.05))
        self._check()

    # ------------------------------------------------------------------ state
    def status(self) -> StageStatus:
        self._check()
        s = self._dev.status
        moving = s["moving_forward"] or s["moving_reverse"] or s["homing"] or self._expect_done is not None
        state = "Home" if s["homing"] else "Run" if moving else ("Hold" if self._held_target is not None else "Idle")
        mm = [0.0, 0.0, 0.0]
        mm[AXES.index(self.axis)] = s["position"] / self.counts_per_mm
        return StageStatus(state=state, machine_mm=tuple(mm), work_mm=tuple(mm), time=time.monotonic())

    def _start(self, command, *args, **kwargs) -> None:
        """Send a motion command whose end the controller will announce."""
        self._check()
        self._expect_done = self._dev.done
        command(*args, **kwargs)

    def home(self) -> None:
        self._held_target = None
        self._start(self._dev.home)
        self.wait_idle(timeout_s=max(self.timeout_s, 120.0))

    def unlock(self) -> None:
        """Enable the channel (a KDC101 has no alarm lock; a disabled channel ignores moves)."""
        self._check()
        self._dev.set_enabled(True)

    def soft_reset(self) -> None:
        self._held_target = None
        self._check()
        self._dev.stop(immediate=True)

    def feed_hold(self) -> None:
        """APT has no hold: stop with the profile, and remember the target so :meth:`resume` goes on."""
        if self._expect_done is not None and self._last_target is not None:
            self._held_target = self._last_target
        self._check()
        self._dev.stop()

    def resume(self) -> None:
        target, self._held_target = self._held_target, None
        if target is not None:
            self._start(self._dev.move_absolute, target)

    # ------------------------------------------------------------------ motion
    def _check_axis(self, axis: str | None) -> None:
        if (axis or self.axis) != self.axis:
            raise HardwareError(f"Thorlabs {self.model}: one channel, axis {self.axis}; {axis} is not driven")

    def _set_speed(self, feed_mm_min: float) -> None:
        cps = feed_mm_min / 60.0 * self.counts_per_mm
        self._dev.set_velocity_params(round(self.accel_mm_s2 * self.counts_per_mm * ACC_SCALE), round(cps * VEL_SCALE))

    def move_to(self, position_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        self._check_axis(axis)
        self._held_target = None
        target = round(position_mm * self.counts_per_mm)
        self._check()
        self._set_speed(feed_mm_min)
        self._start(self._dev.move_absolute, target)
        self._last_target = target

    def jog(self, distance_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        self._check_axis(axis)
        self._check()
        self._set_speed(feed_mm_min)
        self._start(self._dev.move_relative, round(distance_mm * self.counts_per_mm))
        self._last_target = None

    def jog_cancel(self) -> None:
        self._check()
        self._dev.stop()

    def stop(self) -> None:
        """A profiled stop (MOT_MOVE_STOP); a held target is forgotten."""
        self._held_target = None
        self.jog_cancel()

    def wait_idle(self, timeout_s: float = 60.0) -> StageStatus:
        """Wait for the controller's completion message of the last command, then its settled status."""
        if self._held_target is not None and self._expect_done is not None:
            expect, dev = self._expect_done, self._dev
            self._wait(lambda: dev.done > expect and dev.updates > dev.updates_at_done, timeout_s,
                       "the stop did not complete")
            self._expect_done = None
        if self._held_target is not None:
            raise HardwareError(f"Thorlabs {self.model}: stopped in Hold; resume to reach the target")
        if self._expect_done is not None:
            expect, dev = self._expect_done, self._dev
            self._wait(lambda: dev.done > expect and dev.updates > dev.updates_at_done, timeout_s,
                       f"still moving after {timeout_s:g} s")
            self._expect_done = None
        return self.status()

    # ------------------------------------------------------------------ settings
    def read_settings(self) -> list[StageSetting]:
        self._check()
        v, g = self._dev.velparams, self._dev.genmoveparams
        return [
            StageSetting(1, v["max_velocity"] / VEL_SCALE / self.counts_per_mm * 60.0, "max velocity", "mm/min"),
            StageSetting(2, v["acceleration"] / ACC_SCALE / self.counts_per_mm, "acceleration", "mm/s^2"),
            StageSetting(3, g["backlash_distance"] / self.counts_per_mm, "backlash distance", "mm"),
            StageSetting(4, self.counts_per_mm, "encoder counts per mm", "counts/mm"),
        ]

    settings_title = "Thorlabs KDC101 parameters"

    def setting_label(self, setting: StageSetting) -> str:
        return setting.name

    def write_setting(self, number: int, value: float) -> None:
        self._check()
        if number == 3:
            self._dev.set_move_params(round(value * self.counts_per_mm))
        elif number == 2:
            self.accel_mm_s2 = float(value)
        else:
            raise HardwareError(f"Thorlabs: setting {number} is not writable here; write 2 (acceleration) or 3 "
                                "(backlash); speeds are given with each move")

    def describe(self) -> dict:
        return {**super().describe(), "port": self.port, "model": self.model, "serial_number": self.serial_number,
                "counts_per_mm": self.counts_per_mm}
