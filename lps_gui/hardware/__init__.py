"""Stage drivers: the Stage interface, a simulated stage, GRBL 1.1 over serial and its pty emulator.

:func:`open_stage` turns the ``--stage`` spec of the CLI and GUI into a
connected :class:`~lps_gui.hardware.stage.Stage`; pyserial stays inside this
package.
"""
from __future__ import annotations

from lps_gui.errors import InputError
from lps_gui.hardware.stage import Stage

STAGE_SPECS = "sim | emulator | grbl:PORT (e.g. grbl:/dev/ttyUSB0 or grbl:COM3)"


def open_stage(spec: str, **options) -> Stage:
    """Make and connect the stage named by ``spec``.

    ``"sim"`` -> :class:`SimulatedStage` (simulated time), ``"grbl:PORT"`` ->
    :class:`GrblStage` on that serial port, ``"emulator"`` -> a
    :class:`GrblEmulator` on a fresh pseudo-terminal with a :class:`GrblStage`
    connected to it (the emulator stops when the stage disconnects).
    ``options`` go to the stage's constructor (e.g. ``errors``, ``seed``,
    ``clock`` for "sim"; ``baudrate``, ``timeout_s`` for "grbl").
    """
    spec = (spec or "").strip()
    if spec == "sim":
        from lps_gui.hardware.sim_stage import SimulatedStage

        stage: Stage = SimulatedStage(**options)
    elif spec == "emulator":
        from lps_gui.hardware.grbl.emulator import emulated_grbl_stage

        return emulated_grbl_stage(**options)
    elif spec.startswith("grbl:") and len(spec) > 5:
        from lps_gui.hardware.grbl.driver import GrblStage

        stage = GrblStage(spec[5:], **options)
    else:
        raise InputError(f"stage {spec!r}: not understood; use {STAGE_SPECS}")
    stage.connect()
    return stage


def list_serial_ports() -> list[str]:
    """Device names of the serial ports present (``/dev/ttyUSB0``, ``COM3``...), sorted."""
    from serial.tools import list_ports

    return sorted(p.device for p in list_ports.comports())


def serial_ports_by_id(folder: str = "/dev/serial/by-id") -> list[tuple[str, str]]:
    """(stable name, device) of the USB serial adapters udev lists by id, sorted.

    ``/dev/serial/by-id/usb-1a86_USB_Serial-if00-port0`` survives replugging and
    reboots where ``/dev/ttyUSB0`` may become ``ttyUSB1``; empty where it does not exist.
    """
    import os

    try:
        names = sorted(os.listdir(folder))
    except OSError:
        return []
    return [(os.path.join(folder, n), os.path.realpath(os.path.join(folder, n))) for n in names]
