"""Exposure, gain, focus and white balance of a camera, where the device has them (OpenCV properties or an SDK).

A measurement needs them fixed: an auto exposure or autofocus that changes
between frames moves the detected corners (issue 13, item 14). OpenCV exposes
them as ``CAP_PROP_*``; a device without one answers ``get`` with -1 (or 0 on
some back ends) and refuses ``set``, so a control is offered only when the
device reports a value for it. The GUI locks the controls during a capture.
SDK cameras (GenICam, pylon, gphoto2) answer through their
:meth:`~lps_gui.camera.base.Camera.control_surface` instead; the functions
below take either kind.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Protocol

from lps_gui.camera.base import Camera
from lps_gui.camera.control_surface import ControlSurface, Value


@dataclass(frozen=True)
class Control:
    """One adjustable property; ``auto`` is its automatic mode switch (None: there is none)."""

    name: str
    prop: int
    auto: int | None
    auto_on: float = 1.0  # the value of ``auto`` that enables the automatic mode
    auto_off: float = 0.0


@lru_cache(maxsize=1)
def all_controls() -> tuple[Control, ...]:
    """The controls OpenCV names (cv2 imported on first use: importing this module stays light)."""
    import cv2

    return (
        # V4L2 encodes auto exposure as 3 (aperture priority) / 1 (manual); others use 0.75 / 0.25 or 1 / 0
        Control("exposure", cv2.CAP_PROP_EXPOSURE, cv2.CAP_PROP_AUTO_EXPOSURE, auto_on=3.0, auto_off=1.0),
        Control("gain", cv2.CAP_PROP_GAIN, None),
        Control("focus", cv2.CAP_PROP_FOCUS, cv2.CAP_PROP_AUTOFOCUS),
        Control("white balance", cv2.CAP_PROP_WB_TEMPERATURE, cv2.CAP_PROP_AUTO_WB),
    )


class PropertyDevice(Protocol):
    def get(self, prop: int) -> float: ...
    def set(self, prop: int, value: float) -> bool: ...


def device_of(camera: Camera) -> PropertyDevice | None:
    """The ``cv2.VideoCapture`` (or alike) under a camera, if it has one (OpenCVCamera on a device, while open)."""
    return camera.property_device()


def surface_of(camera: Camera) -> ControlSurface | None:
    """The SDK control surface of a camera, when it has one (open GenICam, pylon, gphoto2 cameras)."""
    return camera.control_surface()


def available(camera: Camera) -> dict[str, float]:
    """Numeric controls the device reports a value for: name -> current value (empty for simulated or file cameras)."""
    surface = surface_of(camera)
    if surface is not None:
        return {n: v for n, v in surface.values().items() if isinstance(v, float)}
    dev = device_of(camera)
    if dev is None:  # simulated cameras, files and streams have no controls
        return {}
    out = {}
    for c in all_controls():
        v = float(dev.get(c.prop))
        if v != -1.0:
            out[c.name] = v
    return out


def auto_modes(camera: Camera) -> dict[str, bool]:
    """name -> automatic mode on, for the controls that have one and report it."""
    surface = surface_of(camera)
    if surface is not None:
        return surface.autos()
    dev = device_of(camera)
    out: dict[str, bool] = {}
    if dev is None:
        return out
    for c in all_controls():
        if c.auto is not None:
            v = float(dev.get(c.auto))
            if v != -1.0:
                out[c.name] = abs(v - c.auto_on) < abs(v - c.auto_off)
    return out


def set_control(camera: Camera, name: str, value: Value) -> bool:
    """Switch the control to manual and set it; False when the device refuses (strings: SDK enumerations)."""
    surface = surface_of(camera)
    if surface is not None:
        return surface.set(name, value)
    dev = device_of(camera)
    c = next((c for c in all_controls() if c.name == name), None)
    if dev is None or c is None:
        return False
    if c.auto is not None:
        dev.set(c.auto, c.auto_off)
    return bool(dev.set(c.prop, float(value)))


def set_auto(camera: Camera, name: str, on: bool) -> bool:
    surface = surface_of(camera)
    if surface is not None:
        return surface.set_auto(name, on)
    dev = device_of(camera)
    c = next((c for c in all_controls() if c.name == name), None)
    if dev is None or c is None or c.auto is None:
        return False
    return bool(dev.set(c.auto, c.auto_on if on else c.auto_off))


def choice_controls(camera: Any) -> dict[str, tuple[str, tuple[str, ...]]]:
    """Enumerated SDK controls (pixel format, trigger, ISO...): name -> (current value, allowed values)."""
    surface = surface_of(camera)
    if surface is None:
        return {}
    return {n: (v, surface.choices(n) or (v,)) for n, v in surface.values().items() if isinstance(v, str)}


def lock(camera: Any) -> dict[str, Value]:
    """Every automatic mode off; the values now in force, for session.json (empty: nothing to lock)."""
    surface = surface_of(camera)
    if surface is not None:
        return surface.lock()
    for name, on in auto_modes(camera).items():
        if on:
            set_auto(camera, name, False)
    return dict(available(camera))


def apply(camera: Any, recorded: dict[str, Value]) -> list[str]:
    """Put recorded values back (a resumed capture); the names the device would not take."""
    surface = surface_of(camera)
    if surface is not None:
        return surface.apply(recorded)
    now = lock(camera)
    return [n for n, v in recorded.items() if n in now and now[n] != v and not set_control(camera, n, float(v))]
