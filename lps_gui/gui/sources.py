"""Where stages and cameras come from: the choices the panels offer, and how each opens.

The simulated rig (a simulated stage with a simulated camera that renders
the board at the stage's true pose) is the default, so the application is
usable with no hardware at all. It runs on real time so motion is visible.
Every opener runs on a worker thread (opening a port or building the
renderer takes a moment) and may raise :class:`~lps_gui.gui.services.Unavailable`
while a back end has not landed yet.
"""
from __future__ import annotations

import inspect
from typing import Any

from lps_gui.camera.base import Camera
from lps_gui.core.clock import RealClock
from lps_gui.errors import InputError
from lps_gui.gui.services import lookup
from lps_gui.hardware.stage import Stage

SIM = "sim"
EMULATOR = "emulator"
SIM_PRESET = "small"
BAUD_RATES = (115200, 250000, 57600, 38400, 19200, 9600)
CAMERA_FOLLOWS_STAGE = "sim"  # the simulated camera riding the simulated stage


def stage_choices() -> list[tuple[str, str]]:
    """(label, source) pairs: simulated, emulator, then every serial port found."""
    out = [("Simulated stage", SIM), ("GRBL emulator (pty)", EMULATOR)]
    try:
        ports = lookup("lps_gui.hardware", "list_serial_ports")()
    except Exception:  # no port listing yet (or no serial support): offer the two simulations
        ports = []
    for p in ports:
        name = getattr(p, "device", None) or (p[0] if isinstance(p, (tuple, list)) else str(p))
        desc = getattr(p, "description", "") or ""
        out.append((f"{name} {desc}".strip(), f"grbl:{name}"))
    return out


def _with_clock(fn: Any, *args: Any, **kwargs: Any) -> Any:
    """Call ``fn`` with a real-time clock when it accepts one (motion visible on screen)."""
    try:
        params = inspect.signature(fn).parameters
    except (TypeError, ValueError):
        params = {}
    if "clock" in params:
        kwargs["clock"] = RealClock()
    return fn(*args, **kwargs)


def open_stage_source(source: str, baud: int = 115200) -> tuple[Stage, Camera | None]:
    """Build (not yet connect) the stage for ``source``; the simulated rig also yields its camera."""
    if source == SIM:
        preset = lookup("lps_gui.core.simulate", "preset")
        make_rig = lookup("lps_gui.capture.simulated_rig", "make_simulated_rig")
        stage, camera = _with_clock(make_rig, preset(SIM_PRESET))
        return stage, camera
    open_stage = lookup("lps_gui.hardware", "open_stage")
    if source == EMULATOR:
        return open_stage(EMULATOR), None
    if source.startswith("grbl:"):
        if baud != 115200 and "baud" in inspect.signature(open_stage).parameters:
            return open_stage(source, baud=baud), None
        return open_stage(source), None
    raise InputError(f"stage source {source!r} is unknown; choose one from the list")


def camera_choices(sim_available: bool) -> list[tuple[str, str]]:
    """(label, spec) pairs for the camera panel."""
    out = []
    if sim_available:
        out.append(("Simulated camera (follows the simulated stage)", CAMERA_FOLLOWS_STAGE))
    out += [("Camera device 0", "0"), ("Camera device 1", "1")]
    return out


def open_camera_source(spec: str) -> Camera:
    """Open a non-simulated camera (device index, file or URL) through the camera layer."""
    return lookup("lps_gui.camera", "open_camera")(spec)
