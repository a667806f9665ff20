"""Entry script of the PyInstaller bundle: one program, two commands.

The bundle holds two executables built from this one script, ``lps-gui``
and ``lps``; they share every library, so the folder stays about half the size
of two separate builds. Which command runs is decided by the executable's own
file name. Both imports are written out so PyInstaller's analysis sees them.
"""
from __future__ import annotations

import os
import sys


def _command_name() -> str:
    """``lps-gui`` or ``lps``, from the running executable (or argv[0] outside a bundle)."""
    path = sys.executable if getattr(sys, "frozen", False) else sys.argv[0]
    return os.path.splitext(os.path.basename(path))[0]


def main() -> int:
    """Run the GUI when started as ``lps-gui``, the CLI otherwise."""
    if _command_name() == "lps-gui":
        from lps_gui.gui.app import main as gui_main

        return int(gui_main() or 0)
    from lps_gui.cli import main as cli_main
    return int(cli_main() or 0)


if __name__ == "__main__":
    sys.exit(main())
