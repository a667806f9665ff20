"""The optional SDK packages of the camera families, imported only when their source is opened.

The core install stays small: ``pip install lps-calib[genicam]`` (harvesters
and the genicam wheel), ``[basler]`` (pypylon), ``[gphoto2]`` (python-gphoto2).
A missing one is a one-line error naming the extra to install. The imports
sit inside these functions on purpose: an SDK is loaded only by the source
that needs it (not to dodge an import cycle).
"""
from __future__ import annotations

from types import ModuleType

from lps_gui.errors import InputError


def _missing(package: str, extra: str, source: str) -> InputError:
    return InputError(f"camera {source}: the {package} package is not installed; pip install lps-calib[{extra}]")


def pylon_sdk(source: str) -> tuple[ModuleType, ModuleType]:
    """pypylon's ``pylon`` and ``genicam`` modules."""
    try:
        from pypylon import genicam, pylon
    except ImportError:
        raise _missing("pypylon", "basler", source) from None
    return pylon, genicam


def harvesters_sdk(source: str) -> tuple[ModuleType, ModuleType]:
    """``harvesters.core`` and ``genicam.genapi``."""
    try:
        import harvesters.core
        from genicam import genapi
    except ImportError:
        raise _missing("harvesters", "genicam", source) from None
    return harvesters.core, genapi


def genicam_package(source: str) -> ModuleType:
    """The genicam wheel's package (it bundles the viky.cti demo producer)."""
    try:
        import genicam
    except ImportError:
        raise _missing("genicam", "genicam", source) from None
    return genicam


def gphoto2_sdk(source: str) -> ModuleType:
    try:
        import gphoto2
    except ImportError:
        raise _missing("gphoto2", "gphoto2", source) from None
    return gphoto2


def first_line(exc: BaseException) -> str:
    """An SDK exception's first line (SDK messages run over several lines with file and line numbers)."""
    return (str(exc).strip().splitlines() or [type(exc).__name__])[0][:160]
