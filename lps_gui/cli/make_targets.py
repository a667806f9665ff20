"""`lps make-targets`: printable ChArUco targets for a row or constellation, and their session.json list.

Examples::

    lps make-targets row --count 6 --inner-corners 10x7 --square-mm 30     # the paper's X axis: six targets
    lps make-targets near --count 6 --inner-corners 10x7 --square-mm 15 --first-marker 264

Writes ``targets.pdf`` (one page per target at true scale, vector, with a 100 mm scale bar to check the
print) and ``targets.json`` (``{"targets": [...]}`` for session.json). Measure each printed square size,
and set ``square_mm`` (or ``scale_ppm``) to what you measured: every length of the results is in it.
"""
from __future__ import annotations

import argparse

from lps_gui.cli.option_types import float_range, int_range, nonnegative_int

HELP = "write printable ChArUco targets (PDF, true scale) and their session.json list"


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected COLSxROWS, got {text!r}") from None
    return w, h


MIN_PRINTED_MM = 1.0  # 1e-9 mm squares made a PDF of nothing


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("out", help="folder for targets.pdf and targets.json (created if missing)")
    p.add_argument("--count", type=int_range(1, 100), default=6, help="number of targets (default 6)")
    p.add_argument("--inner-corners", type=_size, default=(10, 7), help="inner corners COLSxROWS (default 10x7)")
    p.add_argument("--square-mm", type=float_range(MIN_PRINTED_MM, 1e4), default=30.0,
                   help="square size, mm (default 30; at least 1: a printer's dots and the detector need the size)")
    p.add_argument("--marker-mm", type=float_range(0.7 * MIN_PRINTED_MM, 1e4), help="marker size, mm (default 70 %% of the square)")
    p.add_argument("--dictionary", default="DICT_5X5_1000", help="ArUco dictionary (default DICT_5X5_1000)")
    p.add_argument("--first-marker", type=nonnegative_int, default=0,
                   help="first marker id of the first target (another set in the same session starts after the last)")
    p.add_argument("--prefix", default="T", help="target ids are PREFIX0, PREFIX1, ... (default T)")


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from lps_gui.core.geometry.board import Board
    from lps_gui.core.geometry.targets import Target, check_targets
    from lps_gui.errors import InputError
    from lps_gui.io.jsonfile import write_json
    from lps_gui.io.targets_file import dictionary_sizes, targets_to_list
    from lps_gui.report.pdf.targets import write_targets_pdf

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise InputError(f"{out}: exists and is not a folder; give a folder for targets.pdf and targets.json")
    cols, rows = args.inner_corners
    board = Board(cols, rows, args.square_mm, type="charuco", marker_mm=args.marker_mm, dictionary=args.dictionary)
    n = (cols + 1) * (rows + 1) // 2
    targets = [Target(f"{args.prefix}{j}", board, args.first_marker + j * n) for j in range(args.count)]
    check_targets(targets, dictionary_sizes(targets))
    out.mkdir(parents=True, exist_ok=True)
    printed = write_targets_pdf(out / "targets.pdf", targets)
    write_json(out / "targets.json", {"targets": targets_to_list(targets)})
    w, h = printed.page_sizes_mm[0]
    last = targets[-1].marker_range.stop - 1
    print(f"{out / 'targets.pdf'}: {printed.pages} targets, pages {w:g} x {h:g} mm, marker ids "
          f"{args.first_marker}-{last}; print at 100 % and check the 100 mm bar")
    print(f"{out / 'targets.json'}: the targets list for session.json")
    return 0
