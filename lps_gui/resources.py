"""Find the application's data files (icon drawings and sizes) wherever it runs.

The files live in the repository's top-level ``resources/`` folder. Three ways
of running put them in three places, and callers should not care which:

- a PyInstaller bundle unpacks them into ``sys._MEIPASS/resources``
  (``packaging/lps-gui.spec`` collects them there);
- a wheel carries them inside the package as ``lps_gui/_resources``
  (in the source tree that name is a symlink to ``../resources``, which
  setuptools follows when it builds the wheel);
- a source checkout or editable install reads ``resources/`` next to the package.

Layer-neutral (no Qt, no I/O beyond ``stat``), so any layer may import it.
"""
from __future__ import annotations

import sys
from pathlib import Path

APP_ICON_SVG = "lps-gui.svg"
APP_ICON_SIZES_PX = (16, 24, 32, 48, 64, 128, 256)

_PACKAGE_DIR = Path(__file__).resolve().parent


def resource_dirs() -> list[Path]:
    """Folders searched for resources, most specific first.

    Returns
    -------
    list of Path
        The bundle's folder (only when frozen), the package's own copy, and
        the source checkout's ``resources/``; entries may not exist.
    """
    dirs = []
    bundle_dir = getattr(sys, "_MEIPASS", None)
    if bundle_dir:
        dirs.append(Path(bundle_dir) / "resources")
    dirs.append(_PACKAGE_DIR / "_resources")
    dirs.append(_PACKAGE_DIR.parent / "resources")
    return dirs


def resource_path(name: str) -> Path:
    """Absolute path of the resource file ``name`` (e.g. ``"lps-gui-48.png"``).

    Parameters
    ----------
    name : str
        File name relative to the resources folder.

    Returns
    -------
    Path
        An existing file.

    Raises
    ------
    FileNotFoundError
        When no resource folder holds ``name``; the message lists the folders
        searched, since that means a broken installation rather than bad input.
    """
    dirs = resource_dirs()
    for folder in dirs:
        candidate = folder / name
        if candidate.is_file():
            return candidate
    searched = ", ".join(str(d) for d in dirs)
    raise FileNotFoundError(f"resource {name!r} not found in {searched}; reinstall lps-calib or rebuild the bundle")


def app_icon_name(size_px: int) -> str:
    """File name of the application icon rendered at ``size_px`` pixels square."""
    return f"lps-gui-{size_px}.png"


def app_icon_paths() -> list[Path]:
    """Every available raster size of the application icon, smallest first.

    Feed them all to one ``QIcon`` (``addFile`` per path) so the window
    manager and taskbar each pick a crisp size. Missing sizes are skipped.
    """
    paths = []
    for size_px in APP_ICON_SIZES_PX:
        try:
            paths.append(resource_path(app_icon_name(size_px)))
        except FileNotFoundError:
            continue
    return paths
