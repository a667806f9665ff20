"""`lps intrinsics IMAGES... --board board.json`: calibrate the camera from varied-pose board images."""
from __future__ import annotations

import argparse
import sys

from lps_gui.cli.option_types import workers

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
    parser.add_argument("--cameramodel", help="also write an mrcal .cameramodel here")
    parser.add_argument("--lensmodel", choices=("opencv5", "opencv8"), default="opencv5",
                        help="mrcal lens model of --cameramodel (opencv8 with k4..k6 = 0; default opencv5)")
    parser.add_argument("--model", choices=("opencv5", "rational", "auto"), default="opencv5",
                        help="lens model: opencv5 (k1 k2 p1 p2 k3, default), rational (+ OpenCV's rational k4-k6 and "
                             "thin-prism s1-s4 terms: a lens the 5-coefficient model misses), or auto (the one that "
                             "predicts held-out views better, by two-fold cross-validation)")
    parser.add_argument("--fix-k3", action="store_true", help="hold k3 at 0 (narrow fields of view)")
    parser.add_argument("--warp", choices=("auto", "on", "off"), default="auto",
                        help="estimate the board's bow with the intrinsics (auto: unless the views cannot separate it; on: fail then)")
    parser.add_argument("--cross-validate", action="store_true",
                        help="also calibrate the even and the odd images apart and compare the two projections")
    parser.add_argument("--report", help="also write the intrinsics report (PDF with residual, uncertainty and coverage maps) here")
    parser.add_argument("--workers", type=workers, default=None, help="processes (default: one per core)")


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    import cv2

    from lps_gui.cli.out_path import check_out_file, resolve_out
    from lps_gui.cli.progress_bar import ProgressBar
    from lps_gui.io.board_file import read_board
    from lps_gui.io.intrinsics_file import write_intrinsics
    from lps_gui.pipeline.intrinsics import calibrate_images, cross_validate_calibration, expand_image_paths

    board = read_board(args.board)
    inputs = [args.board, *args.images, *expand_image_paths([Path(p) for p in args.images if Path(p).exists()])]
    args.out = resolve_out(args.out, "intrinsics.json", None, (".json", ".yaml", ".yml"), "lps intrinsics", inputs=inputs)
    written = [args.out]
    for option, extra in (("--yaml", args.yaml), ("--cameramodel", args.cameramodel), ("--report", args.report)):
        if extra:
            check_out_file(extra, option=option, inputs=inputs + written)
            written.append(extra)
    flags = cv2.CALIB_FIX_K3 if args.fix_k3 else 0
    cal = calibrate_images([Path(p) for p in args.images], board, ProgressBar("intrinsics"), workers=args.workers, flags=flags,
                           warp=args.warp, model=args.model)
    write_intrinsics(args.out, cal.intrinsics)
    if args.yaml:
        write_intrinsics(args.yaml, cal.intrinsics)
    if args.cameramodel:
        from lps_gui.io.cameramodel_file import write_cameramodel

        write_cameramodel(args.cameramodel, cal.intrinsics, "LENSMODEL_" + args.lensmodel.upper())
    print(cal.summary())
    if cal.intrinsics.has_higher:  # the cross-validation compares the halves with the same model
        from lps_gui.core.intrinsics.crossval import LENS_MODELS

        flags |= LENS_MODELS["rational"]
    crossval = cross_validate_calibration(cal, board, flags=flags, warp=args.warp) if args.cross_validate else None
    if crossval is not None:
        print(crossval.summary())
    if args.report:
        from lps_gui.report.pdf.intrinsics import write_intrinsics_report

        write_intrinsics_report(cal, args.report, crossval, title=Path(args.out).name, board=board)
    print("wrote " + ", ".join(str(p) for p in (args.out, args.yaml, args.cameramodel, args.report) if p))
    failed = [w for w in cal.warnings if any(w.startswith(n + ":") for n in cal.view_names)]
    if failed:
        print(f"{len(failed)} image(s) not used; see the lines above", file=sys.stderr)
    return EXIT_SOME_FAILED if failed else 0
