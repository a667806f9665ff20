"""The optional SDK packages of the camera families, imported only when their source is chosen.

The core install stays small: ``pip install lps-calib[genicam]`` (harvesters
and the genicam wheel), ``[basler]`` (pypylon), ``[gphoto2]`` (python-gphoto2).
A missing one is a one-line error naming the extra to install.
"""
from __future__ import annotations

import importlib
import importlib.util
from types import ModuleType

from lps_gui.errors import InputError

EXTRAS = {"harvesters": "genicam", "genicam": "genicam", "pypylon": "basler", "gphoto2": "gphoto2"}


def import_sdk(module: str, source: str) -> ModuleType:
    """``module`` (e.g. "pypylon.pylon"), or InputError naming the extra for ``source`` (e.g. "pylon:123")."""
    try:
        return importlib.import_module(module)
    except ImportError:
        extra = EXTRAS[module.split(".")[0]]
        raise InputError(
            f"camera {source}: the {module.split('.')[0]} package is not installed; pip install lps-calib[{extra}]"
        ) from None


def installed(module: str) -> bool:
    """Whether ``module`` can be imported (the GUI lists only the families it finds)."""
    return importlib.util.find_spec(module) is not None


def first_line(exc: BaseException) -> str:
    """An SDK exception's first line (SDK messages run over several lines with file and line numbers)."""
    return (str(exc).strip().splitlines() or [type(exc).__name__])[0][:160]
