"""Camera sources of the SDK families: ``genicam:SERIAL``, ``pylon:SERIAL``, ``gphoto2:[PORT]``, ``v4l2:/dev/videoN``.

Each family's adapter module is imported only when its source is chosen and
imports its SDK only when it opens, so the core install needs none of them.
:func:`list_devices` asks every installed SDK what it finds (the GUI's source
list); a family whose SDK is missing or fails to enumerate lists nothing.
"""
from __future__ import annotations

import importlib
import logging
from typing import Any

from lps_gui.camera.base import Camera
from lps_gui.camera.extras import installed
from lps_gui.errors import InputError, LpsError

log = logging.getLogger(__name__)

# prefix -> (adapter module, class, SDK module the family needs, device lister)
FAMILIES = {
    "genicam": ("lps_gui.camera.genicam_camera", "GenICamCamera", "harvesters", "list_genicam_devices"),
    "pylon": ("lps_gui.camera.pylon_camera", "PylonCamera", "pypylon", "list_pylon_devices"),
    "gphoto2": ("lps_gui.camera.gphoto2_camera", "GPhoto2Camera", "gphoto2", "list_gphoto2_devices"),
    "v4l2": ("lps_gui.camera.v4l2_camera", "V4L2Camera", "cv2", "list_v4l2_devices"),
}
SDK_SPECS = "genicam:SERIAL [--cti PATH] | pylon:SERIAL | gphoto2:[PORT] | v4l2:/dev/videoN"


def family_of(spec: str) -> str | None:
    """The SDK family a source string names ("pylon:0815-0000" -> "pylon"), None for the other sources."""
    head, sep, _ = spec.partition(":")
    return head if sep and head in FAMILIES else None


def sdk_camera(spec: str, cti: str | None = None, **options: Any) -> Camera:
    """The (unopened) camera of an SDK source; ``cti`` is the GenTL producer of ``genicam:``."""
    family = family_of(spec)
    if family is None:
        raise InputError(f"camera {spec!r}: not an SDK source; use {SDK_SPECS}")
    address = spec.partition(":")[2].strip()
    module, cls, _, _ = FAMILIES[family]
    factory = getattr(importlib.import_module(module), cls)
    if family == "genicam":
        return factory(address, cti=cti, **options)
    return factory(address, **options)


def list_devices(cti: str | None = None) -> list[tuple[str, str]]:
    """(label, source) of the devices every installed SDK finds now."""
    out: list[tuple[str, str]] = []
    for family, (module, _, sdk, lister) in FAMILIES.items():
        if not installed(sdk):
            continue
        fn = getattr(importlib.import_module(module), lister)
        try:
            out += fn(cti) if family == "genicam" else fn()
        except (LpsError, Exception) as exc:  # an SDK that cannot enumerate (no runtime, no permission) lists nothing
            log.info("camera: %s devices not listed (%s)", family, exc)
    return out
