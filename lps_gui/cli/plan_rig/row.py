"""`lps plan-rig --travel`: propose a row (or constellation) of targets and print the sigma it predicts."""
from __future__ import annotations

import argparse
import json
import math
from typing import Any


def _stops(args: argparse.Namespace, travel: tuple[float, ...]) -> tuple[int, ...]:
    """Stops per axis: from --step when given, else 121 along a line (the paper's X axis), 13 x 9 over a plane."""
    if args.step is None:
        return (121,) if len(travel) == 1 else (13, 9)
    step = args.step * len(travel) if len(args.step) == 1 else args.step
    if len(step) != len(travel):
        from lps_gui.errors import InputError

        raise InputError("plan-rig: --step takes one value, or X,Y with --travel-y")
    return tuple(int(math.floor(t / s + 1e-9)) + 1 for t, s in zip(travel, step))


def run_row(args: argparse.Namespace, intrinsics: Any) -> int:
    from lps_gui.core.planning.rows import plan_row, propose_row
    from lps_gui.errors import InputError

    if args.travel is None:
        raise InputError("plan-rig: --travel-y needs --travel (the X travel) too")
    travel = (args.travel,) if args.travel_y is None else (args.travel, args.travel_y)
    stops = _stops(args, travel)
    if args.distance_mm is not None:
        plans = [plan_row(intrinsics, d, travel, stops, args.noise_px, wanted_sigma_um=args.sigma_um)
                 for d in args.distance_mm]
    elif args.sigma_um is not None:
        plans = [propose_row(intrinsics, travel, args.sigma_um, stops, args.noise_px)]
    else:
        raise InputError("plan-rig: with --travel give the wanted --sigma-um per stop (or --distance-mm)")
    if args.json:
        print(json.dumps([p.to_dict() | {"make_targets": p.make_targets_command()} for p in plans], indent=2))
        return 0
    kind = "row" if len(travel) == 1 else "constellation"
    span = " x ".join(f"{t:g}" for t in travel)
    print(f"{kind} of targets for a {span} mm travel, {' x '.join(map(str, stops))} stops; "
          f"corner noise {args.noise_px:g} px")
    print(f"{'distance mm':>12} {'targets':>8} {'target':>16} {'pitch mm':>10} {'square px':>10} "
          f"{'sigma µm (median / max)':>24} {'centred':>8}")
    for p in plans:
        b = p.board
        grid = f"{p.grid[0]}" if len(travel) == 1 else f"{p.grid[0]}x{p.grid[1]}"
        pitch = f"{p.pitch_mm[0]:g}" if len(travel) == 1 else f"{p.pitch_mm[0]:g}x{p.pitch_mm[1]:g}"
        print(f"{p.distance_mm:>12g} {grid:>8} {f'{b.cols}x{b.rows} of {b.square_mm:g} mm':>16} {pitch:>10} "
              f"{p.square_px:>10.0f} {f'{p.sigma_um_median:.2f} / {p.sigma_um_max:.2f}':>24} "
              f"{p.centred_sigma_um_median:>8.2f}")
        for note in p.notes:
            print(f"{'':>12} {note}")
    print(f"print them: {plans[-1].make_targets_command()}")
    return 0
