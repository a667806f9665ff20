"""Camera sources of the SDK families: ``genicam:SERIAL``, ``pylon:SERIAL``, ``gphoto2:[PORT]``, ``v4l2:/dev/videoN``.

Each family's adapter module is imported only when its source is chosen and
imports its SDK only when it opens, so the core install needs none of them.
:func:`list_devices` asks every installed SDK what it finds (the GUI's source
list); a family whose SDK is missing or fails to enumerate lists nothing.
"""
from __future__ import annotations

import logging
from types import ModuleType
from typing import Any

from lps_gui.camera.base import Camera
from lps_gui.errors import InputError

log = logging.getLogger(__name__)

# prefix -> (camera class, device lister) in the family's adapter module
FAMILIES = {
    "genicam": ("GenICamCamera", "list_genicam_devices"),
    "pylon": ("PylonCamera", "list_pylon_devices"),
    "gphoto2": ("GPhoto2Camera", "list_gphoto2_devices"),
    "v4l2": ("V4L2Camera", "list_v4l2_devices"),
}
SDK_SPECS = "genicam:SERIAL [--cti PATH] | pylon:SERIAL | gphoto2:[PORT] | v4l2:/dev/videoN"


def family_of(spec: str) -> str | None:
    """The SDK family a source string names ("pylon:0815-0000" -> "pylon"), None for the other sources."""
    head, sep, _ = spec.partition(":")
    return head if sep and head in FAMILIES else None


def adapter(family: str) -> ModuleType:
    """The family's adapter module, imported when that source is first used (it loads its SDK only on open)."""
    if family == "genicam":
        from lps_gui.camera import genicam_camera as module
    elif family == "pylon":
        from lps_gui.camera import pylon_camera as module
    elif family == "gphoto2":
        from lps_gui.camera import gphoto2_camera as module
    else:
        from lps_gui.camera import v4l2_camera as module
    return module


def sdk_camera(spec: str, cti: str | None = None, **options: Any) -> Camera:
    """The (unopened) camera of an SDK source; ``cti`` is the GenTL producer of ``genicam:``."""
    family = family_of(spec)
    if family is None:
        raise InputError(f"camera {spec!r}: not an SDK source; use {SDK_SPECS}")
    address = spec.partition(":")[2].strip()
    factory = getattr(adapter(family), FAMILIES[family][0])
    if family == "genicam":
        return factory(address, cti=cti, **options)
    return factory(address, **options)


def list_devices(cti: str | None = None) -> list[tuple[str, str]]:
    """(label, source) of the devices every installed SDK finds now."""
    out: list[tuple[str, str]] = []
    for family, (_, lister) in FAMILIES.items():
        fn = getattr(adapter(family), lister)
        try:
            out += fn(cti) if family == "genicam" else fn()
        except Exception as exc:  # an SDK not installed (InputError), or that cannot enumerate, lists nothing
            log.info("camera: %s devices not listed (%s)", family, exc)
    return out
