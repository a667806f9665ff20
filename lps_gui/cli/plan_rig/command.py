"""`lps plan-rig`: before any capture, does the board stay in view, and what sigma to expect."""
from __future__ import annotations

import argparse

from lps_gui.cli.option_types import positive_finite
from lps_gui.cli.plan_rig.two_depth import add_two_depth_arguments

HELP = ("check a rig before capturing: board in view over the whole plan, and the position sigma to expect; "
        "--travel proposes a row of targets for a travel longer than the view")


MAX_SIZE = 100_000  # px of an image; inner corners are held to 1000 by the board check


def _numbers(text: str) -> tuple[float, ...]:
    try:
        values = tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected numbers separated by commas, got {text!r}") from None
    if not values:
        raise argparse.ArgumentTypeError("expected at least one number")
    return values


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, got {text!r}") from None
    if not (2 <= w <= MAX_SIZE and 2 <= h <= MAX_SIZE):  # checked before anything of that size is allocated
        raise argparse.ArgumentTypeError(f"{text}: each of WIDTH and HEIGHT must be from 2 to {MAX_SIZE}")
    return w, h


def add_arguments(p: argparse.ArgumentParser) -> None:
    cam = p.add_argument_group("camera (either --intrinsics or the lens and sensor)")
    cam.add_argument("--intrinsics", help="intrinsics.json or OpenCV YAML of the camera")
    cam.add_argument("--focal-mm", type=positive_finite, help="lens focal length, mm")
    cam.add_argument("--pixel-um", type=positive_finite, help="pixel pitch, µm")
    cam.add_argument("--image", type=_size, help="image size WIDTHxHEIGHT, px")
    p.add_argument("--board", help="board.json; or give --inner-corners and --square-mm")
    p.add_argument("--inner-corners", type=_size, help="inner corners COLSxROWS")
    p.add_argument("--square-mm", type=positive_finite, help="square size, mm")
    p.add_argument("--distance-mm", type=_numbers,
                   help="camera-to-board distance(s), mm; several (400,500,600) print one row each")
    p.add_argument("--start", type=_numbers, default=(0.0,), help="first target: X or X,Y (mm)")
    p.add_argument("--stop", type=_numbers, help="last target: X or X,Y (mm); X,Y plans a planar grid")
    p.add_argument("--step", type=_numbers, help="step: X or X,Y (mm); with --travel, the stops' spacing")
    row = p.add_argument_group("a row of targets (SPEC 13, docs/targets.md) instead of one board")
    row.add_argument("--travel", type=positive_finite, help="travel of X, mm: propose a row of targets along it")
    row.add_argument("--travel-y", type=positive_finite, help="travel of Y, mm: a constellation over the XY plane")
    row.add_argument("--sigma-um", type=positive_finite,
                     help="wanted sigma per stop, µm (median): the distance is proposed; or give --distance-mm")
    add_two_depth_arguments(p)
    p.add_argument("--noise-px", type=positive_finite, default=0.1, help="corner noise to expect, px (default 0.1)")
    p.add_argument("--json", action="store_true", help="print the predictions as JSON")


def _camera(args: argparse.Namespace):
    from lps_gui.core.planning.rig import intrinsics_from_lens
    from lps_gui.errors import InputError

    if args.intrinsics:
        from lps_gui.io.intrinsics_file import read_intrinsics

        return read_intrinsics(args.intrinsics)
    if args.focal_mm is None or args.pixel_um is None or args.image is None:
        raise InputError("plan-rig: give --intrinsics FILE, or --focal-mm, --pixel-um and --image WxH")
    return intrinsics_from_lens(args.focal_mm, args.pixel_um, args.image)


def _board(args: argparse.Namespace):
    from lps_gui.errors import InputError

    if args.board:
        from lps_gui.io.board_file import read_board

        return read_board(args.board)
    if args.inner_corners is None or args.square_mm is None:
        raise InputError("plan-rig: give --board board.json, or --inner-corners COLSxROWS and --square-mm")
    from lps_gui.io.board_file import board_from_dict

    return board_from_dict({"type": "chessboard", "inner_corners": list(args.inner_corners), "square_mm": args.square_mm},
                           "--inner-corners/--square-mm")  # the one limit of every board (before any allocation)


def _plan(args: argparse.Namespace):
    from lps_gui.core.planning.plan import Plan
    from lps_gui.errors import InputError

    dims = {len(args.start), len(args.stop), len(args.step)}
    if dims == {1}:
        return Plan(start_mm=args.start[0], stop_mm=args.stop[0], step_mm=args.step[0], overshoot_mm=0.0)
    if dims <= {1, 2} and len(args.stop) == 2:
        pair = [(v * 2 if len(v) == 1 else v) for v in (args.start, args.stop, args.step)]
        return Plan.xy(start_mm=tuple(pair[0]), stop_mm=tuple(pair[1]), step_mm=tuple(pair[2]), overshoot_mm=0.0)
    raise InputError("plan-rig: --start, --stop and --step take one value (a line) or two, X,Y (a planar grid)")


def run(args: argparse.Namespace) -> int:
    import json

    from lps_gui.core.planning.rig import predict_rig
    from lps_gui.errors import InputError

    if args.two_depth is not None:
        from lps_gui.cli.plan_rig.two_depth import run_two_depth

        return run_two_depth(args, _camera(args))
    if args.travel is not None or args.travel_y is not None:
        from lps_gui.cli.plan_rig.row import run_row

        return run_row(args, _camera(args))
    if args.distance_mm is None or args.stop is None or args.step is None:
        raise InputError("plan-rig: give --distance-mm, --stop and --step for one board, "
                         "or --travel (and --sigma-um) for a row of targets")
    intrinsics, board, plan = _camera(args), _board(args), _plan(args)
    rows = [predict_rig(board, intrinsics, d, plan, args.noise_px) for d in args.distance_mm]
    if args.json:
        print(json.dumps([r.to_dict() for r in rows], indent=2))
        return 0 if all(r.board_in_view for r in rows) else 3
    axes = "X,Y" if len(rows[0].axes) == 2 else "X"
    print(f"plan: {rows[0].n_targets} targets on {axes}; corner noise {args.noise_px:g} px; "
          f"board {board.cols}x{board.rows} at {board.square_mm:g} mm")
    print(f"{'distance mm':>12} {'board px':>12} {'in view':>8} {'sigma µm (median / max)':>24}")
    for r in rows:
        sig = "-" if r.sigma_um_median is None else f"{r.sigma_um_median:.2f} / {r.sigma_um_max:.2f}"
        view = "yes" if r.board_in_view else f"no ({r.targets_losing_board})"
        size = f"{r.board_size_px[0]:.0f}x{r.board_size_px[1]:.0f}"
        print(f"{r.distance_mm:>12g} {size:>12} {view:>8} {sig:>24}")
        for note in r.notes:
            print(f"{'':>12} {note}")
    return 0 if all(r.board_in_view for r in rows) else 3
