"""lps-calib: measure a linear positioning system with a camera and a chessboard.

The version has one source, ``pyproject.toml``; installed metadata carries it,
and a source checkout falls back to reading the file. It is looked up when
first asked for (``from lps_gui import __version__``).
"""
from __future__ import annotations

from pathlib import Path


def _read_version() -> str:
    try:
        from importlib.metadata import version

        return version("lps-calib")
    except Exception:  # not installed: running from a source tree or a bundle
        pyproject = Path(__file__).resolve().parent.parent / "pyproject.toml"
        try:
            for line in pyproject.read_text().splitlines():
                if line.startswith("version"):
                    return line.split("=", 1)[1].strip().strip('"')
        except OSError:
            pass
        return "0+unknown"


def __getattr__(name: str) -> str:
    """``__version__`` on first use: importlib.metadata is slow to import, and a command like `lps estimate` never needs it."""
    if name == "__version__":
        version = _read_version()
        globals()["__version__"] = version
        return version
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
