"""`lps plan-rig --travel L --two-depth NEAR`: a far and a near row of targets, and the angular sigmas they give."""
from __future__ import annotations

import argparse
import json
import math
from typing import Any

from lps_gui.cli.option_types import positive_finite


def add_two_depth_arguments(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("targets at two depths (SPEC 14, docs/error-motions.md): roll, pitch and yaw per stop")
    g.add_argument("--two-depth", type=positive_finite, metavar="NEAR_MM",
                   help="with --travel and --distance-mm: a second, nearer row of smaller targets NEAR_MM in front "
                        "of the far row (300 for the paper's rig); predicts EAX, EBX, ECX per stop")


def run_two_depth(args: argparse.Namespace, intrinsics: Any) -> int:
    from lps_gui.core.planning.two_depth import plan_two_depth
    from lps_gui.errors import InputError

    if args.travel is None or args.distance_mm is None or args.travel_y is not None:
        raise InputError("plan-rig: --two-depth needs --travel (one axis) and --distance-mm (the far row)")
    stops = 121 if args.step is None else int(math.floor(args.travel / args.step[0] + 1e-9)) + 1
    plans = [plan_two_depth(intrinsics, d, args.travel, args.two_depth, stops, args.noise_px) for d in args.distance_mm]
    if args.json:
        print(json.dumps([p.to_dict() | {"make_targets": p.make_targets_commands()} for p in plans], indent=2))
        return 0
    print(f"two-depth targets for a {args.travel:g} mm travel, {stops} stops; corner noise {args.noise_px:g} px")
    print(f"{'distance mm':>12} {'far row':>22} {'near row':>22} {'EAX / EBX / ECX µrad':>22} {'one view':>18}")
    for p in plans:
        far = f"{p.n_far} x {p.far.cols}x{p.far.rows}/{p.far.square_mm:g} mm"
        near = f"{p.n_near} x {p.near.cols}x{p.near.rows}/{p.near.square_mm:g} mm"
        sig = " / ".join(f"{v:.1f}" for v in p.angle_sigma_urad.values())
        one = " / ".join(f"{v:.1f}" for v in p.single_view_urad.values())
        print(f"{p.distance_mm:>12g} {far:>22} {near:>22} {sig:>22} {one:>18}")
        print(f"{'':>12} far pitch {p.far_pitch_mm:g} mm; near row {p.near_mm:g} mm nearer, pitch "
              f"{p.near_pitch_mm:g} mm, in the upper half of the image; EXX at the camera centre "
              f"{p.positioning_sigma_um:.1f} µm per stop")
        for note in p.notes:
            print(f"{'':>12} {note}")
    for line in plans[-1].make_targets_commands():
        print(f"print them: {line}")
    return 0
