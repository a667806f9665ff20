"""`lps detect SESSION|IMAGES...`: find the board's corners in every image, write corners.vnl."""
from __future__ import annotations

import argparse
import sys

from lps_gui.cli.option_types import workers

HELP = "detect the board's corners in a session (writes corners.vnl) or in images"

EXIT_SOME_FAILED = 3


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = "exit status: 0 every view detected, 3 some views failed (listed on stderr and in corners.vnl), 2 bad input"
    parser.add_argument("inputs", nargs="+", metavar="SESSION|IMAGE", help="a session folder, or image files/folders")
    parser.add_argument("--board", help="board.json (required for images; a session has its own)")
    parser.add_argument("--out", help="corners file for images (default corners.vnl here): an existing folder gets "
                        "corners.vnl inside; a name ending in .vnl is the file; a name without suffix is a new folder")
    parser.add_argument("--workers", type=workers, default=None, help="processes (default: one per core)")
    parser.add_argument("--force", action="store_true", help="detect every view again, ignoring corners.vnl (replaced images are detected again without it)")
    parser.add_argument("--no-track", action="store_true", help="detect every image from scratch (unrelated views)")


def run(args: argparse.Namespace) -> int:
    import time
    from pathlib import Path

    from lps_gui.cli.progress_bar import ProgressBar
    from lps_gui.errors import InputError
    from lps_gui.io.session import SESSION_FILE

    inputs = [Path(p) for p in args.inputs]
    missing = [p for p in inputs if not p.exists()]
    if missing:
        raise InputError(f"{missing[0]}: not found; give a session folder or image files/folders")
    bar = ProgressBar("detect")
    t0 = time.monotonic()
    if len(inputs) == 1 and (inputs[0] / SESSION_FILE).exists():
        from lps_gui.io.session_lock import SessionLock
        from lps_gui.pipeline.detect import detect_session

        if args.out:
            raise InputError(f"--out: a session's corners always go into {inputs[0] / 'corners.vnl'}; drop --out")
        if args.board:
            raise InputError(f"--board: the session {inputs[0]} has its own board (session.json); drop --board")
        with SessionLock(inputs[0]):
            table = detect_session(inputs[0], bar, workers=args.workers, force=args.force, track=not args.no_track)
        out = inputs[0] / "corners.vnl"
    else:
        from lps_gui.cli.out_path import resolve_out
        from lps_gui.io.board_file import read_board
        from lps_gui.io.corners.vnl import write_corners_vnl
        from lps_gui.pipeline.detect import detect_images
        from lps_gui.pipeline.intrinsics import expand_image_paths

        paths = expand_image_paths(inputs)
        if not paths:
            raise InputError(f"{inputs[0]}: no images here (and no session.json); give image files, a folder of "
                             "images or a session folder")
        if not args.board:
            raise InputError(f"detect: {len(paths)} image(s) need --board board.json (a session folder has its own)")
        board = read_board(args.board)
        out = resolve_out(args.out, "corners.vnl", None, (".vnl",), "lps detect", inputs=[args.board, *paths])
        table = detect_images(paths, board, bar, workers=args.workers, track=not args.no_track)
        if len(table.failed) == len(table.names):
            for name, reason in table.failed.items():
                print(f"failed: {name}: {reason}", file=sys.stderr)
            unreadable = [(n, why) for n, why in table.failed.items() if "board" not in why]
            if unreadable:
                raise InputError(f"detect: none of the {len(paths)} image(s) could be used (first: {unreadable[0][0]}: "
                                 f"{unreadable[0][1]}); nothing written")
            raise InputError(f"detect: the board was found in none of the {len(paths)} image(s); nothing written "
                             "(check --board matches the printed board)")
        write_corners_vnl(out, table)
    for name, reason in table.failed.items():
        print(f"failed: {name}: {reason}", file=sys.stderr)
    if table.meta.get("up_to_date"):
        print(f"{out} is up to date ({len(table.names)} views, {len(table.failed)} failed); use --force to detect again")
        if hasattr(table, "seen"):
            print(target_counts(table))
        return EXIT_SOME_FAILED if table.failed else 0
    elapsed = time.monotonic() - t0
    n = len(table.names)
    ok = n - len(table.failed)
    how = f" ({table.meta['detection']})" if table.meta.get("detection") else ""
    print(f"{ok}/{n} views detected{how} in {elapsed:.1f} s ({n / max(elapsed, 1e-9):.0f} images/s); corners in {out}")
    if hasattr(table, "seen"):  # a session with targets (SPEC 13): what each target gave
        print(target_counts(table))
    return EXIT_SOME_FAILED if table.failed else 0


def target_counts(table) -> str:
    """One line per target: the views it was found in (partial ones among them) and its corners."""
    import numpy as np

    seen = table.seen()  # (K, T) corners per view and target
    full = np.diff(table.offsets)
    lines = []
    for j, name in enumerate(table.targets):
        views = int((seen[:, j] > 0).sum())
        partial = int(((seen[:, j] > 0) & (seen[:, j] < full[j])).sum())
        lines.append(f"  {name}: {views} views ({partial} partial), {int(seen[:, j].sum())} corners")
    return "targets:\n" + "\n".join(lines)
