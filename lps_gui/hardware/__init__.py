"""Stage drivers: the Stage interface and its capabilities, a simulated stage, GRBL 1.1, Marlin, manual and
command stages, their emulators, and the registry naming them all.

:func:`open_stage` turns the ``--stage`` spec of the CLI and GUI into a
connected :class:`~lps_gui.hardware.stage.Stage`; pyserial stays inside this
package.
"""
from __future__ import annotations

from lps_gui.hardware.stage import Stage


def open_stage(spec: str, **options) -> Stage:
    """Make and connect the stage named by ``spec`` (its kind from :data:`lps_gui.hardware.registry.KINDS`).

    ``"sim"`` -> :class:`SimulatedStage` (simulated time), ``"grbl:PORT"`` ->
    :class:`GrblStage` on that serial port, ``"emulator"`` -> a GRBL driver on a
    fresh emulator (stopped when the stage disconnects), ``"marlin:PORT"``,
    ``"manual"``, ``"command:'./move.sh {mm}'"``... ``options`` go to the
    driver's constructor (e.g. ``errors``, ``seed``, ``clock`` for "sim";
    ``baudrate``, ``timeout_s`` for serial ones).
    """
    from lps_gui.hardware.registry import kind_of

    return kind_of(spec).make((spec or "").strip(), **options)


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
