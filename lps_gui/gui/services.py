"""Late, guarded access to the layers below the GUI.

Several back-end modules (simulated rig, capture engine, estimator, figures)
land independently; the GUI looks them up when an action needs them, so a
missing piece shows a clear "not available yet" state instead of a crash at
start-up. Nothing here pretends to work: an absent module raises
:class:`Unavailable` with one line naming it.
"""
from __future__ import annotations

import importlib
from typing import Any

from lps_gui.errors import LpsError


class Unavailable(LpsError):
    """A back-end module this action needs is not installed in this build."""


def lookup(module: str, attr: str) -> Any:
    """``module.attr``, or raise :class:`Unavailable` naming what is missing."""
    try:
        mod = importlib.import_module(module)
    except ModuleNotFoundError as exc:
        if exc.name and module.startswith(exc.name) or (exc.name or "").startswith("lps_gui"):
            raise Unavailable(f"{module} is not available yet in this build; update lps-calib") from exc
        raise
    try:
        return getattr(mod, attr)
    except AttributeError as exc:
        raise Unavailable(f"{module}.{attr} is not available yet in this build; update lps-calib") from exc


def available(module: str, attr: str) -> bool:
    """Whether :func:`lookup` would succeed (used to grey out actions)."""
    try:
        lookup(module, attr)
    except Unavailable:
        return False
    return True


# Modules the long jobs import lazily. Importing a compiled extension holds the
# GIL for tens of milliseconds; done in a worker thread mid-job it would freeze
# the window, so the GUI imports them once at start-up instead.
BACKEND_MODULES = (
    "lps_gui.pipeline.estimate", "lps_gui.core.estimate", "lps_gui.core.iso230", "lps_gui.io.results_file",
    "lps_gui.pipeline.intrinsics", "lps_gui.pipeline.detect", "lps_gui.camera.detection",
    "lps_gui.capture.engine", "lps_gui.capture.sim_session", "lps_gui.report.summary",
    "scipy.signal", "scipy.optimize", "scipy.stats", "scipy.interpolate", "scipy.ndimage", "scipy.sparse.linalg",
    "cv2",
)


def preload_backends() -> list[str]:
    """Import the back-end modules that exist; returns the ones missing (logged, not fatal)."""
    missing = []
    for name in BACKEND_MODULES:
        try:
            importlib.import_module(name)
        except ImportError:
            missing.append(name)
    return missing
