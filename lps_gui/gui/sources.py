"""Where stages and cameras come from: the choices the panels offer, and how each opens.

The simulated rig (a simulated stage with a simulated camera that renders
the board at the stage's true pose) is the default, so the application is
usable with no hardware at all. It runs on real time so motion is visible.
Every opener runs on a worker thread (opening a port or building the
renderer takes a moment).
"""
from __future__ import annotations

from lps_gui.camera.base import Camera
from lps_gui.core.clock import Clock, RealClock
from lps_gui.errors import InputError
from lps_gui.hardware.stage import Stage

SIM = "sim"
EMULATOR = "emulator"
SIM_PRESET = "small"
BAUD_RATES = (115200, 250000, 57600, 38400, 19200, 9600)
CAMERA_FOLLOWS_STAGE = "sim"  # the simulated camera riding the simulated stage
RIG_SOURCES = (SIM, EMULATOR)  # stage sources that come with the simulated camera (the emulator serves the rig)


def stage_choices() -> list[tuple[str, str]]:
    """(label, source) pairs: simulated, emulator, then every serial port found."""
    out = [("Simulated stage", SIM), ("GRBL emulator (pty)", EMULATOR)]
    from lps_gui.hardware import list_serial_ports

    try:
        ports = list_serial_ports()
    except Exception:  # no port listing yet (or no serial support): offer the two simulations
        ports = []
    for p in ports:
        name = getattr(p, "device", None) or (p[0] if isinstance(p, (tuple, list)) else str(p))
        desc = getattr(p, "description", "") or ""
        out.append((f"{name} {desc}".strip(), f"grbl:{name}"))
    out += by_id_choices()
    from lps_gui.hardware.announce import announced_ports

    listed = {src for _, src in out}
    out += [(f"{p} (GRBL emulator)", f"grbl:{p}") for p in announced_ports() if f"grbl:{p}" not in listed]
    return out


def by_id_choices() -> list[tuple[str, str]]:
    """The stable /dev/serial/by-id names of the serial adapters (they survive replugging)."""
    from lps_gui.hardware import serial_ports_by_id

    return [(f"{link} ({device.rsplit('/', 1)[-1]})", f"grbl:{link}") for link, device in serial_ports_by_id()]


def source_from_text(text: str) -> str | None:
    """A source typed into the editable box: sim, emulator, grbl:PORT, or a bare port (/dev/pts/5, COM3)."""
    text = text.strip()
    if text in (SIM, EMULATOR) or (text.startswith("grbl:") and len(text) > 5):
        return text
    if text.startswith(("/dev/", "COM", "socket://", "rfc2217://", "loop://")):
        return f"grbl:{text}"
    return None


def simulated_rig(clock: Clock | None = None) -> tuple[Stage, Camera]:
    """The simulated stage and the camera riding it, on ``clock`` (real time by default)."""
    from lps_gui.core.simulate import preset
    from lps_gui.sim.rig import make_simulated_rig

    return make_simulated_rig(preset(SIM_PRESET), clock=clock or RealClock())


def open_stage_source(source: str, baud: int = 115200, clock: Clock | None = None) -> tuple[Stage, Camera | None]:
    """Build the stage for ``source``; the simulated rig also yields its camera."""
    if source == SIM:
        return simulated_rig(clock)
    from lps_gui.hardware import open_stage

    if source == EMULATOR:  # the GRBL emulator serves the simulated rig's stage: the simulated camera rides it
        from lps_gui.sim.emulated import emulated_rig_stage

        rig_stage, camera = simulated_rig(clock)
        return emulated_rig_stage(rig_stage), camera
    if source.startswith("grbl:"):
        return (open_stage(source, baudrate=baud) if baud != 115200 else open_stage(source)), None
    raise InputError(f"stage source {source!r} is unknown; choose one from the list")


_sdk_devices: list[tuple[str, str]] | None = None


def sdk_devices(rescan: bool = False) -> list[tuple[str, str]]:
    """The devices every installed camera SDK finds (GenICam, pylon, gphoto2, V4L2), looked up once unless ``rescan``."""
    global _sdk_devices
    if _sdk_devices is None or rescan:
        from lps_gui.camera.sdk_sources import list_devices

        _sdk_devices = list_devices()
    return list(_sdk_devices)


def camera_choices(sim_available: bool, rescan: bool = False) -> list[tuple[str, str]]:
    """(label, spec) pairs for the camera panel: the simulated camera, device indices 0 and 1, the SDKs' devices."""
    out = []
    if sim_available:
        out.append(("Simulated camera", CAMERA_FOLLOWS_STAGE))
    out += [("Camera device 0", "0"), ("Camera device 1", "1")]
    return out + sdk_devices(rescan)


def open_camera_source(spec: str) -> Camera:
    """Open a non-simulated camera (device index, SDK source, file or URL) through the camera layer."""
    from lps_gui.camera import open_camera

    return open_camera(spec)
