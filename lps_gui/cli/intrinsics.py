"""`lps intrinsics IMAGES... --board board.json`: calibrate the camera from varied-pose board images."""
from __future__ import annotations

import argparse
import sys

HELP = "calibrate camera intrinsics (with each parameter's std) from varied-pose board images"

EXIT_SOME_FAILED = 3


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = "exit status: 0 calibrated from every image, 3 some images unusable (listed), 2 bad input"
    parser.add_argument("images", nargs="+", help="image files or folders of images")
    parser.add_argument("--board", required=True, help="board.json")
    parser.add_argument("--out", default=None, help="intrinsics to write (default intrinsics.json here): an existing "
                        "folder gets intrinsics.json inside; a name ending in .json/.yaml/.yml is the file; a name "
                        "without suffix is a new folder")
    parser.add_argument("--yaml", help="also write OpenCV FileStorage YAML here")
    parser.add_argument("--fix-k3", action="store_true", help="hold k3 at 0 (narrow fields of view)")
    parser.add_argument("--workers", type=int, default=None, help="processes (default: one per core)")


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    import cv2

    from lps_gui.cli.progress_bar import ProgressBar
    from lps_gui.io.board_file import read_board
    from lps_gui.io.intrinsics_file import write_intrinsics
    from lps_gui.pipeline.intrinsics import calibrate_images

    from lps_gui.cli.out_path import resolve_out

    board = read_board(args.board)
    args.out = resolve_out(args.out, "intrinsics.json", None, (".json", ".yaml", ".yml"), "lps intrinsics")
    flags = cv2.CALIB_FIX_K3 if args.fix_k3 else 0
    cal = calibrate_images([Path(p) for p in args.images], board, ProgressBar("intrinsics"), workers=args.workers, flags=flags)
    write_intrinsics(args.out, cal.intrinsics)
    if args.yaml:
        write_intrinsics(args.yaml, cal.intrinsics)
    print(cal.summary())
    print(f"wrote {args.out}" + (f" and {args.yaml}" if args.yaml else ""))
    failed = [w for w in cal.warnings if any(w.startswith(n + ":") for n in cal.view_names)]
    if failed:
        print(f"{len(failed)} image(s) not used; see the lines above", file=sys.stderr)
    return EXIT_SOME_FAILED if failed else 0
