"""A GRBL 1.1 controller on a pseudo-terminal: :class:`GrblFirmware` served by the line emulator.

The serving loop, simulated time (``time_scale``, ``stepped``), the link's
latency and its faults (a vanished port, slow replies, garbage) are
:class:`~lps_gui.hardware.line_emulator.LineEmulator`'s; ``lps emulate-grbl``
defaults to 1x, GRBL's own timing. What is GRBL's: its firmware (real-time
bytes ``?`` ``!`` ``~`` 0x18, banners, the 128-byte RX buffer), its fault
switches (:class:`Faults`: an alarm in the middle of a move, error replies,
failed homing) and ``boot_race=True``, a board that boots as the port opens
(an Arduino's DTR reset): the host's first reset byte arrives during GRBL's
init, so the boot banner comes first and the reset's banner after it (main.c
enables the serial interrupt before ``report_init_message()``). Bytes are read
at wire speed: GRBL's main loop takes each byte out of the 128-byte RX buffer
as it arrives, so only bytes that come while a line executes fill it.
"""
from __future__ import annotations

from lps_gui.hardware.grbl.firmware import BANNER, Faults, GrblFirmware
from lps_gui.hardware.line_emulator import LineEmulator
from lps_gui.hardware.pty_device import emulated_stage
from lps_gui.hardware.sim_stage import SimulatedStage

__all__ = ["BANNER", "Faults", "GrblEmulator", "emulated_grbl_stage"]


class GrblEmulator(LineEmulator):
    """GRBL 1.1 on a pty. ``start()`` returns the device path a serial client opens.

    Use as a context manager in tests: ``with GrblEmulator(...) as emu: GrblStage(emu.path)``.
    ``firmware`` holds GRBL's state; ``stage`` is the simulated stage that moves.
    ``homing_init_lock=True`` is stock GRBL 1.1h (config.h HOMING_INIT_LOCK): with
    ``$22=1`` it powers up in Alarm. The default (off, ``[OPT:VL,...]``) keeps the
    in-process rigs of tests and demos unlocked; ``lps emulate-grbl`` is stock.
    """

    firmware: GrblFirmware

    def __init__(self, stage: SimulatedStage | None = None, faults: Faults | None = None, time_scale: float = 1.0,
                 homing_init_lock: bool = False, stepped: bool = False, line_latency_s: float = 0.0,
                 boot_race: bool = False) -> None:
        super().__init__(stage, faults or Faults(), time_scale, stepped, line_latency_s, "grbl-emulator")
        self.boot_race = boot_race
        self.firmware = GrblFirmware(self.stage, self.faults, send=self._send, on_drop=self._drop_now,
                                     homing_init_lock=homing_init_lock)

    @property
    def rx_overflow_bytes(self) -> int:
        """Bytes GRBL dropped because the host overran its RX buffer (0 for a correct host)."""
        return self.firmware.rx_overflow_bytes

    def _opened(self) -> None:
        """Power-up: the homing lock (if built with it), then the welcome (twice with the boot race)."""
        self.firmware.power_up(boot_race=self.boot_race)
        self._flush_out()


def emulated_grbl_stage(time_scale: float = 1.0, faults: Faults | None = None, simulated: SimulatedStage | None = None,
                        **stage_options):
    """A :class:`GrblStage` connected to a fresh emulator (``open_stage("emulator")``).

    The emulator serves ``simulated`` (e.g. the simulated rig's stage, whose
    true pose a simulated camera renders), else a new :class:`SimulatedStage`
    built from ``stage_options`` (``clock`` is replaced: the emulator owns
    simulated time). The returned stage names the simulated stage it serves
    (``Stage.simulated``: a simulated rig's hook seeds its draws through the
    driver) and stops the emulator when it disconnects.
    """
    from lps_gui.hardware.grbl.driver import GrblStage

    return emulated_stage(GrblStage, GrblEmulator, simulated, stage_options, faults=faults, time_scale=time_scale)
