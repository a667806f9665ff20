"""A Thorlabs KDC101 K-Cube (DC servo, one channel) with an MTS/Z8-class stage, on a pseudo-terminal.

Written from Thorlabs' APT Communications Protocol manual. Every message
starts with a 6-byte little-endian header: the message id (word), then
either two parameter bytes (a header-only message) or the length of the data
packet that follows (word), then the destination (with bit 0x80 set when data
follows) and the source. The host is 0x01; a K-Cube answers as the generic
USB unit 0x50. The messages served:

- HW_REQ_INFO 0x0005 -> HW_GET_INFO 0x0006 (84 bytes: serial, model, type, firmware, notes, hardware version,
  mod state, channel count); HW_NO_FLASH_PROGRAMMING 0x0018, HW_START/STOP_UPDATEMSGS 0x0011/0x0012,
  HW_DISCONNECT 0x0002, MOD_IDENTIFY 0x0223 and MOT_ACK_DCSTATUSUPDATE 0x0492 need no answer;
- MOD_SET_CHANENABLESTATE 0x0210 (param2 1 enables, 2 disables), MOD_REQ 0x0211 -> MOD_GET 0x0212;
  a disabled channel ignores motion commands, as the motor is not driven;
- MOT_MOVE_HOME 0x0443 -> MOT_MOVE_HOMED 0x0444 when done; MOT_MOVE_ABSOLUTE 0x0453 and MOT_MOVE_RELATIVE
  0x0448 (6-byte data: channel, counts) -> MOT_MOVE_COMPLETED 0x0464; MOT_MOVE_STOP 0x0465 -> MOT_MOVE_STOPPED
  0x0466; both carry the 14-byte DC status (channel, position, velocity, reserved, status bits);
- MOT_REQ_POSCOUNTER 0x0411 -> 0x0412; MOT_REQ_DCSTATUSUPDATE 0x0490 -> MOT_GET_DCSTATUSUPDATE 0x0491;
  MOT_REQ_STATUSBITS 0x0429 -> 0x042A; MOT_REQ/SET VELPARAMS 0x0414/0x0413 (-> 0x0415), GENMOVEPARAMS
  0x043B (-> 0x043C), JOGPARAMS 0x0417 (-> 0x0418), HOMEPARAMS 0x0441 (-> 0x0442).

Homing (MOT_MOVE_HOME) drives to the home switch and zeroes the position counter there; until then count 0 is
the simulated stage's 0 mm. Units: positions in encoder counts (34304 per mm for the Z8 actuators and MTS stages); velocity and
acceleration in the manual's DC-servo units, counts x T x 65536 per second and counts x T^2 x 65536 per
second squared with T = 2048 / 6e6 s. Unknown messages are ignored, as the controller does.
"""
from __future__ import annotations

import struct
from typing import Any

from lps_gui.hardware.pty_device import PtyServer, emulated_stage
from lps_gui.hardware.sim_stage import SimulatedStage
from lps_gui.hardware.stage import AXES

HOST, USB = 0x01, 0x50
Z8_COUNTS_PER_MM = 34304.0
T_S = 2048 / 6e6  # the KDC101's sampling interval in the velocity and acceleration units
VEL_SCALE = T_S * 65536  # APT velocity = counts/s * VEL_SCALE
ACC_SCALE = T_S * T_S * 65536  # APT acceleration = counts/s^2 * ACC_SCALE

# status bits of a DC servo channel
FWD_LIMIT, REV_LIMIT, MOVING_FWD, MOVING_REV, MOTOR_CONNECTED = 0x1, 0x2, 0x10, 0x20, 0x100
HOMING, HOMED, SETTLED, ENABLED = 0x200, 0x400, 0x2000, 0x80000000


def header(msg_id: int, dest: int, source: int, param1: int = 0, param2: int = 0, data: bytes = b"") -> bytes:
    """One APT message: the 6-byte header, then the data packet when there is one."""
    if data:
        return struct.pack("<HHBB", msg_id, len(data), dest | 0x80, source) + data
    return struct.pack("<HBBBB", msg_id, param1, param2, dest, source)


class AptKdc101:
    """The controller's side of APT: messages in, messages out, the carriage on ``stage``."""

    def __init__(self, stage: SimulatedStage, serial_number: int = 27000036, counts_per_mm: float = Z8_COUNTS_PER_MM) -> None:
        self.stage = stage
        self.serial_number = serial_number
        self.counts_per_mm = counts_per_mm
        self.axis = AXES.index(stage.axis)
        self.enabled = False
        self.homed = False
        self.homing = False
        self.moving = False  # a move whose MOVE_COMPLETED is still due
        self.stopping = False
        self.updates = False
        self.origin_mm = 0.0  # where count 0 is on the simulated stage: the home position once homed
        self.vel = (0, round(self.counts_per_mm * 1.5 * ACC_SCALE), round(self.counts_per_mm * 2.0 * VEL_SCALE))
        self.backlash = round(0.02 * self.counts_per_mm)
        self.home_params = (2, 1, round(self.counts_per_mm * 2.0 * VEL_SCALE), round(0.1 * self.counts_per_mm))
        self.received = 0  # commands received (the drop-after fault counts them)
        self.log: list[tuple[bytes, bytes]] = []  # (message received or b"" when spontaneous, bytes answered)
        self._buf = b""

    # ------------------------------------------------------------------ state
    def position(self) -> int:
        return round((self.stage.status().work_mm[self.axis] - self.origin_mm) * self.counts_per_mm)

    def busy(self) -> bool:
        return self.stage.status().state != "Idle"

    def status_bits(self) -> int:
        bits = MOTOR_CONNECTED | (ENABLED if self.enabled else 0) | (HOMED if self.homed else 0) | (HOMING if self.homing else 0)
        if self.busy():
            target = self.stage.planned_mm(self.axis)
            bits |= MOVING_FWD if target >= self.stage.status().work_mm[self.axis] else MOVING_REV
        else:
            bits |= SETTLED
        return bits

    def dc_status(self) -> bytes:
        return struct.pack("<HlHHL", 1, self.position(), 0, 0, self.status_bits())

    # ------------------------------------------------------------------ bytes
    def receive(self, data: bytes) -> bytes:
        self._buf += data
        out = b""
        while len(self._buf) >= 6:
            msg_id, p1, p2, dest, source = struct.unpack("<HBBBB", self._buf[:6])
            size = 6 + (p1 | p2 << 8 if dest & 0x80 else 0)
            if len(self._buf) < size:
                break
            msg, self._buf = self._buf[:size], self._buf[size:]
            self.received += 1
            answer = self.handle(msg_id, p1, p2, msg[6:])
            self.log.append((msg, answer))
            out += answer
        return out

    def poll(self) -> bytes:
        """A move, a homing or a stop that finished says so, once."""
        if self.busy() or not (self.moving or self.homing or self.stopping):
            return b""
        if self.homing:
            msg = header(0x0444, HOST, USB, param1=1)
            self.homing, self.homed = False, True
            self.origin_mm = self.stage.status().work_mm[self.axis]  # homing zeroes the position counter
        elif self.stopping:
            msg = header(0x0466, HOST, USB, data=self.dc_status())
        else:
            msg = header(0x0464, HOST, USB, data=self.dc_status())
        self.moving = self.stopping = False
        self.log.append((b"", msg))
        return msg

    # ------------------------------------------------------------------ messages
    def handle(self, msg_id: int, p1: int, p2: int, data: bytes) -> bytes:
        if msg_id == 0x0005:
            return header(0x0006, HOST, USB, data=self._info())
        if msg_id == 0x0210:
            self.enabled = p2 == 0x01
            return b""
        if msg_id == 0x0211:
            return header(0x0212, HOST, USB, param1=1, param2=0x01 if self.enabled else 0x02)
        if msg_id in (0x0011, 0x0012):
            self.updates = msg_id == 0x0011
            return b""
        if msg_id == 0x0411:
            return header(0x0412, HOST, USB, data=struct.pack("<Hl", 1, self.position()))
        if msg_id == 0x0490:
            return header(0x0491, HOST, USB, data=self.dc_status())
        if msg_id == 0x0429:
            return header(0x042A, HOST, USB, data=struct.pack("<HL", 1, self.status_bits()))
        if msg_id == 0x0413 and len(data) == 14:
            self.vel = struct.unpack("<lll", data[2:14])
            return b""
        if msg_id == 0x0414:
            return header(0x0415, HOST, USB, data=struct.pack("<Hlll", 1, *self.vel))
        if msg_id == 0x043B:
            return header(0x043C, HOST, USB, data=struct.pack("<Hl", 1, self.backlash))
        if msg_id == 0x0417:
            step = round(0.05 * self.counts_per_mm)
            return header(0x0418, HOST, USB, data=struct.pack("<HHlllLH", 1, 2, step, 0, self.vel[1], self.vel[2], 2))
        if msg_id == 0x0441:
            return header(0x0442, HOST, USB, data=struct.pack("<HHHll", 1, *self.home_params))
        if msg_id == 0x0443 and self.enabled:
            self._interrupt()
            self.stage.start_home()
            self.homing = True
            return b""
        if msg_id in (0x0453, 0x0448) and len(data) == 6 and self.enabled:
            counts = struct.unpack("<l", data[2:6])[0]
            target = counts + (self.position() if msg_id == 0x0448 else 0)
            self._move_to(target)
            return b""
        if msg_id == 0x0465:
            if self.busy():
                self.stage.jog_cancel()
                self.stopping, self.moving = True, False
            else:
                return header(0x0466, HOST, USB, data=self.dc_status())
            return b""
        return b""  # HW_NO_FLASH_PROGRAMMING, HW_DISCONNECT, MOD_IDENTIFY, ACKs and the unknown: no answer

    def _move_to(self, target_counts: int) -> None:
        lo, hi = self.stage.axis_travel_mm[self.axis]
        target_mm = min(max(self.origin_mm + target_counts / self.counts_per_mm, lo), hi)  # the end stops bound it
        speed_mm_s = max(self.vel[2], 1) / VEL_SCALE / self.counts_per_mm
        self._interrupt()
        start = self.stage.planned_mm(self.axis)
        self.stage.jog(target_mm - start, speed_mm_s * 60.0, self.stage.axis)
        self.moving = True

    def _interrupt(self) -> None:
        if self.busy():
            self.stage.jog_cancel()

    def _info(self) -> bytes:
        notes = b"APT DC Motor Controller".ljust(48, b"\0")
        return struct.pack("<L8sH4B48s12sHHH", self.serial_number, b"KDC101\0\0", 16, 3, 0, 1, 0, notes,
                           b"\0" * 12, 1, 0, 1)


class ThorlabsEmulator(PtyServer):
    """A KDC101 on a pty: ``with ThorlabsEmulator(stage) as emu: ThorlabsStage(emu.path)``."""

    def __init__(self, stage: SimulatedStage | None = None, faults: Any = None, time_scale: float = 1.0,
                 **device_options) -> None:
        stage = stage if stage is not None else SimulatedStage()
        self.device = AptKdc101(stage, **device_options)
        super().__init__(self.device, stage, time_scale=time_scale, name="thorlabs-emulator", faults=faults)


def emulated_thorlabs_stage(time_scale: float = 1.0, simulated: SimulatedStage | None = None, **stage_options):
    """A :class:`~lps_gui.hardware.thorlabs.ThorlabsStage` connected to a fresh KDC101 emulator serving
    ``simulated`` (else a new :class:`SimulatedStage` from ``stage_options``); disconnecting stops it."""
    from lps_gui.hardware.thorlabs import ThorlabsStage

    return emulated_stage(ThorlabsStage, ThorlabsEmulator, simulated, stage_options, time_scale=time_scale)
