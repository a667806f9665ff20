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
from lps_gui.hardware.stage import Stage

SIM = "sim"
EMULATOR = "emulator"  # the registry's GRBL emulator kind, which serves the simulated rig here
SIM_PRESET = "small"
BAUD_RATES = (115200, 250000, 57600, 38400, 19200, 9600)
CAMERA_FOLLOWS_STAGE = "sim"  # the simulated camera riding the simulated stage
RIG_SOURCES = (SIM, EMULATOR)  # stage sources that come with the simulated camera (the emulator serves the rig)


def stage_choices() -> list[tuple[str, str]]:
    """(label, source) pairs from the stage registry: the bare kinds, then every serial kind on every port found."""
    from lps_gui.hardware import list_serial_ports, serial_ports_by_id
    from lps_gui.hardware.announce import announced
    from lps_gui.hardware.registry import stage_choices as registry_choices

    try:
        ports = list_serial_ports()
    except Exception:  # no port listing yet (or no serial support): offer the bare kinds
        ports = []
    return registry_choices(ports, serial_ports_by_id(), announced())


def source_from_text(text: str) -> str | None:
    """A source typed into the editable box: any registered spec, or a bare port (/dev/pts/5, COM3)."""
    from lps_gui.hardware.registry import source_from_text as registry_source

    return registry_source(text)


def simulated_rig(clock: Clock | None = None) -> tuple[Stage, Camera]:
    """The simulated stage and the camera riding it, on ``clock`` (real time by default)."""
    from lps_gui.core.truth.simulate import preset
    from lps_gui.sim.rig import make_simulated_rig

    return make_simulated_rig(preset(SIM_PRESET), clock=clock or RealClock())


def open_stage_source(source: str, baud: int = 115200, clock: Clock | None = None) -> tuple[Stage, Camera | None]:
    """Build the stage for ``source``, not yet connected (the stage controller connects it once); the simulated rig
    also yields its camera."""
    if source == SIM:
        return simulated_rig(clock)
    from lps_gui.hardware.registry import kind_of

    if source == EMULATOR:  # the GRBL emulator serves the simulated rig's stage: the simulated camera rides it
        from lps_gui.sim.emulated import emulated_rig_stage

        rig_stage, camera = simulated_rig(clock)
        return emulated_rig_stage(rig_stage), camera
    kind = kind_of(source)
    options = {"baudrate": baud} if kind.serial and baud != 115200 else {}
    return kind.build(source, **options), None


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
