"""``lps emulate KIND``: a stage controller's emulator on a pseudo-terminal, over the simulated stage.

The kinds are those of the stage registry with an emulator (``grbl``,
``marlin``...); ``lps emulate-grbl`` is ``lps emulate grbl``. Prints the pty
path on the first line of stdout (``lps capture --stage KIND:PATH``), then
serves until Ctrl-C. The switches are the GRBL emulator's; a kind ignores
those its controller has no notion of (homing locks, GRBL error codes).
"""
from __future__ import annotations

import argparse

from lps_gui.cli import emulate_grbl
HELP = "serve a stage controller's emulator (grbl, marlin...) on a pseudo-terminal (prints its path) until Ctrl-C"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from lps_gui.hardware.registry import emulated_kinds

    parser.add_argument("kind", choices=sorted(emulated_kinds()), metavar="KIND",
                        help=f"the controller to emulate: {', '.join(sorted(emulated_kinds()))}")
    emulate_grbl.add_arguments(parser)


def run(args: argparse.Namespace) -> int:
    return emulate_grbl.serve(args, args.kind)
