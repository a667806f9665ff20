"""`lps import`: a session from a folder of images the user already has (SPEC 16); then detect, estimate, report.

Examples::

    lps import photos --out run1 --board board.json --intrinsics intrinsics.json --step 1 --start 0
    lps import photos --out run2 --board board.json --step 0.5 --directions both --runs 2
    lps import photos --out run3 --board board.json --from-names 'pos_{mm}.png'
    lps import photos --in-place --board board.json --positions positions.csv   # file,target[,direction,run]

The work is :func:`lps_gui.capture.import_images.import_images`; this module only reads the switches.
"""
from __future__ import annotations

import argparse

from lps_gui.cli.option_types import finite, int_range, positive_finite

HELP = "make a session from images you already have (positions from a step, the file names or a CSV)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("images", metavar="IMAGES_DIR", help="folder of the images (never modified)")
    p.add_argument("--out", metavar="SESSION", help="new session folder; the images are copied into its images/")
    p.add_argument("--in-place", action="store_true", help="write the session into IMAGES_DIR itself and list the "
                   "images where they are (no copy)")
    g = p.add_argument_group("positions (one of --step, --from-names, --positions)")
    g.add_argument("--step", type=positive_finite, dest="step_mm", metavar="MM",
                   help="images in natural name order, one target every MM from --start")
    g.add_argument("--start", type=finite, dest="start_mm", default=0.0, metavar="MM", help="first target, mm (default 0)")
    g.add_argument("--directions", choices=("+", "-", "both"), default="+",
                   help="with --step: the passes of each run as `lps capture` runs them (default +)")
    g.add_argument("--runs", type=int_range(1, 1000), default=1, help="with --step: number of runs (default 1)")
    g.add_argument("--from-names", metavar="PATTERN", help="positions in the file names: 'pos_{mm}.png'; also "
                   "{index}, {run}, {dir} (+, -, fwd, bwd) and * for any text")
    g.add_argument("--positions", metavar="FILE.csv", help="a CSV of file,target[,direction,run], files relative to "
                   "IMAGES_DIR, in capture order")
    s = p.add_argument_group("set-up (as for lps capture)")
    s.add_argument("--board", metavar="FILE", required=True, help="board.json (docs/capture.md)")
    s.add_argument("--intrinsics", metavar="FILE", help="intrinsics (JSON or OpenCV YAML), embedded into session.json")
    from lps_gui.cli.capture.setup import add_setup_arguments

    add_setup_arguments(p, iso_plan=False)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from lps_gui.capture.import_images import Positions, import_images
    from lps_gui.cli.capture.devices import read_intrinsics
    from lps_gui.capture.plans import describe_plan
    from lps_gui.cli.capture.setup import setup_meta
    from lps_gui.cli.progress_bar import ProgressBar
    from lps_gui.io.board_file import read_board
    from lps_gui.io.session import Session

    positions = Positions(step_mm=args.step_mm, start_mm=args.start_mm, directions=args.directions, runs=args.runs,
                          names=args.from_names, csv=Path(args.positions) if args.positions else None)
    extra = setup_meta(args)
    board = read_board(args.board)
    intr = read_intrinsics(args.intrinsics)
    if args.intrinsics:
        extra["intrinsics_source"] = str(args.intrinsics)
    folder = import_images(args.images, args.out, board, positions, intr, in_place=args.in_place, extra=extra,
                           progress=ProgressBar("import"))
    session = Session.open(folder)
    print(f"{folder}: {len(session.records())} images imported ({describe_plan(session.plan())}); "
          f"next: lps detect {folder}")
    return 0
